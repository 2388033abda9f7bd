"""Metrics that compare saved results: deviations on common samples, observed convergence orders."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from study.results import SimulationResult

# Two sample times are the same sample if they differ by less than this [s] (output grids are
# built as k * output_step, so equal grids agree to a few ulps of t <= 100 s).
TIME_MATCH = 1e-9


def common_samples(a: SimulationResult, b: SimulationResult, t_max: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Indices (ia, ib) of the sample times that a and b share (up to ``t_max``).

    A ValueError says so if they share none: results are compared on common samples only, never
    through interpolation, so a deviation is never an interpolation error.
    """
    ta, tb = np.asarray(a.t), np.asarray(b.t)
    ib = np.searchsorted(tb, ta - TIME_MATCH)
    ib = np.clip(ib, 0, len(tb) - 1)
    ok = np.abs(tb[ib] - ta) <= TIME_MATCH
    if t_max is not None:
        ok &= ta <= t_max + TIME_MATCH
    if not ok.any():
        raise ValueError(f"the results share no sample times (a: {ta[:3]}..., b: {tb[:3]}...)")
    return np.nonzero(ok)[0], ib[ok]


def max_deviation(a: SimulationResult, b: SimulationResult, field: str = "q", t_max: float | None = None) -> float:
    """max over common samples and components of |a.field - b.field| (field: q, qd, qdd, lam, or a force name)."""
    ia, ib = common_samples(a, b, t_max)
    if field in ("q", "qd", "qdd", "lam", "phi", "phidot"):
        xa, xb = getattr(a, field)[ia], getattr(b, field)[ib]
    else:
        xa, xb = a.forces[field][ia], b.forces[field][ib]
    return float(np.max(np.abs(np.asarray(xa) - np.asarray(xb))))


def observed_orders(steps: Sequence[float], errors: Sequence[float]) -> np.ndarray:
    """p_k = log(e_k / e_{k+1}) / log(h_k / h_{k+1}) for consecutive step sizes (any ratio)."""
    h, e = np.asarray(steps, dtype=float), np.asarray(errors, dtype=float)
    if h.shape != e.shape or h.size < 2:
        raise ValueError(f"need at least two matching steps and errors, got {h.size} and {e.size}")
    if np.any(h <= 0) or np.any(e <= 0):
        raise ValueError(f"steps {h} and errors {e} must be > 0 to take logarithms")
    return np.log(e[:-1] / e[1:]) / np.log(h[:-1] / h[1:])
