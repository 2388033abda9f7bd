"""Mechanism A: slider-crank with Coulomb friction in the slider guide (paper 000, sec. 3).

Relative coordinates q = [q1, q2]: crank angle, rod angle relative to the crank (rod absolute
angle q1 + q2). The crank is balanced (centre of mass at its pivot O). A = l1 e(q1);
C2 = A - c2 e(q1+q2); B = A - l2 e(q1+q2). The slider B moves on the guide y = 0, whose normal
gap y_B is 000's constraint (eq. 22), so its multiplier is the normal force; the resistance F and
the Coulomb friction act through that contact.

:func:`add_bodies` and :func:`add_guide_and_loads` hold the mechanism's bodies, guide and loads for any choice of
coordinates (:mod:`study.mechanisms.slider_crank_pins` uses them with a coordinate set of its own).
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from study.model.joints import GROUND, Description, Friction
from study.params import ParameterSet

LABEL = "slider-crank (paper 000)"
#: The parameter file's entries (numbers become symbols of the description; alpha_law selects its form;
#: resistance_reading is read by the friction solver).
PARAMETERS = ("J1", "m1", "J2", "m2", "m3", "J3", "l1", "l2", "c2", "g", "mu", "F", "alpha", "M", "alpha_law", "resistance_reading")
#: The pins' ends: (first body, point), (second body, point).
PIN_ENDS = {"O": ((GROUND, "O"), ("crank", "O")), "A": (("crank", "A"), ("rod", "A")),
            "B": (("rod", "B"), ("slider", "B"))}


def add_bodies(d: Description, crank_angle: Any, rod_angle: Any, positions: dict | None = None) -> None:
    """The ground points O and guide and the bodies crank, rod and slider (angle 0), their angles given in the
    description's coordinates; ``positions`` (body -> (x, y)) makes those bodies free bodies placed by their own
    coordinates."""
    p, where = d.p, positions or {}
    d.ground("O", 0, 0)
    d.ground("guide", 0, 0)
    d.body("crank", p.m1, p.J1, {"O": (0, 0), "A": (p.l1, 0)}, angle=crank_angle, position=where.get("crank"))
    d.body("rod", p.m2, p.J2, {"A": (p.c2, 0), "B": (p.c2 - p.l2, 0)}, angle=rod_angle, position=where.get("rod"))
    d.body("slider", p.m3, p.J3, {"B": (0, 0)}, angle=0, position=where.get("slider"))


def add_guide_and_loads(d: Description, alpha_law: str) -> None:
    """The guide with its Coulomb friction and resistance, gravity, the drive torque and 000's '-alpha q1' term
    (``alpha_law``: 'spring' or 'damping')."""
    p = d.p
    d.prismatic("guide", slider=("slider", "B"), guide=(GROUND, "guide"), axis=(1, 0), normal=(0, 1),
                friction=Friction(p.mu, p.mu, p.F))
    d.gravity(p.g)
    d.torque("drive", "crank", p.M)
    if alpha_law == "spring":      # 000's '-alpha q1' read as a torsion spring on the crank
        d.torsion_spring("alpha_spring", "crank", p.alpha)
    else:                          # ... or as a viscous damper
        d.torque("alpha_damper", "crank", -p.alpha * d.rate("crank"))


def describe(ps: ParameterSet) -> Description:
    """The joint-level description of the slider-crank for one parameter set."""
    v = ps.values
    d = Description("slider_crank", ("q1", "q2"), {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    q1, q2 = d.q
    add_bodies(d, q1, q1 + q2)
    for name, (a, b) in PIN_ENDS.items():
        d.revolute(name, a, b)
    add_guide_and_loads(d, v.alpha_law)
    # 000 eqs. (13), (32): B lies beyond A from O, cos(q1+q2) > 0
    d.assembly_branch(sp.cos(q1 + q2), "cos(q1+q2) > 0")
    return d
