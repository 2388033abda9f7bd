"""The cross-validation study: the in-house solver against the independent Exudyn models.

Case list ``reference/cases/cross_validation.toml``. Its groups are named
``<mechanism>/<variant>[/frictionless]:<role>`` with role

* ``reference``: the in-house high-accuracy run (DOP853, rtol 1e-12, projection; regularized tanh
  friction with the common eps, or no friction for the ``frictionless`` sets);
* ``exudyn``: Exudyn, swept over solver (index3, index2) and step h, same friction law and eps;
* ``inhouse``: an in-house method at everyday settings (adaptive RK45), for the cost comparison.

Every case of one set has the same horizon and output step, so all comparisons use common samples
(:func:`study.compare.common_samples`), never interpolation.

:func:`summarize` (pure: it only reads saved results through ``load``) returns the tables

``exudyn_agreement``
    one row per Exudyn run and per in-house method run: max |dq|, max |dqd|, max |dF_friction|,
    max |dN|, max |dlam| against the set's reference and the observed orders between successive h
    of the same solver (no timing);
``exudyn_agreement_timing``
    the same keys with the CPU seconds of the run and of the in-house reference;
``exudyn_reactions``
    the frictionless sets: every Exudyn joint force (revolute joints: global x, y on the distal
    body; prismatic joints through the multipliers) against the in-house reference's reaction of
    the same joint, with the observed order.

The friction force compared is the whole tangential force of the guide: the in-house
``friction_<contact>`` already contains the resistance F (slider-crank), Exudyn records the Coulomb
part and the resistance separately (``friction_guide`` + ``resistance_guide``).

In-house revolute-joint reactions are not multipliers (the in-house coordinates eliminate those
joints); :func:`inhouse_joint_forces` recovers them from the in-house q, qd, qdd and lambda by the
bodies' Newton equations, taken from the distal end of each chain inwards.
"""

from __future__ import annotations

import math
from typing import Callable, Iterable

import numpy as np
import pandas as pd

from study.compare import common_samples, observed_orders
from study.params import load_parameters
from study.pipeline import Case
from study.results import SimulationResult

Array = np.ndarray

#: Name of the guide's tangential and normal force per mechanism (the same in both engines).
FRICTION_FORCE = {"slider_crank": "friction_guide", "quick_return": "friction_ram_guide"}
NORMAL_FORCE = {"slider_crank": "normal_guide", "quick_return": "normal_ram_guide"}
#: Revolute joints of the Exudyn models (joint -> distal body), as in study.exudyn_models.
REVOLUTE_JOINTS = {"slider_crank": ("O", "A", "B"), "quick_return": ("O", "P", "A", "E", "D")}
ROLES = ("reference", "exudyn", "inhouse")

AGREEMENT_KEYS = ["mechanism", "variant", "friction", "t_end", "engine", "solver", "h"]


# --------------------------------------------------------------------------------------------
# quantities compared
# --------------------------------------------------------------------------------------------
def tangential_force(result: SimulationResult) -> Array | None:
    """The guide's whole tangential force on the sliding body [N] (None without friction)."""
    mech = result.meta["mechanism"]
    name = FRICTION_FORCE[mech]
    if name not in result.forces:
        return None
    total = np.asarray(result.forces[name], dtype=float)
    if result.meta.get("engine") == "exudyn" and "resistance_guide" in result.forces:
        total = total + result.forces["resistance_guide"]
    return total


def normal_force(result: SimulationResult) -> Array:
    """The guide's normal force (the in-house sign convention, -lambda of the contact row) [N]."""
    mech = result.meta["mechanism"]
    name = NORMAL_FORCE[mech]
    if name in result.forces:
        return np.asarray(result.forces[name], dtype=float)
    row = -1 if mech == "quick_return" else 0            # the contact's constraint row
    return -np.asarray(result.lam[:, row], dtype=float)


def _e(a: Array) -> Array:
    return np.stack([np.cos(a), np.sin(a)], axis=-1)


def _n(a: Array) -> Array:
    return np.stack([-np.sin(a), np.cos(a)], axis=-1)


def _acc(r: float, a: Array, w: Array, al: Array) -> Array:
    """Acceleration of r e(a): r (al n(a) - w^2 e(a)), shape (N, 2)."""
    return r * (al[:, None] * _n(a) - (w ** 2)[:, None] * _e(a))


def inhouse_joint_forces(result: SimulationResult) -> dict[str, Array]:
    """Revolute-joint reactions of an in-house result, in the Exudyn models' convention.

    ``joint_<J>_x/_y``: global force of joint J on its distal body [N], from Newton's second law of
    each body with the in-house accelerations and multipliers (lambda: guide and block normal
    forces; see the mechanism modules for the sign of each row), the applied loads (gravity,
    cutting force, the guide's tangential force) and the parameter set of the result.

    Parameters
    ----------
    result : SimulationResult of the in-house solver (meta 'mechanism', 'variant')

    Returns
    -------
    dict name -> (N,) array
    """
    mech, variant = result.meta["mechanism"], result.meta["variant"]
    v = load_parameters(mech, variant).values
    q, qd, qdd, lam = result.q, result.qd, result.qdd, result.lam
    n = len(result.t)
    gravity = lambda m: np.tile([0.0, -m * v.g], (n, 1))   # noqa: E731 - weight of a body
    tangential = tangential_force(result)
    ft = np.zeros(n) if tangential is None else tangential
    out = {}
    if mech == "slider_crank":
        q1, w1, a1 = q[:, 0], qd[:, 0], qdd[:, 0]
        ph, wph, aph = q[:, 0] + q[:, 1], qd[:, 0] + qd[:, 1], qdd[:, 0] + qdd[:, 1]
        acc_a = _acc(v.l1, q1, w1, a1)
        acc_c2 = acc_a - _acc(v.c2, ph, wph, aph)
        acc_b = acc_a - _acc(v.l2, ph, wph, aph)
        guide = np.column_stack([ft, -lam[:, 0]])           # guide on the slider: (F_t, N), N = -lam1
        f_b = v.m3 * acc_b - guide - gravity(v.m3)          # rod on slider
        f_a = v.m2 * acc_c2 + f_b - gravity(v.m2)           # crank on rod
        f_o = f_a - gravity(v.m1)                           # ground on crank (COM at O: no acceleration)
        forces = {"O": f_o, "A": f_a, "B": f_b}
    elif mech == "quick_return":
        from study.mechanisms.quick_return import cutting_law

        q1, q2, q3 = q.T
        w1, w2, w3 = qd.T
        a1, a2, a3 = qdd.T
        acc_a = _acc(v.l1, q1, w1, a1)
        acc_c1 = _acc(v.a1, q1, w1, a1)
        acc_c2 = _acc(v.a2, q2, w2, a2)
        acc_e = _acc(v.l2, q2, w2, a2)
        acc_c3 = acc_e + _acc(v.a3, q3, w3, a3)
        acc_d = acc_e + _acc(v.l3, q3, w3, a3)
        law = cutting_law(load_parameters(mech, variant))
        pos_d = np.column_stack([v.l2 * np.cos(q2) + v.l3 * np.cos(q3), v.l2 * np.sin(q2) + v.l3 * np.sin(q3)])
        vel_d = v.l2 * w2[:, None] * _n(q2) + v.l3 * w3[:, None] * _n(q3)
        cut = np.array([law(t, r, w, None)[0] for t, r, w in zip(result.t, pos_d, vel_d)])
        ram_guide = np.column_stack([cut + ft, lam[:, 1]])  # guide pushes the ram with (0, lam2)
        f_d = v.m5 * acc_d - ram_guide - gravity(v.m5)      # rod on ram
        f_e = v.m3 * acc_c3 + f_d - gravity(v.m3)           # rocker on rod
        rocker_on_block = -lam[:, [0]] * _n(q2)             # rocker pushes the block with -lam1 n
        f_a = v.m4 * acc_a - rocker_on_block - gravity(v.m4)  # crank on block
        f_o = v.m1 * acc_c1 + f_a - gravity(v.m1)           # ground on crank
        f_p = v.m2 * acc_c2 + f_e + rocker_on_block - gravity(v.m2)  # ground on rocker
        forces = {"O": f_o, "P": f_p, "A": f_a, "E": f_e, "D": f_d}
    else:
        raise ValueError(f"unknown mechanism {mech!r}; valid choices: slider_crank, quick_return")
    for joint, f in forces.items():
        out[f"joint_{joint}_x"], out[f"joint_{joint}_y"] = f[:, 0], f[:, 1]
    return out


def deviations(run: SimulationResult, ref: SimulationResult) -> dict[str, float]:
    """max over common samples of |run - ref| for q, qd, lam, tangential and normal force."""
    ia, ib = common_samples(run, ref)
    out = {
        "max_abs_dq": float(np.abs(run.q[ia] - ref.q[ib]).max()),
        "max_abs_dqd": float(np.abs(run.qd[ia] - ref.qd[ib]).max()),
        "max_abs_dlam": float(np.abs(run.lam[ia] - ref.lam[ib]).max()),
        "max_abs_dN": float(np.abs(normal_force(run)[ia] - normal_force(ref)[ib]).max()),
    }
    fr, ff = tangential_force(run), tangential_force(ref)
    out["max_abs_dF_friction"] = float(np.abs(fr[ia] - ff[ib]).max()) if fr is not None and ff is not None \
        else float("nan")
    out["max_abs_F_friction_ref"] = float(np.abs(ff[ib]).max()) if ff is not None else float("nan")
    out["max_abs_N_ref"] = float(np.abs(normal_force(ref)[ib]).max())
    out["n_samples"] = int(len(ia))
    return out


def reaction_deviations(run: SimulationResult, ref: SimulationResult,
                        ref_joints: dict[str, Array] | None = None) -> dict[str, tuple[float, float]]:
    """Per joint force component: (max |Exudyn - in-house|, max |in-house|) over common samples.

    Keys: ``joint_<J>_x/_y`` (revolute joints) and ``lam<i>`` (the prismatic joints' multipliers,
    mapped from Exudyn's ForceLocal by the Exudyn model).
    """
    ia, ib = common_samples(run, ref)
    ref_joints = inhouse_joint_forces(ref) if ref_joints is None else ref_joints
    out = {}
    for i in range(ref.lam.shape[1]):
        out[f"lam{i + 1}"] = (float(np.abs(run.lam[ia, i] - ref.lam[ib, i]).max()),
                              float(np.abs(ref.lam[ib, i]).max()))
    for name in sorted(ref_joints):
        out[name] = (float(np.abs(run.forces[name][ia] - ref_joints[name][ib]).max()),
                     float(np.abs(ref_joints[name][ib]).max()))
    return out


# --------------------------------------------------------------------------------------------
# summary tables
# --------------------------------------------------------------------------------------------
def parse_group(group: str) -> tuple[str, str]:
    """'slider_crank/seed:exudyn' -> ('slider_crank/seed', 'exudyn')."""
    key, sep, role = group.rpartition(":")
    if not sep or role not in ROLES:
        raise ValueError(f"group {group!r} is not '<set>:<role>' with role in {ROLES}")
    return key, role


def friction_label(case: Case) -> str:
    opts = case.kwargs
    if case.engine == "exudyn":
        if opts.get("friction", "regularized") == "none" or case.group.split(":")[0].endswith("/frictionless"):
            return "none"
        return f"tanh eps={opts.get('eps', 1e-3):g}"
    if opts.get("friction") is None:
        return "none"
    return f"{opts.get('friction_sgn', 'tanh')} eps={opts.get('friction_eps', 1e-3):g}"


def _inhouse_label(case: Case) -> str:
    o = case.kwargs
    tol = f" rtol={o['rtol']:g}" if "rtol" in o else f" h={o['step']:g}" if "step" in o else ""
    return f"in-house {o.get('integrator', 'RK45')}{tol} {o.get('method', 'none')}"


def _with_orders(frame: pd.DataFrame, columns: Iterable[str]) -> pd.DataFrame:
    """order_<c>: observed order between this row's h and the next larger h of the same set and solver."""
    frame = frame.copy()
    for c in columns:
        frame[f"order_{c.removeprefix('max_abs_')}"] = np.nan
    exu = frame["engine"] == "exudyn"
    for _, idx in frame[exu].groupby(["set", "solver"]).groups.items():
        sub = frame.loc[idx].sort_values("h", ascending=False)
        for c in columns:
            e, h = sub[c].to_numpy(float), sub["h"].to_numpy(float)
            for k in range(1, len(sub)):
                if e[k - 1] > 0 and e[k] > 0 and np.isfinite(e[k - 1]) and np.isfinite(e[k]):
                    frame.loc[sub.index[k], f"order_{c.removeprefix('max_abs_')}"] = \
                        float(observed_orders(h[k - 1:k + 1], e[k - 1:k + 1])[0])
    return frame


def summarize(cases: list[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    """Agreement, timing and reaction tables of the cross-validation study (see the module docstring).

    Parameters
    ----------
    cases : the study's cases (``CaseList.cases``)
    load : case -> its saved SimulationResult (LookupError if missing)

    Returns
    -------
    dict table name -> DataFrame, rows sorted by mechanism, variant, engine, solver, h
    """
    sets: dict[str, dict[str, list[Case]]] = {}
    for case in cases:
        key, role = parse_group(case.group)
        sets.setdefault(key, {r: [] for r in ROLES})[role].append(case)
    rows, timing, reactions = [], [], []
    for key in sorted(sets):
        roles = sets[key]
        if len(roles["reference"]) != 1:
            raise LookupError(f"set {key!r} needs exactly one reference case, has {len(roles['reference'])}")
        ref_case = roles["reference"][0]
        ref = load(ref_case)
        ref_cpu = float(ref.stats.get("cpu_seconds", math.nan))
        frictionless = friction_label(ref_case) == "none"
        ref_joints = inhouse_joint_forces(ref) if frictionless else None
        for case in roles["exudyn"] + roles["inhouse"]:
            run = load(case)
            base = {"set": key, "mechanism": case.mechanism, "variant": case.variant,
                    "friction": friction_label(case), "t_end": case.t_end, "engine": case.engine}
            if case.engine == "exudyn":
                o = case.kwargs
                base.update(solver=o.get("solver", "index3"), h=float(o["h"]))
                cpu = float(run.stats.get("process_cpu_seconds", run.stats.get("cpu_seconds", math.nan)))
                extra = {"newton_iterations": int(run.stats.get("newton_iterations", 0))}
            else:
                base.update(solver=_inhouse_label(case), h=np.nan)
                cpu = float(run.stats.get("cpu_seconds", math.nan))
                extra = {"newton_iterations": np.nan}
            dev = deviations(run, ref)
            rows.append({**base, **dev, "max_abs_phi": float(np.abs(run.phi).max()), **extra})
            timing.append({**base, "cpu_seconds": cpu, "inhouse_reference_cpu_seconds": ref_cpu,
                           "steps": int(run.stats.get("steps", 0))})
            if frictionless and case.engine == "exudyn":
                for quantity, (diff, scale) in reaction_deviations(run, ref, ref_joints).items():
                    reactions.append({**base, "quantity": quantity, "max_abs_diff": diff, "max_abs_inhouse": scale,
                                      "relative": diff / scale if scale > 0 else np.nan})
    sort = ["mechanism", "variant", "friction", "engine", "solver", "h"]
    agreement = pd.DataFrame(rows)
    if not agreement.empty:
        agreement = _with_orders(agreement, ["max_abs_dq", "max_abs_dqd", "max_abs_dF_friction", "max_abs_dN",
                                             "max_abs_dlam"])
        agreement = agreement.sort_values(sort, ascending=[True] * 5 + [False], na_position="last")
        agreement = agreement.drop(columns=["set"]).reset_index(drop=True)
    timing_frame = pd.DataFrame(timing)
    if not timing_frame.empty:
        timing_frame = timing_frame.sort_values(sort, ascending=[True] * 5 + [False], na_position="last")
        timing_frame = timing_frame.drop(columns=["set"]).reset_index(drop=True)
    react = pd.DataFrame(reactions)
    if not react.empty:
        react["order"] = np.nan
        for _, idx in react.groupby(["set", "solver", "quantity"]).groups.items():
            sub = react.loc[idx].sort_values("h", ascending=False)
            e, h = sub["max_abs_diff"].to_numpy(float), sub["h"].to_numpy(float)
            for k in range(1, len(sub)):
                if e[k - 1] > 0 and e[k] > 0:
                    react.loc[sub.index[k], "order"] = float(observed_orders(h[k - 1:k + 1], e[k - 1:k + 1])[0])
        react = react.sort_values(["mechanism", "variant", "solver", "quantity", "h"],
                                  ascending=[True, True, True, True, False])
        react = react.drop(columns=["set", "engine"]).reset_index(drop=True)
    return {"exudyn_agreement": agreement, "exudyn_agreement_timing": timing_frame, "exudyn_reactions": react}
