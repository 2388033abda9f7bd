"""Frictionless runs: Exudyn's joint forces over the whole trajectory against the in-house reactions.

* Prismatic joints: Exudyn's ForceLocal, mapped by the Exudyn model to the in-house multiplier
  convention (``lam``), against the in-house multipliers.
* Revolute joints: Exudyn's global joint forces (on the distal body) against the in-house
  reactions recovered from the reference's q, qd, qdd and lambda by each body's Newton equation
  (:func:`study.studies.cross_validation.inhouse_joint_forces`).

Compared on common samples every 0.01 s at h, h/2, h/4; tolerances in reference/cross_validation.toml.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from cross_validation.frictionless_runs import FINE_STEP, frictionless_run
from study.compare import observed_orders
from study.reference_data import tolerance
from study.simulate import simulate
from study.studies.cross_validation import inhouse_joint_forces, reaction_deviations

OUTPUT_STEP = 0.01
#: Exudyn's sampling where it is not OUTPUT_STEP: the quick-return's runs are those of test_against_inhouse.py
#: (frictionless_runs.py); compared on the common samples, every OUTPUT_STEP, they give the same numbers.
EXUDYN_SAMPLING = {"quick_return": FINE_STEP}


def tol(key: str) -> float:
    return tolerance(key, table="cross_validation")


@lru_cache(maxsize=None)
def reference(mechanism, variant, t_end):
    """The in-house reference without friction, as the Exudyn runs it is compared with (friction='none')."""
    return simulate(mechanism, variant=variant, t_end=t_end, method="projection", integrator="DOP853",
                    rtol=tolerance("reference_rtol"), atol=tolerance("reference_atol"), output_step=OUTPUT_STEP,
                    friction="none")


def deviations(mechanism, variant, t_end, solver, steps):
    ref = reference(mechanism, variant, t_end)
    joints = inhouse_joint_forces(ref)
    sampling = EXUDYN_SAMPLING.get(mechanism, OUTPUT_STEP)
    return [reaction_deviations(frictionless_run(mechanism, variant, t_end, h, solver, sampling), ref, joints)
            for h in steps]


CASES = [
    # mechanism, variant, horizon [s], largest step
    ("quick_return", "smooth_cutting", tol("cut_window"), tol("cut_steps")),
    ("slider_crank", "sustained_sliding", tol("friction_horizon_sustained_sliding"),
     tol("slider_crank_friction_steps")),
]


@pytest.mark.parametrize("mechanism,variant,t_end,h", CASES)
def test_index2_reactions_converge_at_order_two(mechanism, variant, t_end, h):
    """Every prismatic multiplier and every revolute-joint force component: order >= min_order with
    index 2 (the quick-return through its first cut)."""
    steps = [h, h / 2, h / 4]
    rows = deviations(mechanism, variant, t_end, "index2", steps)
    expected = {"slider_crank": {"lam1", "joint_guide_n"} | {f"joint_{j}_{c}" for j in "OAB" for c in "xy"},
                "quick_return": {"lam1", "lam2", "joint_block_on_rocker_n", "joint_ram_guide_n"}
                | {f"joint_{j}_{c}" for j in "OPAED" for c in "xy"}}[mechanism]
    assert set(rows[0]) == expected
    low, floor = tol("min_order"), tol("order_error_floor")
    for quantity in sorted(expected):
        e = [row[quantity][0] for row in rows]
        assert min(e) > floor, (quantity, e)
        p = observed_orders(steps, e)
        assert np.all(p >= low), f"{quantity}: errors {e}, orders {p}"


def test_index3_reactions_quick_return_order_two_through_the_cut():
    """Index-3 reactions of the quick-return through the first cut, at steps that resolve the smooth
    law (cut_steps): every prismatic multiplier and revolute-joint force at order >= min_order."""
    mechanism, variant, t_end, h = CASES[0]
    steps = [h, h / 2, h / 4]
    rows = deviations(mechanism, variant, t_end, "index3", steps)
    low, floor = tol("min_order"), tol("order_error_floor")
    for quantity in sorted(rows[0]):
        e = [row[quantity][0] for row in rows]
        assert min(e) > floor, (quantity, e)
        p = observed_orders(steps, e)
        assert np.all(p >= low), f"{quantity}: errors {e}, orders {p}"


def test_index3_reactions_slider_crank_round_off_floor():
    """Slider-crank index 3: the reaction deviations sit on a round-off floor (no order); bounded."""
    mechanism, variant, t_end, h = CASES[1]
    rows = deviations(mechanism, variant, t_end, "index3", [h, h / 2, h / 4])
    scale = max(s for row in rows for _, s in row.values())
    bound = tol("index3_reaction_floor_relative") * scale
    worst = max(d for row in rows for d, _ in row.values())
    assert worst <= bound, f"largest deviation {worst:.3e} N > {bound:.3e} N: {rows}"
