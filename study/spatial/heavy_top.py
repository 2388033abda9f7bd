"""The heavy top of Terze, Müller and Zlatar (2016), set up as in Exudyn's TestModels/heavyTop.py, as a spatial
description (reference/spatial/heavy_top.toml): a body whose centre of mass starts at c, on a spherical joint at its
body point -c to the global origin, spinning at the published angular velocity."""

from __future__ import annotations

import numpy as np

from study.reference_data import tolerance, values
from study.spatial.description import SpatialDescription
from study.spatial.elements import GROUND
from study.spatial.mechanism import SpatialMechanism

TABLE = "spatial/heavy_top"


def heavy_top() -> SpatialDescription:
    """The top as a body whose centre of mass starts at c, on a spherical joint at its body point -c to the origin."""
    c = np.array(values("centre_of_mass", TABLE))
    d = SpatialDescription("heavy_top", label="heavy top (Terze, Müller, Zlatar 2016)")
    d.body("top", tolerance("mass", TABLE), values("inertia", TABLE), points={"pivot": tuple(-c)})
    d.spherical("fixed_point", ("top", "pivot"), (GROUND, (0.0, 0.0, 0.0)))
    d.gravity(values("gravity", TABLE))
    return d


def heavy_top_mechanism() -> SpatialMechanism:
    """The top with its start: centre of mass at c, no rotation, the published angular velocity (global frame)."""
    return SpatialMechanism(heavy_top(), positions={"top": values("centre_of_mass", TABLE)},
                            angular_velocities={"top": values("angular_velocity", TABLE)})
