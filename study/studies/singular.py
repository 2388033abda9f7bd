"""The singular-position study: the IFToMM A02 N-four-bar (N = 2, 10 s) with every method and engine.

For each case: whether it passed the horizontal positions (rank Phi_q drops from 2N to N there) or
stopped, where and why (the failure record the pipeline keeps), the drift of the total mechanical
energy max|E(t) - E(0)| (the benchmark's accuracy measure; the mechanism is conservative), the
constraint violation, B0's x coordinate at the end, and the cost. A second table samples B0's x every
0.5 s for every run that finished (the benchmark's trajectory output).
"""

from __future__ import annotations

import re
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.params import load_parameters
from study.pipeline import Case, MissingResult
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
                         "crank_spread_max_rad": np.nan, "nfev_or_steps": np.nan, "cpu_s": np.nan})
            continue
        E = r.energies["kinetic"] + r.energies["potential"]
        m = r.q.shape[1]
        cranks = r.q[:, : (m + 1) // 2]
        rows.append({**row, "passed": True, "stopped_at_s": np.nan, "error": "",
                     "energy_drift_J": float(np.abs(E - E[0]).max()),
                     "energy_drift_relative": float(np.abs(E - E[0]).max() / abs(E[0])),
                     "max_abs_phi": float(np.abs(r.phi).max()), "x_B0_end_m": float(x_b0(case, r)[-1]),
                     "crank_spread_max_rad": float(np.ptp(cranks, axis=1).max()),
                     "nfev_or_steps": r.stats.get("nfev", r.stats.get("steps")),
                     "cpu_s": r.stats.get("cpu_seconds", np.nan)})
        every = max(int(round(SAMPLE_EVERY / (r.t[1] - r.t[0]))), 1)
        traj[f"{row['method']} ({row['setting']}, {case.engine})"] = pd.Series(x_b0(case, r)[::every], index=r.t[::every])
    runs = pd.DataFrame(rows)
    trajectory = pd.DataFrame(traj)
    trajectory.index.name = "t_s"
    # CPU seconds depend on the machine: they go to timing/, so tables/ stays byte-identical between runs
    timing = runs[["engine", "method", "setting", "cpu_s"]]
    return {"singular_four_bar_runs": runs.drop(columns="cpu_s"), "singular_four_bar_x_B0": trajectory.reset_index(),
            "singular_four_bar_timing": timing}
