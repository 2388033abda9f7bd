"""Haug's spatial slider-crank (Computer-Aided Kinematics and Dynamics of Mechanical Systems, 1989, sec. 12.2) through
every engine: ``python examples/spatial_slider_crank/spatial_slider_crank.py [out]``.

A crank turns on a revolute joint about the global x axis, a slider runs on a prismatic joint along x, and a coupler
joins them by a spherical joint at the crank and a universal joint at the slider. The masses, inertias and lengths
are Haug's as transcribed in two public implementations (S. Acuna's simEngine3D driver, "Haug's book, section 12.2
(pages 455-458)", and gorzech/CosimaModels.jl); the book itself was not available to check them. Haug joins coupler
and slider by a revolute-cylindrical joint and a distance row; the universal joint here is this example's. Every
body frame is parallel to the global one at t = 0, so the inertias are Haug's turned onto the links' directions.
"""
import sys

import numpy as np

import study
from study.spatial import GROUND, SpatialDescription, SpatialMechanism

u = np.array([0.2, -0.1, -0.2]) / 0.3                 # the coupler's direction at t = 0, crank tip -> slider
d = SpatialDescription("spatial_slider_crank", label="Haug's spatial slider-crank")
d.body("crank", 0.12, (1e-4, 1e-4, 1e-5),              # [kg], [kg m^2]; 0.08 m long along z at t = 0
       points={"pivot": (0, 0, -0.04), "tip": (0, 0, 0.04)}, axes={"pin": (1, 0, 0)})
d.body("coupler", 0.5, 4e-3 * np.eye(3) - 3.6e-3 * np.outer(u, u),   # 0.3 m long; 4e-4 kg m^2 about its length
       points={"crank_end": tuple(-0.15 * u), "slider_end": tuple(0.15 * u)}, axes={"cross": (-1, -2, 0)})
d.body("slider", 2.0, (1e-4, 1e-4, 1e-4), points={"centre": (0, 0, 0)}, axes={"pin": (0, 0, 1)})
d.revolute("crank_pin", ("crank", "pivot", "pin"), (GROUND, (0, 0.1, 0.12), (1, 0, 0)))   # pivot at [m], about x
d.spherical("crank_ball", ("coupler", "crank_end"), ("crank", "tip"))
d.universal("slider_cross", ("coupler", "slider_end", "cross"), ("slider", "centre", "pin"))
d.prismatic("slider_guide", ("slider", "centre"), (GROUND, (0, 0, 0), (1, 0, 0)))         # along x through the origin
d.gravity((0, 0, -9.81))                                                                  # [m/s^2]
slider_crank = SpatialMechanism(d, positions={"crank": (0, 0.1, 0.16), "coupler": (0.1, 0.05, 0.1),   # centres [m]
                                              "slider": (0.2, 0, 0)},
                                angular_velocities={"crank": (-2 * np.pi, 0, 0)})   # [rad/s]; the others follow

if __name__ == "__main__":
    study.validate(slider_crank, study.ValidationSettings(t_end=1.0), sys.argv[1] if len(sys.argv) > 1 else "out")
