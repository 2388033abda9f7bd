"""Prismatic joints with a travel place bodies in relative coordinates (tree joints), like revolute joints.

Independent references: Lagrange's equations of a cart carrying a pendulum and of a slider on a rotating arm,
derived by hand below (not from the description); and, for the cart, the same description in absolute
coordinates, where the prismatic joint is a block of constraint rows.
"""

from __future__ import annotations

import numpy as np
import pytest

from study.model.compile import compile_description
from study.model.coordinates import lower
from study.model.joints import GROUND, Description, DescriptionError, Friction
from study.reference_data import tolerance
from study.simulate import simulate

CART = {"mc": 2.0, "mp": 0.7, "a": 0.4, "Jp": 0.03, "g": 9.81}
ARM = {"ma": 1.5, "Ja": 0.2, "ms": 0.8, "Js": 0.01, "g": 9.81}
STATES = [(np.array([0.3, 0.7]), np.array([0.5, -1.2])), (np.array([-1.1, 2.9]), np.array([-0.4, 3.0]))]


def cart_pendulum(**change) -> Description:
    """A cart on a horizontal rail (coordinate s) carrying a pendulum (angle th from the downward vertical) whose
    centre of mass lies a below its pivot."""
    d = Description("cart_pendulum", ["s", "th"], CART)
    p = d.p
    s, th = d.q
    d.ground("O", 0, 0)
    d.body("cart", p.mc, 1.0, {"rail": (0, 0), "hinge": (0, 0)}, angle=change.get("cart_angle", 0))
    d.body("pendulum", p.mp, p.Jp, {"pivot": (0, p.a)}, angle=th)
    d.prismatic("rail", slider=("cart", "rail"), guide=(GROUND, "O"), axis=(1, 0), normal=(0, 1), travel=s,
                friction=change.get("friction"))
    d.revolute("hinge", ("cart", "hinge"), ("pendulum", "pivot"))
    d.gravity(p.g)
    return d


def cart_hand(q, qd):
    """M and Q of the cart-pendulum from T = mc s'^2/2 + mp |v_c|^2/2 + Jp th'^2/2, V = -mp g a cos th."""
    v = CART
    c, s = np.cos(q[1]), np.sin(q[1])
    M = np.array([[v["mc"] + v["mp"], v["mp"] * v["a"] * c], [v["mp"] * v["a"] * c, v["mp"] * v["a"] ** 2 + v["Jp"]]])
    Q = np.array([v["mp"] * v["a"] * qd[1] ** 2 * s, -v["mp"] * v["g"] * v["a"] * s])
    return M, Q


def arm_slider(slider_first: bool) -> Description:
    """A body sliding along an arm that turns about the origin (coordinates ph, r), both centres of mass on the arm's
    axis: the slider's at distance r. ``slider_first``: the sleeve turns about the origin and the rod slides
    through it (the rod's point is placed from the sleeve, at -r), else the arm turns and the slider rides on it."""
    d = Description("arm_slider", ["ph", "r"], ARM)
    p = d.p
    ph, r = d.q
    d.ground("O", 0, 0)
    d.body("turning", p.ma, p.Ja, {"pin": (0, 0), "line": (0, 0)}, angle=ph)
    d.body("sliding", p.ms, p.Js, {"line": (0, 0)}, angle=ph)
    d.revolute("pin", (GROUND, "O"), ("turning", "pin"))
    if slider_first:   # the turning body is the slider: the sliding one is placed as the guide
        d.prismatic("slide", slider=("turning", "line"), guide=("sliding", "line"), axis=(1, 0), normal=(0, 1),
                    travel=-r)
    else:
        d.prismatic("slide", slider=("sliding", "line"), guide=("turning", "line"), axis=(1, 0), normal=(0, 1),
                    travel=r)
    d.gravity(p.g)
    return d


def arm_hand(q, qd):
    """T = (Ja + Js + ms r^2) ph'^2/2 + ms r'^2/2, V = ms g r sin ph."""
    v = ARM
    ph, r = q
    M = np.diag([v["Ja"] + v["Js"] + v["ms"] * r ** 2, v["ms"]])
    Q = np.array([-2 * v["ms"] * r * qd[1] * qd[0] - v["ms"] * v["g"] * r * np.cos(ph),
                  v["ms"] * r * qd[0] ** 2 - v["ms"] * v["g"] * np.sin(ph)])
    return M, Q


@pytest.mark.parametrize("build, hand", [(cart_pendulum, cart_hand), (lambda: arm_slider(False), arm_hand),
                                         (lambda: arm_slider(True), arm_hand)],
                         ids=["cart_pendulum", "slider_on_arm", "rod_through_sleeve"])
def test_relative_equations_equal_the_hand_derivation(build, hand):
    eom = compile_description(lower(build(), "relative"))
    assert (eom.n_coordinates, eom.n_constraints) == (2, 0)   # placed by the travel: no loop, no rows
    bound = tolerance("round_off")
    for q, qd in STATES:
        M, Q = hand(q, qd)
        assert np.abs(eom.mass(q) - M).max() <= bound * np.abs(M).max()
        assert np.abs(eom.forces(0.0, q, qd) - Q).max() <= bound * max(np.abs(Q).max(), 1.0)


def test_cart_moves_alike_in_relative_and_absolute_coordinates():
    """1 s from rest at th = 1 rad: the pendulum's centre of mass in both coordinate sets, each run at rtol 1e-10,
    agrees within twice the adaptive runs' global error bound (adaptive_global_error_factor * rtol * scale)."""
    d = cart_pendulum()
    rel, ab = compile_description(lower(d, "relative")), compile_description(lower(d, "absolute"))
    a, th = CART["a"], 1.0
    q_abs = [0.0, 0.0, 0.0, a * np.sin(th), -a * np.cos(th), th]   # cart x, y, angle; pendulum x, y, angle
    kw = dict(t_end=1.0, integrator="DOP853", rtol=1e-10, atol=1e-12, output_step=0.01)
    r_rel = simulate(rel, [0.0, th], [0.0, 0.0], **kw)
    r_abs = simulate(ab, q_abs, np.zeros(6), method="projection", **kw)
    x_rel = r_rel.q[:, 0] + a * np.sin(r_rel.q[:, 1])
    bound = 2 * tolerance("adaptive_global_error_factor") * 1e-10 * 1.0
    assert np.abs(x_rel - r_abs.q[:, 3]).max() <= bound


def test_a_travel_with_mismatched_angles_is_refused_by_name():
    with pytest.raises(DescriptionError, match=r"joint 'rail' has a travel.*slider's angle is not the guide's"):
        lower(cart_pendulum(cart_angle=0.1), "relative")


def test_a_travel_on_a_joint_with_friction_is_refused():
    with pytest.raises(DescriptionError, match=r"joint 'rail': a joint with friction cannot have a travel"):
        lower(cart_pendulum(friction=Friction(0.3, 0.2)), "relative")
