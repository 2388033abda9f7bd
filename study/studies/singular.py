"""The singular-position study: the IFToMM A02 N-four-bar (N = 2 over 10 s, N = 40 over 20 s) with every
method and engine.

For each case: whether it passed the horizontal positions (rank Phi_q drops from 2N to N there) or
stopped, where and why (the failure record the pipeline keeps), the drift of the total mechanical
energy max|E(t) - E(0)| (the mechanism is conservative), the largest change of E between two output
samples and how far in time it lies from the nearest crossing of a horizontal position (a jump made at a
crossing lies within a sample of it), the solves whose iteration reached its limit (ALI3P: steps; the
acceleration-level augmented Lagrangian: evaluations), the constraint violation, B0's x coordinate at the
end, the largest distance of B0's x and of its rate from the exact motion
(:func:`study.reference_solutions.n_four_bar_b0`) over every output sample, the benchmark's verdict by both
(high precision: both <= 1e-3 m, m/s; low precision: <= 1e-1: reference/benchmarks.toml), for N = 2 the
difference of x_B0(10 s) from the value Exudyn's IFToMM four-bar test model publishes (``a02_published_x_b0_10s``,
computed from the run at full precision: the table's x_B0_end_m has 6 digits, too few to tell a miss of 5e-6 m),
and the cost. A second table samples B0's x every 0.5 s for the reference motion and every N = 2 run that finished.
"""

from __future__ import annotations

import re
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.params import load_parameters
from study.pipeline import Case, MissingResult
from study.reference_data import tolerance
from study.reference_solutions import n_four_bar_b0
from study.results import SimulationResult

SAMPLE_EVERY = 0.5   # [s] spacing of the B0 trajectory table
PUBLISHED_AT = 10.0  # [s] the time of Exudyn's published x_B0 (reference/benchmarks.toml a02_published_x_b0_10s), N = 2
_STOPPED_AT = re.compile(r"t = ([0-9.eE+-]+) s")


def _method(case: Case) -> str:
    o = case.kwargs
    if case.engine == "exudyn":
        return (f"{o['solver']}" + (" + ignoreSingularJacobian" if o.get("ignore_singular") else "")
                + (" + EigenSparse" if o.get("linear_solver") == "sparse" else "")
                + (f", Newton tolerance {o['newton_tolerance']:g}" if "newton_tolerance" in o else ""))
    if o.get("integrator") == "ALI3P":
        return "ALI3P (index-3 augmented Lagrangian)"
    return f"{o['acceleration_solver']} + {o.get('method', 'none')}"


def _largest_energy_step(t: np.ndarray, E: np.ndarray, theta: np.ndarray) -> tuple[float, float]:
    """The largest |E(t_k+1) - E(t_k)| between output samples, and the time from the middle of that interval to
    the nearest crossing of a horizontal position (sin theta changes sign; the crossing by linear interpolation)."""
    k = int(np.argmax(np.abs(np.diff(E))))
    s = np.sin(theta)
    i = np.flatnonzero(s[:-1] * s[1:] < 0)
    crossings = t[i] + (t[i + 1] - t[i]) * s[i] / (s[i] - s[i + 1])
    middle = 0.5 * (t[k] + t[k + 1])
    to_crossing = float(np.min(np.abs(crossings - middle))) if crossings.size else np.nan
    return float(abs(E[k + 1] - E[k])), to_crossing


def _setting(case: Case) -> str:
    o = case.kwargs
    return f"h={o['h']:g}" if case.engine == "exudyn" else case.label("setting")


def run_label(case: Case) -> str:
    """A run's name in the tables and figures: method (setting, engine)."""
    return f"{_method(case)} ({_setting(case)}, {case.engine})"


def b0(case: Case, r: SimulationResult) -> tuple[np.ndarray, np.ndarray]:
    """x of B0, the top of the first crank, L cos(th0), and its rate -L sin(th0) th0' (relative coordinate 0 is
    the first crank's angle)."""
    length = load_parameters(case.mechanism, case.variant).values.L
    return length * np.cos(r.q[:, 0]), -length * np.sin(r.q[:, 0]) * r.qd[:, 0]


def reference_b0(case: Case, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The exact x of B0 and its rate at the times t for the case's parameter set (B0 starting at -L th0'(0)
    along +x)."""
    ps = load_parameters(case.mechanism, case.variant)
    v = ps.values
    return n_four_bar_b0(t, int(v.N), v.L, v.g, v0=-v.L * ps.initial.qd_independent[0])


def a02_verdict(error: float) -> str:
    """The benchmark's verdict on a run whose B0 (x [m] and its rate [m/s]) is at most ``error`` from the
    reference motion."""
    if error <= tolerance("a02_high_precision", table="benchmarks"):
        return "high precision"
    return "low precision" if error <= tolerance("a02_low_precision", table="benchmarks") else "fails"


def minus_published(n: int, t: np.ndarray, xb: np.ndarray) -> float:
    """x_B0(10 s) of an N = 2 run minus the value Exudyn's IFToMM four-bar test model publishes; NaN for another N
    or a run that does not end at 10 s."""
    if n != 2 or not np.isclose(t[-1], PUBLISHED_AT, rtol=0, atol=1e-9):
        return np.nan
    return float(xb[-1]) - tolerance("a02_published_x_b0_10s", table="benchmarks")


def summarize(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    rows, traj = [], {}
    for case in cases:
        row = {"engine": case.engine, "method": _method(case), "setting": _setting(case),
               "N": int(load_parameters(case.mechanism, case.variant).values.N), "t_end_s": case.t_end}
        try:
            r = load(case)
        except MissingResult as exc:
            text = str(exc)
            found = _STOPPED_AT.findall(text)
            kind = re.search(r"it failed: (\w+)", text)
            rows.append({**row, "passed": False, "stopped_at_s": float(found[-1]) if found else np.nan,
                         "error": (kind.group(1) if kind else text)[:60], "energy_drift_J": np.nan,
                         "energy_drift_relative": np.nan, "largest_energy_step_J": np.nan,
                         "largest_energy_step_to_crossing_s": np.nan, "solves_at_iteration_limit": np.nan,
                         "max_abs_phi": np.nan, "x_B0_end_m": np.nan, "x_B0_max_error_m": np.nan,
                         "vx_B0_max_error_m_s": np.nan, "a02_verdict": "stopped",
                         "x_B0_10s_minus_published_m": np.nan,
                         "crank_spread_max_rad": np.nan, "nfev_or_steps": np.nan, "cpu_s": np.nan})
            continue
        E = r.energies["kinetic"] + r.energies["potential"]
        (xb, vxb), (reference, reference_vx) = b0(case, r), reference_b0(case, r.t)
        error = float(np.abs(xb - reference).max())   # over every output sample: 1001 or 401, the benchmark's 400
        error_vx = float(np.abs(vxb - reference_vx).max())
        every = max(int(round(SAMPLE_EVERY / (r.t[1] - r.t[0]))), 1)
        if row["N"] == 2:
            traj.setdefault("reference (exact motion)", pd.Series(reference[::every], index=r.t[::every]))
            traj[run_label(case)] = pd.Series(xb[::every], index=r.t[::every])
        step, to_crossing = _largest_energy_step(r.t, E, r.q[:, 0])
        at_limit = r.stats.get("newton_limit_steps", r.stats.get("al_unconverged", np.nan))
        m = r.q.shape[1]
        cranks = r.q[:, : (m + 1) // 2]
        rows.append({**row, "passed": True, "stopped_at_s": np.nan, "error": "",
                     "energy_drift_J": float(np.abs(E - E[0]).max()),
                     "energy_drift_relative": float(np.abs(E - E[0]).max() / abs(E[0])),
                     "largest_energy_step_J": step, "largest_energy_step_to_crossing_s": to_crossing,
                     "solves_at_iteration_limit": at_limit,
                     "max_abs_phi": float(np.abs(r.phi).max()), "x_B0_end_m": float(xb[-1]),
                     "x_B0_max_error_m": error, "vx_B0_max_error_m_s": error_vx,
                     "a02_verdict": a02_verdict(max(error, error_vx)),
                     "x_B0_10s_minus_published_m": minus_published(row["N"], r.t, xb),
                     "crank_spread_max_rad": float(np.ptp(cranks, axis=1).max()),
                     "nfev_or_steps": r.stats.get("nfev", r.stats.get("steps")),
                     "cpu_s": r.stats.get("cpu_seconds", np.nan)})
    runs = pd.DataFrame(rows)
    trajectory = pd.DataFrame(traj)
    trajectory.index.name = "t_s"
    # CPU seconds depend on the machine: they go to timing/, so tables/ stays byte-identical between runs
    timing = runs[["N", "engine", "method", "setting", "cpu_s"]]
    return {"singular_four_bar_runs": runs.drop(columns="cpu_s"), "singular_four_bar_x_B0": trajectory.reset_index(),
            "singular_four_bar_timing": timing}
