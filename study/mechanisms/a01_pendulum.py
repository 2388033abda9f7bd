"""IFToMM benchmark A01, the simple pendulum, in Cartesian coordinates: a lumped mass on a massless link.

q = [x, y]: the position of the mass P1 (a body that does not turn, so its inertia never enters). The link is a
distance constraint of length L to the fixed point O, one row |r_P1 - r_O| - L, whose multiplier is the link's
tension. Gravity g along -y. The benchmark starts P1 at rest on the horizontal through O, at x = +L.
"""

from __future__ import annotations

from study.model.joints import GROUND, Description
from study.params import ParameterSet

LABEL = "IFToMM A01 simple pendulum (Cartesian coordinates)"
PARAMETERS = ("m", "L", "g")
COORDINATE_UNIT = "m"


def describe(ps: ParameterSet) -> Description:
    v = ps.values
    d = Description("a01_pendulum", ("x", "y"), {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    p = d.p
    x, y = d.q
    d.ground("O", 0, 0)
    d.body("P1", p.m, p.m * p.L ** 2, {"P1": (0, 0)}, angle=0, position=(x, y))   # inertia unused: P1 never turns
    d.distance("link", (GROUND, "O"), ("P1", "P1"), p.L)
    d.gravity(p.g)
    d.assembly_branch(x + 2 * p.L, "any point of the circle (the branch check is vacuous: x > -2L)")
    return d
