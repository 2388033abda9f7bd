"""The singular-position study: the IFToMM A02 N-four-bar (N = 2, 10 s) with every method and engine.

For each case: whether it passed the horizontal positions (rank Phi_q drops from 2N to N there) or
stopped, where and why (the failure record the pipeline keeps), the drift of the total mechanical
energy max|E(t) - E(0)| (the mechanism is conservative), the constraint violation, B0's x coordinate at
the end, its largest distance from the exact motion (:func:`study.reference_solutions.n_four_bar_x_b0`)
over every output sample, the benchmark's verdict by that distance (high precision <= 1e-3 m, low
precision <= 1e-1 m: reference/benchmarks.toml), and the cost. A second table samples B0's x every
0.5 s for the reference motion and every run that finished.
"""

from __future__ import annotations

import re
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.params import load_parameters
from study.pipeline import Case, MissingResult
from study.reference_data import tolerance
from study.reference_solutions import n_four_bar_x_b0
from study.results import SimulationResult

SAMPLE_EVERY = 0.5   # [s] spacing of the B0 trajectory table
_STOPPED_AT = re.compile(r"t = ([0-9.eE+-]+) s")


def _method(case: Case) -> str:
    o = case.kwargs
    if case.engine == "exudyn":
        return f"{o['solver']}" + (" + ignoreSingularJacobian" if o.get("ignore_singular") else "")
    return f"{o['acceleration_solver']} + {o.get('method', 'none')}"


def _setting(case: Case) -> str:
    o = case.kwargs
    return f"h={o['h']:g}" if case.engine == "exudyn" else case.label("setting")


def x_b0(case: Case, r: SimulationResult) -> np.ndarray:
    """x of B0, the top of the first crank: L cos(th0) (relative coordinate 0 is the first crank's angle)."""
    return load_parameters(case.mechanism, case.variant).values.L * np.cos(r.q[:, 0])


def reference_x_b0(case: Case, t: np.ndarray) -> np.ndarray:
    """The exact x of B0 at the times t for the case's parameter set (B0 starting at -L th0'(0) along +x)."""
    ps = load_parameters(case.mechanism, case.variant)
    v = ps.values
    return n_four_bar_x_b0(t, int(v.N), v.L, v.g, v0=-v.L * ps.initial.qd_independent[0])


def a02_verdict(error: float) -> str:
    """The benchmark's verdict on a run whose x of B0 is at most ``error`` [m] from the reference motion."""
    if error <= tolerance("a02_high_precision", table="benchmarks"):
        return "high precision"
    return "low precision" if error <= tolerance("a02_low_precision", table="benchmarks") else "fails"


def summarize(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    rows, traj = [], {}
    for case in cases:
        row = {"engine": case.engine, "method": _method(case), "setting": _setting(case)}
        try:
            r = load(case)
        except MissingResult as exc:
            text = str(exc)
            found = _STOPPED_AT.findall(text)
            kind = re.search(r"it failed: (\w+)", text)
            rows.append({**row, "passed": False, "stopped_at_s": float(found[-1]) if found else np.nan,
                         "error": (kind.group(1) if kind else text)[:60], "energy_drift_J": np.nan,
                         "energy_drift_relative": np.nan, "max_abs_phi": np.nan, "x_B0_end_m": np.nan,
                         "x_B0_max_error_m": np.nan, "a02_verdict": "stopped",
                         "crank_spread_max_rad": np.nan, "nfev_or_steps": np.nan, "cpu_s": np.nan})
            continue
        E = r.energies["kinetic"] + r.energies["potential"]
        xb, reference = x_b0(case, r), reference_x_b0(case, r.t)
        error = float(np.abs(xb - reference).max())   # over every output sample (0.01 s): 1001, the benchmark's 400
        every = max(int(round(SAMPLE_EVERY / (r.t[1] - r.t[0]))), 1)
        traj.setdefault("reference (exact motion)", pd.Series(reference[::every], index=r.t[::every]))
        m = r.q.shape[1]
        cranks = r.q[:, : (m + 1) // 2]
        rows.append({**row, "passed": True, "stopped_at_s": np.nan, "error": "",
                     "energy_drift_J": float(np.abs(E - E[0]).max()),
                     "energy_drift_relative": float(np.abs(E - E[0]).max() / abs(E[0])),
                     "max_abs_phi": float(np.abs(r.phi).max()), "x_B0_end_m": float(xb[-1]),
                     "x_B0_max_error_m": error, "a02_verdict": a02_verdict(error),
                     "crank_spread_max_rad": float(np.ptp(cranks, axis=1).max()),
                     "nfev_or_steps": r.stats.get("nfev", r.stats.get("steps")),
                     "cpu_s": r.stats.get("cpu_seconds", np.nan)})
        traj[f"{row['method']} ({row['setting']}, {case.engine})"] = pd.Series(xb[::every], index=r.t[::every])
    runs = pd.DataFrame(rows)
    trajectory = pd.DataFrame(traj)
    trajectory.index.name = "t_s"
    # CPU seconds depend on the machine: they go to timing/, so tables/ stays byte-identical between runs
    timing = runs[["engine", "method", "setting", "cpu_s"]]
    return {"singular_four_bar_runs": runs.drop(columns="cpu_s"), "singular_four_bar_x_B0": trajectory.reset_index(),
            "singular_four_bar_timing": timing}
