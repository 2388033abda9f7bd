"""Coulomb friction in spatial joints in the spatial study (``reference/cases/spatial.toml``, the groups
``<mechanism>:friction_exact``, ``:friction_reference`` and ``:friction_exudyn``;
reference/spatial/friction_carriage.toml): the exact law in-house, and the regularized law (Exudyn's only one)
in-house at the reference tolerance against Exudyn at three steps.

:func:`summarize` writes
- ``spatial_friction``: per run, its law, the joints the exact law holds and when (``stuck_joints``,
  ``stick_times``, the located stick events in order), the energy balance's error max|E - E(0)| with the friction's
  work (``energy_balance_error``), the friction's total work (``dissipated_J``) and max|Phi|;
- ``spatial_friction_orders``: per Exudyn solver, quantity and step, the error against the in-house regularized run
  on the common samples (``max_abs_diff``: q, qd, the joint rows' multipliers, each joint's normal and friction
  force and the friction's work; for ``energy balance`` Exudyn's own balance error), the observed order against the
  next coarser step, and the quantity's verdict: ``order >= min_order`` where every order is at least
  ``min_order`` (cross_validation.toml), ``at floor`` where every error is at most its floor (not a
  discretization error: order_error_floor, and for forces and multipliers index3_reaction_floor_relative of the
  reference's largest value, cross_validation.toml), ``below min_order`` otherwise.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.compare import observed_orders
from study.pipeline import Case
from study.reference_data import tolerance
from study.results import SimulationResult
from study.studies.spatial_cases import role, setting

EXACT, REFERENCE, EXUDYN = "friction_exact", "friction_reference", "friction_exudyn"
ROLES = (EXACT, REFERENCE, EXUDYN)
BALANCE = "energy balance"


def is_friction(case: Case) -> bool:
    """Whether a case belongs to this part of the study (its group's role is one of ROLES)."""
    return role(case) in ROLES


def law(case: Case) -> str:
    o = case.kwargs
    if case.engine == "exudyn":
        return f"regularized eps={o['eps']:g}"
    return "exact" if o["friction"] == "exact" else f"{o['friction']} eps={o['friction_eps']:g}"


def _friction_works(r: SimulationResult) -> list[str]:
    return [k for k in r.energies if k.startswith("work_friction_")]


def stick_events(r: SimulationResult) -> tuple[str, str]:
    """(joints, times): the located stick events of an exact run in order, ';'-joined ('' for none)."""
    events = [x for x in r.stats.get("friction_transitions", []) if x.get("contact") and x["to"] == "stick"]
    return ";".join(x["contact"] for x in events), ";".join(repr(float(x["t"])) for x in events)


def run_row(case: Case, r: SimulationResult) -> dict:
    balance = r.energy_balance()
    joints, times = stick_events(r) if case.engine == "inhouse" else ("", "")
    return {"mechanism": case.mechanism, "engine": case.engine, "group": role(case), "setting": setting(case),
            "law": law(case), "t_end": case.t_end, "stuck_joints": joints, "stick_times": times,
            "energy_balance_error": float(np.abs(balance - balance[0]).max()),
            "dissipated_J": float(-sum(r.energies[k][-1] for k in _friction_works(r))),
            "max_abs_phi": float(np.abs(r.phi).max())}


def differences(r: SimulationResult, ref: SimulationResult) -> dict[str, tuple[float, float]]:
    """quantity -> (max|r - ref| on the common samples, its floor) (module docstring)."""
    if r.t.shape != ref.t.shape or np.abs(r.t - ref.t).max() > tolerance("round_off") * r.t[-1]:
        raise ValueError(f"{r.meta.get('mechanism')}: the Exudyn run's samples are not its reference's "
                         f"({len(r.t)} against {len(ref.t)})")
    floor = tolerance("order_error_floor", "cross_validation")
    relative = tolerance("index3_reaction_floor_relative", "cross_validation")
    joints = [k for k, n in enumerate(ref.meta["constraint_names"]) if not n.endswith("_norm")]
    out = {"q": (np.abs(r.q - ref.q).max(), floor), "qd": (np.abs(r.qd - ref.qd).max(), floor),
           "joint multipliers": (np.abs(r.lam[:, joints] - ref.lam[:, joints]).max(),
                                 max(floor, relative * np.abs(ref.lam[:, joints]).max()))}
    for key in ref.forces:
        if key.startswith(("normal_", "friction_")):
            out[key] = (np.abs(r.forces[key] - ref.forces[key]).max(),
                        max(floor, relative * np.abs(ref.forces[key]).max()))
    for key in _friction_works(ref):
        out[key] = (np.abs(r.energies[key] - ref.energies[key]).max(), floor)
    balance = r.energy_balance()
    out[BALANCE] = (np.abs(balance - balance[0]).max(), floor)
    return {k: (float(e), float(f)) for k, (e, f) in out.items()}


def verdict(errors: Sequence[float], orders: Sequence[float], floor: float) -> str:
    if max(errors) <= floor:
        return "at floor"
    return "order >= min_order" if min(orders) >= tolerance("min_order", "cross_validation") else "below min_order"


def order_rows(runs: list[tuple[Case, SimulationResult]], ref: SimulationResult) -> list[dict]:
    """The rows of ``spatial_friction_orders`` of one mechanism's Exudyn runs (any solvers, any steps)."""
    rows = []
    for solver in sorted({c.kwargs.get("solver", "index3") for c, _ in runs}):
        series = sorted(((c.kwargs["h"], differences(r, ref)) for c, r in runs
                         if c.kwargs.get("solver", "index3") == solver), reverse=True)
        steps = [h for h, _ in series]
        for quantity, (_, floor) in series[0][1].items():
            errors = [d[quantity][0] for _, d in series]
            orders = [np.nan, *observed_orders(steps, errors)]
            judged = verdict(errors, orders[1:], floor)
            rows += [{"mechanism": runs[0][0].mechanism, "solver": solver, "quantity": quantity, "h": h,
                      "max_abs_diff": e, "order": float(o), "floor": floor, "verdict": judged}
                     for h, e, o in zip(steps, errors, orders)]
    return rows


def summarize(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    """The tables of the module docstring (from the cases of ROLES only)."""
    cases = [c for c in cases if is_friction(c)]
    loaded = [(c, load(c)) for c in cases]
    references = {c.mechanism: r for c, r in loaded if role(c) == REFERENCE}
    orders = []
    for mechanism, ref in references.items():
        exudyn = [(c, r) for c, r in loaded if c.mechanism == mechanism and role(c) == EXUDYN]
        if exudyn:
            orders += order_rows(exudyn, ref)
    return {"spatial_friction": pd.DataFrame([run_row(c, r) for c, r in loaded]),
            "spatial_friction_orders": pd.DataFrame(orders)}
