"""The description of Coulomb friction in spatial joints: every wrong value is refused by name."""

import pytest

from study.spatial import GROUND, SpatialDescription, SpatialDescriptionError


def _described() -> SpatialDescription:
    d = SpatialDescription("rig")
    d.body("wheel", 1.0, (0.1, 0.1, 0.15), points={"c": (0, 0, 0)}, axes={"z": (0, 0, 1)})
    d.body("block", 1.0, (0.1, 0.1, 0.1), points={"c": (0, 0, 0)})
    d.body("ball", 1.0, (0.1, 0.1, 0.1), points={"c": (0, 0, 0)})
    d.revolute("pin", ("wheel", "c", "z"), (GROUND, (0, 0, 0), (0, 0, 1)))
    d.prismatic("guide", ("block", "c"), (GROUND, (1, 0, 0), (1, 0, 0)))
    d.spherical("socket", ("ball", "c"), (GROUND, (0, 2, 0)))
    return d


def test_friction_is_kept_per_joint_and_changes_the_fingerprint():
    d = _described()
    before = d.fingerprint()
    d.friction("pin", 0.3, 0.2, radius=0.01)
    d.friction("guide", 0.4, 0.3, resistance=1.5)
    assert d.frictions["pin"].radius == 0.01 and d.frictions["guide"].radius is None
    assert d.frictions["guide"].resistance == 1.5
    assert d.fingerprint() != before


@pytest.mark.parametrize("args, kwargs, culprit", [
    (("nowhere", 0.3, 0.2), {"radius": 0.01}, "no such joint"),
    (("socket", 0.3, 0.2), {}, "Spherical joint has no friction"),
    (("pin", 0.3, 0.2), {}, "needs its pin radius"),
    (("guide", 0.3, 0.2), {"radius": 0.01}, "has no radius"),
    (("pin", 0.2, 0.3), {"radius": 0.01}, "mu_kinetic"),
    (("pin", 0.3, -0.1), {"radius": 0.01}, "mu_kinetic"),
    (("pin", 0.3, 0.2), {"radius": 0.0}, "must be > 0"),
    (("guide", 0.3, 0.2), {"resistance": -1.0}, "resistance"),
    (("guide", "x", 0.2), {}, "mu_static of the friction in joint 'guide'"),
])
def test_bad_friction_is_refused_by_name(args, kwargs, culprit):
    with pytest.raises(SpatialDescriptionError, match=culprit):
        _described().friction(*args, **kwargs)


def test_friction_given_twice_is_refused():
    d = _described()
    d.friction("guide", 0.3, 0.2)
    with pytest.raises(SpatialDescriptionError, match="given twice"):
        d.friction("guide", 0.3, 0.2)
