"""IFToMM benchmark A01, the simple pendulum, judged by its own criterion against the exact motion.

The case list ``reference/cases/a01.toml`` runs the Cartesian description (``study/mechanisms/a01_pendulum.py``)
over the benchmark's 2000 s with every method and tolerance, and Exudyn over the first 20 s. :func:`summarize`
writes ``a01_runs``: per run, the horizon, the largest error of x and y of P1 over the output steps against
:func:`study.reference_solutions.simple_pendulum_p1`, the benchmark's verdict (high precision, low precision or
fails: ``a01_high_precision`` / ``a01_low_precision`` in reference/benchmarks.toml, applied to the larger of the
two errors; "not judged: 20 s of 2000 s" for a run shorter than the benchmark's horizon ``a01_horizon``, whose
errors are shown but are not the benchmark's), the energy drift max|E - E0| and max|Phi|; a run that stopped, with
its error. CPU goes to ``a01_timing``.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.params import load_parameters
from study.pipeline import Case, MissingResult
from study.reference_data import tolerance
from study.reference_solutions import simple_pendulum_p1
from study.results import SimulationResult


def verdict(error: float, t_end: float) -> str:
    """The benchmark's verdict on the larger position error [m] of a run over ``t_end`` [s]: none for a run that
    stops short of the benchmark's horizon."""
    horizon = tolerance("a01_horizon", table="benchmarks")
    if t_end < horizon:
        return f"not judged: {t_end:g} s of {horizon:g} s"
    if error <= tolerance("a01_high_precision", table="benchmarks"):
        return "high precision"
    return "low precision" if error <= tolerance("a01_low_precision", table="benchmarks") else "fails"


def summarize(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    rows, timing = [], []
    for case in cases:
        o = case.kwargs
        key = {"engine": case.engine,
               "method": case.label("method", o.get("method", "none")) if case.engine == "inhouse" else "exudyn",
               "setting": f"{o['integrator']} rtol={o['rtol']:g}" if case.engine == "inhouse" else
               f"{o.get('solver', 'index3')} h={o['h']:g}"}
        try:
            r = load(case)
        except MissingResult as exc:   # a run that stopped (its case list expects it): the stop is the result
            kind = str(exc).partition("it failed: ")[2].partition(":")[0]   # when it stops is not reproducible
            rows.append({**key, "t_end_s": case.t_end, "a01_verdict": "stopped", "error": kind})
            continue
        v = load_parameters(case.mechanism, case.variant).values
        x, y = simple_pendulum_p1(r.t, v.L, v.g)
        errors = float(np.abs(r.q[:, 0] - x).max()), float(np.abs(r.q[:, 1] - y).max())
        energy = r.energies["kinetic"] + r.energies["potential"]
        rows.append({**key, "t_end_s": case.t_end, "output_steps": len(r.t) - 1, "x_max_error_m": errors[0],
                     "y_max_error_m": errors[1], "a01_verdict": verdict(max(errors), case.t_end),
                     "energy_drift_J": float(np.abs(energy - energy[0]).max()),
                     "max_abs_phi": float(np.abs(r.phi).max()), "error": ""})
        timing.append({**key, "cpu_s": float(r.stats.get("cpu_seconds", np.nan))})
    return {"a01_runs": pd.DataFrame(rows), "a01_timing": pd.DataFrame(timing)}
