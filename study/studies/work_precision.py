"""Convergence and work-precision of the in-house methods (SPEC sec. 5, 'Accuracy').

The case list ``reference/cases/work_precision.toml`` runs the quick-return with the smooth cutting
law for 5 s with every stabilization method (none, Baumgarte, sliding mode, projection), with
adaptive RK45 and DOP853 over rtol 1e-4 ... 1e-11 and with fixed-step RK4 over h, against a DOP853
rtol 1e-13 projection reference. Two more RK4 groups measure the observed convergence order: over
the smooth first 0.08 s, and over one whole crank revolution (1 s) with every ramp of the cutting law.

:func:`summarize` writes

- ``work_precision``: one row per run: method, integrator, rtol or h, max|q - q_ref| on common
  samples (the error), nfev and steps (deterministic cost), max|Phi|;
- ``work_precision_timing``: the same keys with the backend, the case name and CPU seconds (machine-dependent,
  kept apart; the sweeps run compiled, and the reference-path CPU of their sampled twins is in
  ``backend_cpu_timing``, joined on the case name by the report);
- ``work_precision_orders``: observed orders p = log(e_k / e_k+1) / log(h_k / h_k+1) between
  consecutive step sizes of every RK4 series (:func:`study.compare.observed_orders`).
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.compare import max_deviation, observed_orders
from study.pipeline import Case, find_one
from study.results import SimulationResult

Load = Callable[[Case], SimulationResult]
RK4_SERIES = ("rk4", "rk4_order_smooth", "rk4_order_revolution")  # groups whose steps form a series


def describe(case: Case) -> dict:
    """Identifying columns: group, method label, integrator, rtol or step h, horizon."""
    o = case.kwargs
    return {"group": case.group, "method": case.label("method", o.get("method", "none")),
            "integrator": o["integrator"], "rtol": o.get("rtol", np.nan), "step": o.get("step", np.nan),
            "t_end": case.t_end}


def run_row(case: Case, result: SimulationResult, reference: SimulationResult) -> dict:
    """Error on common samples up to the case's horizon, cost counts, max|Phi|."""
    s = result.summary()
    return {**describe(case),
            "max_abs_dq": max_deviation(result, reference, "q", t_max=case.t_end),
            "nfev": result.stats.get("nfev"), "steps": result.stats.get("steps"),
            "max_abs_phi": s["max_abs_phi"], "max_abs_phidot": s["max_abs_phidot"],
            "energy_error_relative": s["energy_error_relative"]}


def order_rows(table: pd.DataFrame) -> pd.DataFrame:
    """Observed orders between consecutive step sizes of each RK4 series (group, method)."""
    rows = []
    series = table[table["group"].isin(RK4_SERIES)]
    for (group, method), runs in series.groupby(["group", "method"], sort=False):
        runs = runs.sort_values("step", ascending=False)
        h, e = runs["step"].to_numpy(dtype=float), runs["max_abs_dq"].to_numpy(dtype=float)
        if len(h) < 2:
            continue
        p = observed_orders(h, e)
        for k in range(len(p)):
            rows.append({"group": group, "method": method, "t_end": runs["t_end"].iloc[0], "h_coarse": h[k],
                         "h_fine": h[k + 1], "error_coarse": e[k], "error_fine": e[k + 1], "observed_order": p[k]})
    return pd.DataFrame(rows, columns=["group", "method", "t_end", "h_coarse", "h_fine", "error_coarse",
                                       "error_fine", "observed_order"])


def summarize(cases: Sequence[Case], load: Load) -> dict[str, pd.DataFrame]:
    """The study's tables (rows in case-list order); see the module docstring."""
    reference = load(find_one(cases, group="reference"))
    rows, timing = [], []
    for case in cases:
        if case.group == "reference":
            continue
        result = load(case)
        rows.append(run_row(case, result, reference))
        timing.append({**describe(case), "backend": case.kwargs.get("backend", "reference"), "case": case.name,
                       "cpu_seconds": result.stats.get("cpu_seconds"), "nfev": result.stats.get("nfev")})
    table = pd.DataFrame(rows)
    ref_row = {"group": "reference", "backend": "reference", "cpu_seconds": reference.stats.get("cpu_seconds"),
               "nfev": reference.stats.get("nfev")}
    return {"work_precision": table,
            "work_precision_timing": pd.concat([pd.DataFrame(timing), pd.DataFrame([ref_row])], ignore_index=True),
            "work_precision_orders": order_rows(table)}


def rk4_order_verdict(orders: pd.DataFrame, group: str, band: float, expected: float = 4.0) -> dict:
    """Whether the finest pair of an RK4 series has the expected order within ``band``."""
    sel = orders[orders["group"] == group].sort_values("h_fine")
    if sel.empty:
        return {"group": group, "observed_order": np.nan, "holds": False}
    p = float(sel["observed_order"].iloc[0])
    return {"group": group, "observed_order": p, "holds": bool(abs(p - expected) <= band)}

