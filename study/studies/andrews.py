"""Andrews' squeezing mechanism against the Test Set's published reference solution.

The case list ``reference/cases/andrews.toml`` runs the in-house reference (DOP853, rtol 1e-13),
every stabilization method with adaptive RK45 / DOP853 / Radau over rtol and fixed-step RK4 over h,
and Exudyn (index 3, index 2) over h, all to t = 0.03 s. The published values (the Test Set's
``andrews.f``, PSIDE at tolerance 1e-14) are read from ``reference/andrews_published.toml``.

:func:`summarize` writes

- ``andrews_reference``: per angle and rate at t = 0.03 s: published value, in-house reference,
  difference (absolute and relative);
- ``andrews_work_precision``: one row per run: engine, backend, method, integrator or solver, rtol or step,
  the error at 0.03 s against the published values (``error_published``, max over the seven angles [rad]; and
  ``relative_error_published``, max |q_i - q_i,pub| / |q_i,pub|, whose -log10 is the Test Set's significant
  correct digits, scd) and against the in-house reference (``error_reference``), evaluations or steps, max|Phi|;
- ``andrews_work_precision_timing``: the same keys with CPU seconds (machine-dependent, kept apart);
- ``andrews_orders``: observed orders between consecutive steps of every fixed-step series (RK4
  per method, Exudyn per solver), against the published values and against the in-house reference.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.compare import observed_orders
from study.pipeline import Case, find_one
from study.reference_data import values
from study.results import SimulationResult

Load = Callable[[Case], SimulationResult]
TABLE = "andrews_published"
COORDINATES = ("beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon")
KEYS = ["group", "engine", "backend", "method", "integrator", "rtol", "step"]


def published() -> tuple[np.ndarray, np.ndarray]:
    """The Test Set's q and qd at t = 0.03 s."""
    return np.array(values("q_t003", table=TABLE)), np.array(values("qd_t003", table=TABLE))


def final_state(result: SimulationResult, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """q, qd at the case's horizon (the last sample, checked to be at t_end)."""
    if not np.isclose(result.t[-1], t_end, rtol=0, atol=1e-12):
        raise ValueError(f"the run ends at t = {result.t[-1]!r}, not at the horizon {t_end!r}")
    return result.q[-1], result.qd[-1]


def describe(case: Case) -> dict:
    """Identifying columns: group, engine, backend, method, integrator (Exudyn: its solver), rtol, step (h)."""
    o = case.kwargs
    if case.engine == "exudyn":
        return {"group": case.group, "engine": "exudyn", "backend": "exudyn", "method": "exudyn",
                "integrator": o.get("solver", "index3"), "rtol": np.nan, "step": o["h"]}
    return {"group": case.group, "engine": "inhouse", "backend": o.get("backend", "reference"),
            "method": case.label("method", o.get("method", "none")), "integrator": o["integrator"],
            "rtol": o.get("rtol", np.nan), "step": o.get("step", np.nan)}


def reference_rows(q: np.ndarray, qd: np.ndarray) -> pd.DataFrame:
    """The in-house reference against the published values, angle by angle and rate by rate."""
    q_pub, qd_pub = published()
    rows = []
    for kind, ours, theirs, unit in (("angle", q, q_pub, "rad"), ("rate", qd, qd_pub, "rad/s")):
        for name, a, b in zip(COORDINATES, ours, theirs):
            rows.append({"quantity": kind, "coordinate": name, "unit": unit, "published": b, "inhouse": a,
                         "difference": a - b, "relative_difference": (a - b) / abs(b)})
    return pd.DataFrame(rows)


def order_rows(table: pd.DataFrame) -> pd.DataFrame:
    """Observed orders between consecutive steps of each fixed-step series (RK4 per method, Exudyn per solver)."""
    rows = []
    fixed = table[table["group"].isin(["rk4", "exudyn"])]
    for (group, method, integrator), runs in fixed.groupby(["group", "method", "integrator"], sort=False):
        runs = runs.sort_values("step", ascending=False)
        h = runs["step"].to_numpy(dtype=float)
        if len(h) < 2:
            continue
        p_pub = observed_orders(h, runs["error_published"].to_numpy(dtype=float))
        p_ref = observed_orders(h, runs["error_reference"].to_numpy(dtype=float))
        for k in range(len(p_pub)):
            rows.append({"group": group, "method": method, "integrator": integrator, "h_coarse": h[k],
                         "h_fine": h[k + 1], "error_published_coarse": runs["error_published"].iloc[k],
                         "error_published_fine": runs["error_published"].iloc[k + 1], "order_published": p_pub[k],
                         "error_reference_fine": runs["error_reference"].iloc[k + 1], "order_reference": p_ref[k]})
    return pd.DataFrame(rows, columns=["group", "method", "integrator", "h_coarse", "h_fine", "error_published_coarse",
                                       "error_published_fine", "order_published", "error_reference_fine",
                                       "order_reference"])


def summarize(cases: Sequence[Case], load: Load) -> dict[str, pd.DataFrame]:
    """The study's tables (rows in case-list order); see the module docstring."""
    ref_case = find_one(cases, group="reference")
    reference = load(ref_case)
    q_ref, qd_ref = final_state(reference, ref_case.t_end)
    q_pub, _ = published()
    rows, timing = [], []
    for case in cases:
        result = load(case)
        q, _ = final_state(result, case.t_end)
        s = result.summary()
        rows.append({**describe(case), "error_published": float(np.abs(q - q_pub).max()),
                     "relative_error_published": float((np.abs(q - q_pub) / np.abs(q_pub)).max()),
                     "error_reference": float(np.abs(q - q_ref).max()),
                     "nfev": result.stats.get("nfev", np.nan), "steps": result.stats.get("steps", np.nan),
                     "max_abs_phi": s["max_abs_phi"]})
        timing.append({**describe(case), "cpu_seconds": result.stats.get("cpu_seconds")})
    table = pd.DataFrame(rows)
    return {"andrews_reference": reference_rows(q_ref, qd_ref),
            "andrews_work_precision": table,
            "andrews_work_precision_timing": pd.DataFrame(timing),
            "andrews_orders": order_rows(table)}
