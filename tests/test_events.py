"""Event location (study.laws.events): the scan and Brent's root of a crossing, in Python and compiled."""

from __future__ import annotations

import math

import pytest
from numba import njit
from scipy.optimize import brentq

from study.laws.events import BRENT_MAXITER, BRENT_RTOL, BRENT_XTOL, SCAN_POINTS, crossing_finder


FUNCTIONS = {   # g(t, c) and its exact root
    "cos": (lambda t, c: math.cos(t) - c, lambda c: math.acos(c)),
    "ninth power": (lambda t, c: t**9 - c, lambda c: c ** (1 / 9)),   # flat: Brent falls back to bisection
    "exp": (lambda t, c: math.exp(20 * t) - c, lambda c: math.log(c) / 20),
}
ROOTS_IN_STEP = [("cos", 0.55), ("cos", 0.9), ("ninth power", 0.001), ("ninth power", 0.123), ("ninth power", 0.3),
                 ("ninth power", 0.55), ("ninth power", 0.9), ("exp", 2.0), ("exp", 100.0)]   # roots in [0, 1]


@pytest.mark.parametrize("name, c", ROOTS_IN_STEP)
def test_brent_is_scipys_brentq(name, c):
    """Where the step starts on its side, the root is scipy's brentq's, bit for bit, and within its tolerance of
    the exact root."""
    g, exact = FUNCTIONS[name]
    root = crossing_finder(g)(1 if g(0.0, c) > 0 else -1, 0.0, 1.0, c)
    assert root == brentq(g, 0.0, 1.0, args=(c,), xtol=BRENT_XTOL, rtol=BRENT_RTOL)
    assert 0.0 < root < 1.0 and abs(root - exact(c)) <= BRENT_XTOL + BRENT_RTOL * abs(root)


def test_no_convergence_in_brent_maxiter_is_nan_where_scipy_raises():
    """(t - 0.3)^3 is too flat at its root for BRENT_XTOL in BRENT_MAXITER iterations."""
    with pytest.raises(RuntimeError, match="converge"):
        brentq(lambda t: (t - 0.3) ** 3, 0.0, 1.0, xtol=BRENT_XTOL, rtol=BRENT_RTOL, maxiter=BRENT_MAXITER)
    assert math.isnan(crossing_finder(lambda t: (t - 0.3) ** 3)(-1, 0.0, 1.0))


def test_compiled_and_python_roots_are_the_same():
    """The compiled law (as the compiled loop builds it: the function of t fixed, its data in *args) and the Python
    law (as the reference loop runs it) give the same root, also for a crossing found by the scan."""
    g = njit(lambda t, a, b: (t - a) * (t - b))
    compiled, python = njit(crossing_finder(g)), crossing_finder(g.py_func)
    for sign, a, b in ((1, 0.3, 5.0), (-1, 0.2, 0.7), (-1, 0.05, 0.61)):
        assert compiled(sign, 0.0, 1.0, a, b) == python(sign, 0.0, 1.0, a, b), (sign, a, b)


def test_a_step_that_starts_across_and_comes_back_locates_the_later_crossing():
    """g(t) = (t - 0.2)(t - 0.7) with sign -1 starts on the far side (g(0) > 0), returns to the side after 0.2 and
    leaves it at 0.7: that crossing is the one located."""
    root = crossing_finder(lambda t: (t - 0.2) * (t - 0.7))(-1, 0.0, 1.0)
    assert abs(root - 0.7) <= BRENT_XTOL + BRENT_RTOL * 0.7


def test_a_step_that_stays_across_switches_at_its_start():
    assert crossing_finder(lambda t: 1.0 + t)(-1, 0.25, 1.0) == 0.25


@pytest.mark.parametrize("g, why", [
    (lambda t: t - 0.2 if t < 0.5 else 0.3, "starts across, comes back to the side and stays there"),
    (lambda t: 1.0 + t, "no sign change between the ends of the step (scipy's brentq: ValueError)"),
    (lambda t: math.nan if t > 0.5 else 1.0 - 2 * t, "g is NaN (scipy's brentq: ValueError)"),
])
def test_what_cannot_be_located_is_nan(g, why):
    assert math.isnan(crossing_finder(g)(1, 0.0, 1.0)), why


def test_the_scan_samples_the_step_at_scan_points():
    """The scan evaluates g at t_lo (the side test), then at t_lo + (t_hi - t_lo) k / SCAN_POINTS, k = 1, 2, ...
    until it is back on the side: here never, so at every one of them."""
    seen = []

    def g(t):
        seen.append(t)
        return 1.0
    assert crossing_finder(g)(-1, 2.0, 3.0) == 2.0
    assert seen == [2.0] + [2.0 + k / SCAN_POINTS for k in range(1, SCAN_POINTS + 1)]
