"""Exudyn's slider-crank test model (``sliderCrankFloatingTest``), fixed-frame case: a peer's test, described here.

Crank O-A (length L1) pinned at O, rod A-B (L2), slider at B on a guide along x through O; slender links with the
centre of mass at mid-length (J = m L^2 / 12), the slider a rigid body of inertia 0.001 m3. A constant torque M
drives the crank from rest in the straight position (the model's user function switches it off after 2 s, beyond
the 0.3 s horizon of its test). No gravity. Relative coordinates q = [a1, a2]: the absolute angles of crank and
rod. The floating-frame case (``exudyn_slider_crank_floating``) mounts the same mechanism on a frame held by
coordinate spring-dampers (x, y and the angle of its centre of mass); it is described by :func:`describe` too.
"""

from __future__ import annotations

from study.model.joints import GROUND, Description
from study.params import ParameterSet

LABEL = "Exudyn's slider-crank test model (fixed frame)"
PARAMETERS = ("L1", "L2", "m1", "m2", "m3", "M")
FRAME = ("mf", "Jf", "k", "d")
TIME_SCALE = 0.3


def describe(ps: ParameterSet) -> Description:
    """The description of either case: on ground, or, when the parameter set has the frame's parameters, on a
    frame that floats on coordinate spring-dampers (coordinates [a1, a2, x, y, phi])."""
    v = ps.values
    floating = hasattr(v, "mf")
    names = PARAMETERS + (FRAME if floating else ())
    coordinates = ("a1", "a2", "x", "y", "phi") if floating else ("a1", "a2")
    d = Description(ps.mechanism, coordinates, {k: getattr(v, k) for k in names},
                    "Exudyn's slider-crank test model (" + ("floating frame)" if floating else "fixed frame)"))
    p = d.p
    a1, a2 = d.q[0], d.q[1]
    if floating:
        x, y, phi = d.q[2], d.q[3], d.q[4]
        d.body("frame", p.mf, p.Jf, {"O": (0, 0), "guide": (p.L1 + p.L2, 0)}, angle=phi, position=(x, y))
        frame, slider_angle = "frame", phi
        (fx, fy), (vx, vy) = d.position("frame", "O"), d.velocity("frame", "O")
        d.force("mount", "frame", "O", -p.k * fx - p.d * vx, -p.k * fy - p.d * vy)
        d.torque("mount_turn", "frame", -p.k * d.angle("frame") - p.d * d.rate("frame"))
    else:
        d.ground("O", 0, 0)
        d.ground("guide", p.L1 + p.L2, 0)
        frame, slider_angle = GROUND, 0
    d.body("crank", p.m1, p.m1 * p.L1 ** 2 / 12, {"O": (-p.L1 / 2, 0), "A": (p.L1 / 2, 0)}, angle=a1)
    d.body("rod", p.m2, p.m2 * p.L2 ** 2 / 12, {"A": (-p.L2 / 2, 0), "B": (p.L2 / 2, 0)}, angle=a2)
    d.body("slider", p.m3, p.m3 / 1000, {"B": (0, 0)}, angle=slider_angle)
    d.revolute("O", (frame, "O"), ("crank", "O"))
    d.revolute("A", ("crank", "A"), ("rod", "A"))
    d.revolute("B", ("rod", "B"), ("slider", "B"))
    d.prismatic("guide", slider=("slider", "B"), guide=(frame, "guide"), axis=(1, 0), normal=(0, 1))
    d.torque("drive", "crank", p.M)
    return d
