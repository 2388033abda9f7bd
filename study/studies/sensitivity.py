"""Sensitivity of the constraint stabilization to its gains (SPEC sec. 5, 'Sensitivity').

Paper 001 gives neither the Baumgarte gains (d, omega; eq. 11) nor the sliding-mode gains (Lambda,
K, k; eqs. 14-17) nor the width of its sgn approximations. The case list
``reference/cases/sensitivity.toml`` sweeps them for the quick-return mechanism with 001's on/off
cutting law over 5 s (the case list says why 5 s), at one integrator setting (RK45, rtol 1e-8), and
compares every run with a high-accuracy reference (DOP853, rtol 1e-12, projection).

:func:`summarize` writes

- ``sensitivity``: one row per run: its gains, max|Phi|, max|Phidot|, max|dq| against the reference
  on common samples, the energy-balance error, and the deterministic work counts (nfev, steps);
- ``sensitivity_timing``: CPU seconds per run (machine-dependent, kept apart);
- ``sensitivity_horizon``: for the 20 s runs of the group 'horizon_check', max|Phi| over the first
  5 s (``max_abs_phi_short``) against the whole run (``max_abs_phi_full``), the evidence that 5 s
  is long enough for the stabilized runs.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.compare import common_samples
from study.pipeline import Case, find, find_one
from study.results import SimulationResult

Load = Callable[[Case], SimulationResult]

# The gains and settings reported per run, in column order (blank where they do not apply).
PARAMETER_COLUMNS = ("d", "omega", "Lambda", "K", "k", "width")


def run_metrics(result: SimulationResult, reference: SimulationResult) -> dict:
    """max|Phi|, max|Phidot|, max|q - q_ref| on common samples, energy-balance error, work counts."""
    s = result.summary()
    ia, ib = common_samples(result, reference)
    return {
        "max_abs_phi": s["max_abs_phi"],
        "max_abs_phidot": s["max_abs_phidot"],
        "max_abs_dq_vs_reference": float(np.abs(result.q[ia] - reference.q[ib]).max()),
        "energy_error": s["energy_error"],
        "energy_error_relative": s["energy_error_relative"],
        "nfev": result.stats.get("nfev"),
        "steps": result.stats.get("steps"),
    }


def describe(case: Case) -> dict:
    """The identifying columns of a run: group, method, sgn, integrator setting and gains."""
    o = case.kwargs
    setting = f"{o['integrator']} h={o['step']:g}" if o["integrator"] == "RK4" else \
        f"{o['integrator']} rtol={o['rtol']:g}"
    row = {"group": case.group, "method": o.get("method", "none"), "sgn": o.get("sgn", ""),
           "integrator_setting": setting}
    row.update({p: o.get(p, np.nan) for p in PARAMETER_COLUMNS})
    return row


def summarize(cases: Sequence[Case], load: Load) -> dict[str, pd.DataFrame]:
    """The study's tables (rows in case-list order); see the module docstring.

    A run that failed or is missing gets a row with ``status`` saying so and blank metrics; the
    reference must exist (LookupError otherwise).
    """
    reference = load(find_one(cases, group="reference"))
    rows, timing = [], []
    for case in cases:
        if case.group in ("reference", "horizon_check"):
            continue
        row = describe(case)
        try:
            result = load(case)
        except LookupError as exc:
            rows.append({**row, "status": f"failed: {exc}"})
            timing.append({**row, "cpu_seconds": np.nan})
            continue
        rows.append({**row, **run_metrics(result, reference), "status": "ok"})
        timing.append({**row, "cpu_seconds": result.stats.get("cpu_seconds"), "nfev": result.stats.get("nfev")})
    tables = {"sensitivity": pd.DataFrame(rows), "sensitivity_timing": pd.DataFrame(timing)}

    horizon = []
    short_horizon = reference.t[-1]  # the horizon of every grid: the reference's (see the case list)
    for case in find(cases, group="horizon_check"):
        result = load(case)
        phi = np.abs(result.phi).max(axis=1)
        early = result.t <= short_horizon + 1e-9
        quarter = max(len(result.t) // 4, 1)
        horizon.append({
            "setting": case.label("setting"), "short_horizon": short_horizon, "t_end": case.t_end,
            "max_abs_phi_short": float(phi[early].max()),
            "max_abs_phi_full": float(phi.max()),
            "ratio_full_to_short": float(phi.max() / max(phi[early].max(), 1e-300)),
            "max_abs_phi_last_quarter": float(phi[-quarter:].max()),
        })
    if horizon:
        tables["sensitivity_horizon"] = pd.DataFrame(horizon)
    return tables
