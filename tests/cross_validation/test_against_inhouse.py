"""Exudyn (generated from the descriptions) against the in-house high-accuracy reference (DOP853,
rtol 1e-12, projection, located switches). The mechanisms here have no friction; their Exudyn runs (friction
'none') are shared with test_reactions.py (frictionless_runs.py)."""

from functools import lru_cache

import numpy as np
import pytest

from cross_validation.frictionless_runs import FINE_STEP, frictionless_run
from study.params import load_parameters
from study.reference_data import tolerance
from study.simulate import simulate

OUTPUT_STEP = FINE_STEP  # common sampling of both codes [s]; a multiple of every Exudyn step used


def tol(key):
    return tolerance(key, table="cross_validation")


@lru_cache(maxsize=None)   # one reference for both Exudyn solvers
def reference(mechanism, variant, t_end):
    return simulate(mechanism, variant=variant, t_end=t_end, method="projection", integrator="DOP853",
                    rtol=tolerance("reference_rtol"), atol=tolerance("reference_atol"), output_step=OUTPUT_STEP)


def errors(mechanism, variant, t_end, solver, steps):
    ref = reference(mechanism, variant, t_end)
    rows = []
    for h in steps:
        r = frictionless_run(mechanism, variant, t_end, h, solver, OUTPUT_STEP)
        rows.append({
            "h": h,
            "dq": np.abs(r.q - ref.q).max(),
            "dqd": np.abs(r.qd - ref.qd).max(),
            "dlam": np.abs(r.lam - ref.lam).max() / np.abs(ref.lam).max(),
        })
    return ref, rows


def orders(values, steps):
    """Observed orders between successive steps (any ratio)."""
    values, steps = np.asarray(values, dtype=float), np.asarray(steps, dtype=float)
    return np.log(values[:-1] / values[1:]) / np.log(steps[:-1] / steps[1:])


def check_min_order(rows, steps, keys):
    """Every error above the reference's accuracy floor and every observed order >= min_order."""
    floor, low = tol("order_error_floor"), tol("min_order")
    for key in keys:
        e = [row[key] for row in rows]
        assert min(e) > floor, (key, e)
        observed = orders(e, steps)
        assert np.all(observed >= low), (key, observed, rows)


def full_cut_work():
    """Work [J] of one whole cut, from the parameters: F_cut over the window x_max - x_min, less the two
    x-ramps' widths (the smooth law's edges; the tanh ramps are odd about the edges, so this is a lower bound)."""
    v = load_parameters("quick_return", "smooth_cutting").values
    return v.F_cut * (v.x_cut_max - v.x_cut_min - 2 * v.x_ramp)


def cut_steps():
    h = tol("cut_steps")
    return [h, h / 2, h / 4]


@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_quick_return_through_the_first_cut_order_2(solver):
    """Smooth law over the first cut (cut_window: on at 0.29 s, off at 0.61 s), at steps that resolve
    the x-ramp (cut_steps): q, qd and the multipliers (the ram-guide force among them) converge to
    the in-house reference at order >= min_order with both solvers."""
    ref, rows = errors("quick_return", "smooth_cutting", tol("cut_window"), solver, cut_steps())
    assert -ref.energies["work_cutting"][-1] >= full_cut_work(), "the window must contain a whole cut"
    check_min_order(rows, cut_steps(), ("dq", "dqd", "dlam"))


@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_four_bar_converges_to_inhouse_reference_at_order_2(solver):
    """The four-bar, defined by its description only: Exudyn's model generated from the same
    description converges to the in-house reference at order 2 in q and qd (and the cut joint's
    multipliers: at order 2 with index 2, faster than first order with index 3)."""
    h = tol("four_bar_order_steps")
    steps = [h, h / 2, h / 4]
    _, rows = errors("four_bar", "seed", tol("four_bar_horizon"), solver, steps)
    check_min_order(rows, steps, ("dq", "dqd", "dlam"))


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_quick_return_smooth_law_five_cuts(solver):
    """Smooth law over cut_horizon (3 s, five cuts) at cut_steps: order >= min_order in q, qd, lambda."""
    ref, rows = errors("quick_return", "smooth_cutting", tol("cut_horizon"), solver, cut_steps())
    assert -ref.energies["work_cutting"][-1] >= 3 * full_cut_work(), "three whole cuts at least"
    check_min_order(rows, cut_steps(), ("dq", "dqd", "dlam"))
