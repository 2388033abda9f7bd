"""A carriage on an inclined guide carrying a wheel, with Coulomb friction in both joints: the study's spatial
mechanism with joint friction (``friction_carriage``), both kinds at once (:mod:`study.spatial.friction`).

The carriage (4 kg) slides on a prismatic joint along the guide u = (2, 1, 1)/sqrt(6) through the origin (inclined
24.1 deg, tan = 0.447), its shoe on the guide, its orientation locked; mu_s = 0.5, mu_k = 0.3 (mu_s above tan: it
sticks where it stops). A wheel (1.5 kg, radius 0.15 m, a disc: axial moment m R^2 / 2, transverse m R^2 / 4) turns on
a revolute joint about the horizontal axle h = (1, -2, 0)/sqrt(5) (across the guide) at 0.15 m above the carriage's
centre; the pin (radius 0.02 m) has mu_s = 0.2, mu_k = 0.15. Gravity -9.81 m/s^2 along z. The start: both bodies
moving up the guide at 2 m/s, the wheel spinning at 3 rad/s about its axle. The carriage slows at
g.u - mu_k |g_perp| = -6.7 m/s^2 (the guide's normal force is the weight across it, 5.5 kg |g_perp| = 49.3 N: the
axle's direction is fixed, so the spin adds no gyroscopic moment) and sticks at 0.30 s; the pin's transverse
reaction (the wheel's weight across the axle and its inertia force while the carriage decelerates, 14 to 14.7 N)
brakes the wheel at about mu_k r |R_t| / I_axle = 2.6 rad/s^2 until it stops at about 1.15 s. The numbers are the
study's own, chosen so that both joints slide, then stick, within 2 s.
"""

from __future__ import annotations

import numpy as np

from study.spatial.description import SpatialDescription
from study.spatial.elements import GROUND
from study.spatial.mechanism import SpatialMechanism

GUIDE = np.array([2.0, 1.0, 1.0]) / np.sqrt(6.0)
AXLE = np.array([1.0, -2.0, 0.0]) / np.sqrt(5.0)
WHEEL_MASS, WHEEL_RADIUS = 1.5, 0.15


def friction_carriage() -> SpatialMechanism:
    """The mechanism of the module docstring at t = 0."""
    axial, transverse = WHEEL_MASS * WHEEL_RADIUS ** 2 / 2, WHEEL_MASS * WHEEL_RADIUS ** 2 / 4
    d = SpatialDescription("friction_carriage", label="carriage and wheel with joint friction")
    d.body("carriage", 4.0, (0.05, 0.08, 0.1), points={"shoe": (0, 0, -0.05), "axle_end": (0, 0, 0.15)},
           axes={"axle": tuple(AXLE)})
    d.body("wheel", WHEEL_MASS, transverse * np.eye(3) + (axial - transverse) * np.outer(AXLE, AXLE),
           points={"hub": (0, 0, 0)}, axes={"axle": tuple(AXLE)})
    d.prismatic("guide", ("carriage", "shoe"), (GROUND, (0, 0, 0), tuple(GUIDE)))
    d.revolute("axle", ("wheel", "hub", "axle"), ("carriage", "axle_end", "axle"))
    d.friction("guide", 0.5, 0.3)
    d.friction("axle", 0.2, 0.15, radius=0.02)
    d.gravity((0, 0, -9.81))
    return SpatialMechanism(d, positions={"carriage": (0, 0, 0.05), "wheel": (0, 0, 0.2)},
                            velocities={"carriage": tuple(2.0 * GUIDE), "wheel": tuple(2.0 * GUIDE)},
                            angular_velocities={"wheel": tuple(3.0 * AXLE)})
