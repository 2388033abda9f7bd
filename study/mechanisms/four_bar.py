"""A four-bar linkage under gravity (crank, coupler, rocker): the study's own third mechanism.

Relative coordinates q = [q1, q2, q3]: the absolute angles of crank, coupler and rocker. Crank
pivot O at the origin, rocker pivot C at (d, 0); A = a e(q1), B = A + b e(q2) = C + c e(q3). The
links are slender bars with the centre of mass at mid-length. The coupler-rocker joint B is the
cut joint: its two rows are the loop closure.
"""

from __future__ import annotations

import sympy as sp

from study.model.joints import GROUND, Description
from study.params import ParameterSet

LABEL = "four-bar under gravity"
PARAMETERS = ("a", "b", "c", "d", "m1", "m2", "m3", "J1", "J2", "J3", "g")


def describe(ps: ParameterSet) -> Description:
    """The joint-level description of the four-bar for one parameter set."""
    v = ps.values
    d = Description("four_bar", ("q1", "q2", "q3"), {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    p = d.p
    q1, q2, q3 = d.q
    d.ground("O", 0, 0)
    d.ground("C", p.d, 0)
    d.body("crank", p.m1, p.J1, {"O": (-p.a / 2, 0), "A": (p.a / 2, 0)}, angle=q1)
    d.body("coupler", p.m2, p.J2, {"A": (-p.b / 2, 0), "B": (p.b / 2, 0)}, angle=q2)
    d.body("rocker", p.m3, p.J3, {"C": (-p.c / 2, 0), "B": (p.c / 2, 0)}, angle=q3)
    d.revolute("O", (GROUND, "O"), ("crank", "O"))
    d.revolute("A", ("crank", "A"), ("coupler", "A"))
    d.revolute("C", (GROUND, "C"), ("rocker", "C"))
    d.revolute("B", ("coupler", "B"), ("rocker", "B"))
    d.gravity(p.g)
    d.assembly_branch(sp.sin(q3), "sin(q3) > 0")
    return d
