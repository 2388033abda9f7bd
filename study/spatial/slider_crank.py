"""Haug's spatial slider-crank (Computer-Aided Kinematics and Dynamics of Mechanical Systems, 1989, sec. 12.2), the
study's copy of the user's example examples/spatial_slider_crank/ (the example stays a user's script, which no file of
study/ names; this one is the spatial study's mechanism ``spatial_slider_crank``, the same description and start).

A crank turns on a revolute joint about the global x axis, a slider runs on a prismatic joint along x, and a coupler
joins them by a spherical joint at the crank and a universal joint at the slider. Masses, inertias and lengths as in
the example's docstring (Haug's, as transcribed by S. Acuna's simEngine3D driver and gorzech/CosimaModels.jl).
"""

from __future__ import annotations

import numpy as np

from study.spatial.description import SpatialDescription
from study.spatial.elements import GROUND
from study.spatial.mechanism import SpatialMechanism


def spatial_slider_crank() -> SpatialMechanism:
    """The mechanism at t = 0: crank along z, turning at -2 pi rad/s about x; the others follow the joints."""
    u = np.array([0.2, -0.1, -0.2]) / 0.3   # the coupler's direction at t = 0, crank tip -> slider
    d = SpatialDescription("spatial_slider_crank", label="Haug's spatial slider-crank")
    d.body("crank", 0.12, (1e-4, 1e-4, 1e-5), points={"pivot": (0, 0, -0.04), "tip": (0, 0, 0.04)},
           axes={"pin": (1, 0, 0)})
    d.body("coupler", 0.5, 4e-3 * np.eye(3) - 3.6e-3 * np.outer(u, u),
           points={"crank_end": tuple(-0.15 * u), "slider_end": tuple(0.15 * u)}, axes={"cross": (-1, -2, 0)})
    d.body("slider", 2.0, (1e-4, 1e-4, 1e-4), points={"centre": (0, 0, 0)}, axes={"pin": (0, 0, 1)})
    d.revolute("crank_pin", ("crank", "pivot", "pin"), (GROUND, (0, 0.1, 0.12), (1, 0, 0)))
    d.spherical("crank_ball", ("coupler", "crank_end"), ("crank", "tip"))
    d.universal("slider_cross", ("coupler", "slider_end", "cross"), ("slider", "centre", "pin"))
    d.prismatic("slider_guide", ("slider", "centre"), (GROUND, (0, 0, 0), (1, 0, 0)))
    d.gravity((0, 0, -9.81))
    return SpatialMechanism(d, positions={"crank": (0, 0.1, 0.16), "coupler": (0.1, 0.05, 0.1), "slider": (0.2, 0, 0)},
                            angular_velocities={"crank": (-2 * np.pi, 0, 0)})
