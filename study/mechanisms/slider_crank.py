"""Mechanism A: slider-crank with Coulomb friction in the slider guide (paper 000, sec. 3).

Relative coordinates q = [q1, q2]: crank angle, rod angle relative to the crank (rod absolute
angle q1 + q2). The crank is balanced (centre of mass at its pivot O). A = l1 e(q1);
C2 = A - c2 e(q1+q2); B = A - l2 e(q1+q2). The slider B moves on the guide y = 0, whose normal
gap y_B is 000's constraint (eq. 22), so its multiplier is the normal force; the resistance F and
the Coulomb friction act through that contact.
"""

from __future__ import annotations

import sympy as sp

from study.model.joints import GROUND, Description, Friction
from study.params import ParameterSet

LABEL = "slider-crank (paper 000)"
#: The parameter file's entries (numbers become symbols of the description; alpha_law selects its form;
#: resistance_reading is read by the friction solver).
PARAMETERS = ("J1", "m1", "J2", "m2", "m3", "J3", "l1", "l2", "c2", "g", "mu", "F", "alpha", "M", "alpha_law", "resistance_reading")


def describe(ps: ParameterSet) -> Description:
    """The joint-level description of the slider-crank for one parameter set."""
    v = ps.values
    d = Description("slider_crank", ("q1", "q2"), {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    p = d.p
    q1, q2 = d.q
    d.ground("O", 0, 0)
    d.ground("guide", 0, 0)
    d.body("crank", p.m1, p.J1, {"O": (0, 0), "A": (p.l1, 0)}, angle=q1)
    d.body("rod", p.m2, p.J2, {"A": (p.c2, 0), "B": (p.c2 - p.l2, 0)}, angle=q1 + q2)
    d.body("slider", p.m3, p.J3, {"B": (0, 0)}, angle=0)
    d.revolute("O", (GROUND, "O"), ("crank", "O"))
    d.revolute("A", ("crank", "A"), ("rod", "A"))
    d.revolute("B", ("rod", "B"), ("slider", "B"))
    d.prismatic("guide", slider=("slider", "B"), guide=(GROUND, "guide"), axis=(1, 0), normal=(0, 1),
                friction=Friction(p.mu, p.mu, p.F))
    d.gravity(p.g)
    d.torque("drive", "crank", p.M)
    if v.alpha_law == "spring":      # 000's '-alpha q1' read as a torsion spring on the crank
        d.torsion_spring("alpha_spring", "crank", p.alpha)
    else:                            # ... or as a viscous damper
        d.torque("alpha_damper", "crank", -p.alpha * d.rate("crank"))
    # 000 eqs. (13), (32): B lies beyond A from O, cos(q1+q2) > 0
    d.assembly_branch(sp.cos(q1 + q2), "cos(q1+q2) > 0")
    return d
