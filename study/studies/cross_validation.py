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
    of the same solver (no timing); ``reference_switches`` counts the switches the reference located
    (a switched load law, e.g. an on/off force: Exudyn cannot locate them, see the report section);
``exudyn_agreement_timing``
    the same keys with the CPU seconds of the run and of the in-house reference;
``exudyn_reactions``
    the frictionless sets without switches (an on/off load's jump at a mis-timed switch would only
    show the size of the jump): every Exudyn joint force (revolute joints: global x, y on the distal
    body; prismatic joints through the multipliers) against the in-house reference's reaction of
    the same joint, with the observed order.

The friction force compared is the whole tangential force of the guide: the in-house
``friction_<contact>`` already contains the contact's resistance F, Exudyn records the Coulomb
part and the resistance separately (``friction_guide`` + ``resistance_guide``).

In-house tree-joint reactions are not multipliers (the relative coordinates eliminate those joints);
:func:`inhouse_joint_forces` gets every joint's reaction from the description's absolute-coordinate
equations (:mod:`study.reactions`). Which forces are compared (the contact, the joints) comes from
the mechanism's description; nothing here names a mechanism.

The differences and orders are computed once, here, for this study and for ``study validate``
(:mod:`study.validation`): :func:`state_deviations`, :func:`joint_force_deviations` and :func:`with_orders`.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Callable, Iterable

import numpy as np
import pandas as pd

from study.compare import common_samples, observed_orders
from study import mechanisms
from study.params import load_parameters
from study.pipeline import Case
from study.reactions import joint_reactions
from study.results import SimulationResult
from study.solver.friction import DEFAULT_EPS

Array = np.ndarray

ROLES = ("reference", "exudyn", "inhouse")

# --------------------------------------------------------------------------------------------
# quantities compared
# --------------------------------------------------------------------------------------------
def contact_name(result: SimulationResult) -> str | None:
    """The first sliding contact of the result's mechanism (its description), or None."""
    return _contact_name(result.meta["mechanism"], result.meta["variant"])


@lru_cache(maxsize=None)
def _contact_name(mechanism: str, variant: str) -> str | None:
    contacts = mechanisms.description(load_parameters(mechanism, variant)).contacts()
    return contacts[0].name if contacts else None


def tangential_force(result: SimulationResult, name: str | None = None) -> Array | None:
    """The whole tangential force of contact ``name`` (default: the first) on the sliding body [N], or a pin's whole
    friction torque [N m] (None without friction)."""
    name = contact_name(result) if name is None else name
    if name is None or f"friction_{name}" not in result.forces:
        return None
    total = np.asarray(result.forces[f"friction_{name}"], dtype=float)
    if result.meta.get("engine") == "exudyn" and f"resistance_{name}" in result.forces:
        total = total + result.forces[f"resistance_{name}"]
    return total


def normal_force(result: SimulationResult, name: str | None = None) -> Array | None:
    """The normal force (-lambda of the contact row) of contact ``name`` (default: the first) [N], or a pin's |R|;
    None without a contact."""
    name = contact_name(result) if name is None else name
    if name is None:
        return None
    if f"normal_{name}" in result.forces:
        return np.asarray(result.forces[f"normal_{name}"], dtype=float)
    row = list(result.meta["constraint_names"]).index(name)
    return -np.asarray(result.lam[:, row], dtype=float)


def inhouse_joint_forces(result: SimulationResult) -> dict[str, Array]:
    """Every joint's reaction of an in-house result (:func:`study.reactions.joint_reactions`)."""
    return joint_reactions(load_parameters(result.meta["mechanism"], result.meta["variant"]), result)


def state_deviations(run: SimulationResult, ref: SimulationResult,
                     fields: Iterable[str] = ("q", "qd", "lam")) -> dict[str, float]:
    """``max_abs_d<field>``: max over common samples and components of |run - ref| of each state field."""
    ia, ib = common_samples(run, ref)
    return {f"max_abs_d{f}": float(np.abs(getattr(run, f)[ia] - getattr(ref, f)[ib]).max()) for f in fields}


def deviations(run: SimulationResult, ref: SimulationResult) -> dict[str, float]:
    """max over common samples of |run - ref| for q, qd, lam, tangential and normal force."""
    out = state_deviations(run, ref)
    ia, ib = common_samples(run, ref)
    nr, nf = normal_force(run), normal_force(ref)
    out["max_abs_dN"] = float(np.abs(nr[ia] - nf[ib]).max()) if nr is not None else float("nan")
    fr, ff = tangential_force(run), tangential_force(ref)
    out["max_abs_dF_friction"] = float(np.abs(fr[ia] - ff[ib]).max()) if fr is not None and ff is not None \
        else float("nan")
    out["max_abs_F_friction_ref"] = float(np.abs(ff[ib]).max()) if ff is not None else float("nan")
    out["max_abs_N_ref"] = float(np.abs(nf[ib]).max()) if nf is not None else float("nan")
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
    return out | joint_force_deviations(run, ref, ref_joints)


def joint_force_deviations(run: SimulationResult, ref: SimulationResult,
                           ref_joints: dict[str, Array]) -> dict[str, tuple[float, float]]:
    """Per joint force component of ``ref_joints`` (the reactions of the in-house run ``ref``, by name):
    (max |run's force of that name - in-house|, max |in-house|) over common samples; the moments are left out
    (Exudyn's PrismaticJoint2D outputs no constraint torque)."""
    ia, ib = common_samples(run, ref)
    return {name: (float(np.abs(run.forces[name][ia] - ref_joints[name][ib]).max()),
                   float(np.abs(ref_joints[name][ib]).max()))
            for name in sorted(ref_joints) if not name.endswith("_moment")}


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
        return f"tanh eps={opts.get('eps', DEFAULT_EPS):g}"
    if opts.get("friction", "none") == "none":   # the case lists name the frictionless runs of a mechanism with friction
        return "none"
    return f"{opts.get('friction_sgn', 'tanh')} eps={opts.get('friction_eps', DEFAULT_EPS):g}"


def _inhouse_label(case: Case) -> str:
    o = case.kwargs
    tol = f" rtol={o['rtol']:g}" if "rtol" in o else f" h={o['step']:g}" if "step" in o else ""
    return f"in-house {o.get('integrator', 'RK45')}{tol} {o.get('method', 'none')}"


def with_orders(frame: pd.DataFrame, columns: Iterable[str], by: Iterable[str] = ("set", "solver")) -> pd.DataFrame:
    """order_<c>: observed order between this row's step h and the next larger h of the same ``by`` group (the same
    set and solver); a row without a step (an in-house run, h NaN) or whose error or its predecessor's is not a
    finite number > 0 has none (NaN)."""
    frame = frame.copy()
    for c in columns:
        frame[f"order_{c.removeprefix('max_abs_')}"] = np.nan
    for _, group in frame[frame["h"].notna()].groupby(list(by)):
        sub = group.sort_values("h", ascending=False)
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
        switches = int(ref.stats.get("events", 0))
        ref_joints = inhouse_joint_forces(ref) if frictionless and not switches else None
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
            rows.append({**base, **dev, "max_abs_phi": float(np.abs(run.phi).max()), **extra,
                         "reference_switches": switches})
            timing.append({**base, "cpu_seconds": cpu, "inhouse_reference_cpu_seconds": ref_cpu,
                           "steps": int(run.stats.get("steps", 0))})
            if frictionless and case.engine == "exudyn" and not switches:
                for quantity, (diff, scale) in reaction_deviations(run, ref, ref_joints).items():
                    reactions.append({**base, "quantity": quantity, "max_abs_diff": diff, "max_abs_inhouse": scale,
                                      "relative": diff / scale if scale > 0 else np.nan})
    sort = ["mechanism", "variant", "friction", "engine", "solver", "h"]
    agreement = pd.DataFrame(rows)
    if not agreement.empty:
        agreement = with_orders(agreement, ["max_abs_dq", "max_abs_dqd", "max_abs_dF_friction", "max_abs_dN",
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
