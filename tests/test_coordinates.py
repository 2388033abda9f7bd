"""The joint-level description's two coordinate sets, and the joint reactions generated from it.

Relative coordinates (the papers' joint angles with loop closures) and absolute coordinates
(x, y, theta per body, one constraint block per joint) are two independent redundant formulations of
the same mechanism, derived separately from the description. Every variant of every mechanism is
simulated in both, and the absolute run is compared with the relative run mapped through the
kinematics. The reactions are checked against hand-derived Newton-Euler balances.
"""

import math

import numpy as np
import pytest

import study
from study import mechanisms
from study.params import available_mechanisms, available_variants, load_parameters
from study.reactions import absolute_state, joint_reactions
from study.reference_data import tolerance

HORIZON = tolerance("coordinate_sets_horizon", table="cross_validation")
REFERENCE = dict(method="projection", integrator="DOP853", rtol=tolerance("reference_rtol"),
                 atol=tolerance("reference_atol"))


LARGE = {("n_four_bar", "n20"), ("n_four_bar", "n40")}   # 5-20 s each: with the slow tests (make verify)


def _variants():
    return [pytest.param(m, v, marks=pytest.mark.slow) if (m, v) in LARGE else (m, v)
            for m in available_mechanisms() for v in available_variants(m)]


@pytest.mark.parametrize("mechanism,variant", _variants())
def test_absolute_coordinates_agree_with_relative(mechanism, variant):
    """Both formulations of one description give the same motion (q mapped through the kinematics)."""
    ps = load_parameters(mechanism, variant)
    horizon = HORIZON * mechanisms.time_scale(mechanism)
    friction = "regularized" if any(c.mu_kinetic > 0 or c.resistance > 0
                                    for c in mechanisms.equations(ps).contacts) else None
    rel = study.simulate(mechanism, variant=variant, t_end=horizon, output_step=horizon / 10, friction=friction,
                         **REFERENCE)
    x0, xd0, _ = absolute_state(ps, rel.q[0], rel.qd[0], rel.qdd[0])
    eom_abs = mechanisms.equations(ps, "absolute")
    assert eom_abs.n_coordinates == 3 * len(mechanisms.description(ps).bodies)
    absolute = study.simulate(eom_abs, x0, xd0, t_end=horizon, output_step=horizon / 10, friction=friction,
                              **REFERENCE)
    mapped = np.array([absolute_state(ps, q, qd, qdd)[0] for q, qd, qdd in zip(rel.q, rel.qd, rel.qdd)])
    tol = tolerance("coordinate_sets_agreement", table="cross_validation")
    scale = max(1.0, np.abs(mapped).max())
    assert np.abs(absolute.q - mapped).max() <= tol * scale
    for name, force in rel.forces.items():
        if name.startswith(("normal_", "friction_")):
            assert np.abs(absolute.forces[name] - force).max() <= tol * max(1.0, np.abs(force).max())


def test_slider_crank_reactions_against_hand_balance():
    """Slider-crank while sliding: the slider's and the crank's Newton equations written by hand."""
    ps = load_parameters("slider_crank", "sustained_sliding")
    v = ps.values
    run = study.simulate("slider_crank", variant="sustained_sliding", t_end=0.2, output_step=0.1,
                         friction="regularized", **REFERENCE)
    r = joint_reactions(ps, run)
    q1, q2 = run.q[-1]
    w1, w2 = run.qd[-1]
    a1, a2 = run.qdd[-1]
    ph, wph, aph = q1 + q2, w1 + w2, a1 + a2
    # slider acceleration along x: B = A - l2 e(q1+q2)
    ax_b = (-v.l1 * (a1 * math.sin(q1) + w1 ** 2 * math.cos(q1))
            + v.l2 * (aph * math.sin(ph) + wph ** 2 * math.cos(ph)))
    friction = run.forces["friction_guide"][-1]
    normal = run.forces["normal_guide"][-1]
    # the balances hold exactly for the solver's accelerations: round-off of the largest force involved
    atol = tolerance("round_off") * max(abs(f[-1]) for f in r.values())
    # slider: m3 a_B = F_rod->slider + friction + (0, N) + weight; rod->slider = joint B reaction
    assert r["joint_B_x"][-1] + friction == pytest.approx(v.m3 * ax_b, abs=atol)
    assert r["joint_B_y"][-1] + normal - v.m3 * v.g == pytest.approx(0.0, abs=atol)
    assert r["joint_guide_n"][-1] == pytest.approx(normal, abs=atol)
    # crank: balanced (COM at O, no acceleration): ground->crank = -(rod->crank) - weight = A reaction - weight
    assert r["joint_O_x"][-1] == pytest.approx(r["joint_A_x"][-1], abs=atol)
    assert r["joint_O_y"][-1] == pytest.approx(r["joint_A_y"][-1] + v.m1 * v.g, abs=atol)


def test_four_bar_cut_joint_reaction_is_the_multiplier():
    """In relative coordinates the cut joint's rows are constraints: their multipliers are its reaction."""
    ps = load_parameters("four_bar")
    run = study.simulate("four_bar", t_end=0.5, output_step=0.1, **REFERENCE)
    r = joint_reactions(ps, run)
    rows = list(run.meta["constraint_names"])
    tol = tolerance("coordinate_sets_agreement", table="cross_validation")
    scale = np.abs(run.lam).max()
    assert np.abs(r["joint_B_x"] - run.lam[:, rows.index("B_x")]).max() <= tol * scale
    assert np.abs(r["joint_B_y"] - run.lam[:, rows.index("B_y")]).max() <= tol * scale


def test_description_problems_are_reported_together():
    from study.model.joints import GROUND, Description, DescriptionError

    d = Description("bad", ("q1",), {"L": 1.0})
    d.body("bar", 1.0, 0.1, {"O": (0, 0)}, angle=d.q[0])
    d.revolute("O", (GROUND, "nowhere"), ("bar", "X"))
    d.prismatic("slide", ("bar", "O"), (GROUND, "nowhere"), axis=(1, 0), normal=(1, 0))
    with pytest.raises(DescriptionError) as err:
        d.validate()
    msg = str(err.value)
    assert "unknown ground point 'nowhere'" in msg and "has no point 'X'" in msg and "orthogonal unit" in msg
