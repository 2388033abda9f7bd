"""The prismatic, cylindrical, universal and distance joints of study.spatial against closed forms: a block sliding on
an inclined guide under gravity, a sleeve spinning and falling along an inclined shaft, and a Cardan shaft whose
output turns at cos(beta) / (1 - sin(beta)^2 cos(theta_1)^2) times the input's rate, its far end held by two
distance links. Each run on the reference path (DOP853, rtol 1e-10), bounded by the adaptive_global_error_factor
rule of reference/tolerances.toml."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from study.reference_data import tolerance
from study.simulate import simulate
from study.spatial import GROUND, SpatialDescription, SpatialDescriptionError, initial_state, spatial_equations
from tests.test_spatial_heavy_top import quaternion_matrix

RTOL = 1e-10
G = np.array([0.0, 0.0, -9.81])
GUIDE = np.array([2.0, 0.0, 1.0]) / np.sqrt(5.0)             # the block's guide and the sleeve's shaft, global
SHAFT = np.array([0.0, 1.0, 2.0]) / np.sqrt(5.0)
BLOCK_TURN = Rotation.from_euler("xyz", [0.2, 0.4, -0.3]).as_matrix()   # the block's locked orientation
BETA = 0.5                                                   # the Cardan shaft's bend [rad]
OMEGA_1 = 5.0                                                # the input shaft's initial rate [rad/s]


def bound(scale: float) -> float:
    return tolerance("adaptive_global_error_factor") * RTOL * scale


def wxyz(matrix: np.ndarray) -> tuple:
    x, y, z, w = Rotation.from_matrix(matrix).as_quat()
    return w, x, y, z


def run(d, eom, q0, qd0, t_end=1.0):
    return simulate(eom, q0, qd0, t_end=t_end, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=0.05)


def block() -> SpatialDescription:
    """A block on a prismatic joint to ground along GUIDE, its shoe 0.2 off its centre of mass, turned by BLOCK_TURN."""
    d = SpatialDescription("block")
    d.body("block", 3.0, (0.1, 0.2, 0.25), points={"shoe": (0.0, 0.1, -0.2), "rail_end": (0.1, 0.0, 0.3)},
           axes={"rail": (0.0, 0.6, 0.8)})   # the rail carries the sleeve of tests/test_spatial_exudyn.py
    d.prismatic("slide", ("block", "shoe"), (GROUND, (0.0, 0.0, 0.0), tuple(GUIDE)), BLOCK_TURN)
    d.gravity(G)
    return d


def block_start(s0=0.3, v0=0.7):
    d = block()
    eom = spatial_equations(d)
    centre = s0 * GUIDE - BLOCK_TURN @ np.array([0.0, 0.1, -0.2])
    q0, qd0 = initial_state(d, eom, {"block": centre}, orientations={"block": wxyz(BLOCK_TURN)},
                            velocities={"block": v0 * GUIDE})
    return d, eom, q0, qd0


def test_a_block_slides_down_its_prismatic_guide_as_under_gravity_alone():
    """s(t) = s0 + v0 t + (g . h) t^2 / 2 along the guide h, the orientation held, and the guide's reaction on the
    centre of mass J_r^T lam = m (g - (g . h) h), the weight's part across the guide."""
    d, eom, q0, qd0 = block_start()
    res = run(d, eom, q0, qd0)
    s = 0.3 + 0.7 * res.t + 0.5 * (G @ GUIDE) * res.t ** 2
    centres = s[:, None] * GUIDE - BLOCK_TURN @ np.array([0.0, 0.1, -0.2])
    assert np.abs(res.q[:, :3] - centres).max() <= bound(np.abs(centres).max())
    assert np.abs(res.q[:, 3:] - q0[3:]).max() <= bound(1.0)
    reaction = np.array([eom.phi_q(q)[:, :3].T @ lam for q, lam in zip(res.q, res.lam)])
    across = 3.0 * (G - (G @ GUIDE) * GUIDE)
    assert np.abs(reaction - across).max() <= bound(3.0 * 9.81)


def sleeve() -> SpatialDescription:
    """A sleeve (full inertia tensor) on a cylindrical joint about SHAFT through the origin, its hub on its own axis."""
    d = SpatialDescription("sleeve")
    d.body("sleeve", 2.0, [[0.3, 0.02, -0.01], [0.02, 0.25, 0.03], [-0.01, 0.03, 0.2]],
           points={"hub": (0.0, 0.0, 0.3)}, axes={"bore": (0.0, 0.0, 1.0)})
    d.cylindrical("shaft", ("sleeve", "hub", "bore"), (GROUND, (0.0, 0.0, 0.0), tuple(SHAFT)))
    d.gravity(G)
    return d


def sleeve_start(s0=0.5, v0=-0.4, spin=4.0):
    d = sleeve()
    eom = spatial_equations(d)
    turn = Rotation.from_euler("x", -np.arctan2(1.0, 2.0)).as_matrix()   # body z onto SHAFT
    q0, qd0 = initial_state(d, eom, {"sleeve": (s0 - 0.3) * SHAFT}, orientations={"sleeve": wxyz(turn)},
                            angular_velocities={"sleeve": spin * SHAFT}, velocities={"sleeve": v0 * SHAFT})
    return d, eom, q0, qd0, turn


def test_a_sleeve_falls_along_and_spins_about_its_cylindrical_shaft():
    """Gravity has no moment about the shaft (the centre of mass is on it) and the gyroscopic moment w x J w is
    perpendicular to w: the spin stays, theta = w t, while the sleeve slides as under g . h alone."""
    d, eom, q0, qd0, turn = sleeve_start()
    np.testing.assert_allclose(turn @ np.array([0.0, 0.0, 1.0]), SHAFT, atol=1e-15)
    res = run(d, eom, q0, qd0)
    s = 0.5 - 0.4 * res.t + 0.5 * (G @ SHAFT) * res.t ** 2
    assert np.abs(res.q[:, :3] - (s - 0.3)[:, None] * SHAFT).max() <= bound(1.0)
    for t, q in zip(res.t, res.q):
        expected = Rotation.from_rotvec(4.0 * t * SHAFT).as_matrix() @ turn
        assert np.abs(quaternion_matrix(q[3:]) - expected).max() <= bound(4.0 * t + 1.0), t


def cardan() -> SpatialDescription:
    """Two shafts joined at the origin by a universal joint: the input on a revolute bearing about x, the output
    along u = (cos b, sin b, 0), its far end held by two distance links (0.3 m, across u) to ground."""
    u, across = np.array([np.cos(BETA), np.sin(BETA), 0.0]), np.array([-np.sin(BETA), np.cos(BETA), 0.0])
    d = SpatialDescription("cardan")
    d.body("input", 1.0, (0.02, 0.1, 0.1), points={"bearing": (-0.5, 0.0, 0.0), "yoke": (0.5, 0.0, 0.0)},
           axes={"shaft": (1.0, 0.0, 0.0), "fork": (0.0, 1.0, 0.0)})
    d.revolute("bearing", ("input", "bearing", "shaft"), (GROUND, (-1.0, 0.0, 0.0), (1.0, 0.0, 0.0)))
    d.body("output", 1.5, (0.03, 0.12, 0.12), points={"yoke": (-0.5, 0.0, 0.0), "end": (0.5, 0.0, 0.0)},
           axes={"fork": (0.0, 0.0, 1.0)})
    d.universal("cross", ("output", "yoke", "fork"), ("input", "yoke", "fork"))
    d.distance("link_up", ("output", "end"), (GROUND, tuple(u + 0.3 * np.array([0.0, 0.0, 1.0]))), 0.3)
    d.distance("link_side", ("output", "end"), (GROUND, tuple(u + 0.3 * across)), 0.3)
    return d


def cardan_start(omega_1=OMEGA_1, d: SpatialDescription | None = None):
    """Input fork along y (in the shafts' plane), theta_1 = 0: the output turns at omega_1 / cos(beta). ``d``: the
    Cardan shaft with loads added (default: unloaded)."""
    d = cardan() if d is None else d
    eom = spatial_equations(d)
    u = np.array([np.cos(BETA), np.sin(BETA), 0.0])
    q0, qd0 = initial_state(d, eom, {"input": (-0.5, 0.0, 0.0), "output": 0.5 * u},
                            orientations={"output": wxyz(Rotation.from_euler("z", BETA).as_matrix())},
                            angular_velocities={"input": (omega_1, 0.0, 0.0),
                                                "output": omega_1 / np.cos(BETA) * u})
    return d, eom, q0, qd0


def global_angular_velocity(p: np.ndarray, p_dot: np.ndarray) -> np.ndarray:
    """w = 2 (e0 e_dot - e0_dot e + e x e_dot) of unit Euler parameters (e0, e) and their rates."""
    return 2.0 * (p[0] * p_dot[1:] - p_dot[0] * p[1:] + np.cross(p[1:], p_dot[1:]))


def test_a_cardan_shaft_turns_at_its_velocity_ratio():
    """w_2 / w_1 = cos b / (1 - sin^2 b cos^2 theta_1) at every sample, theta_1 the input's angle from the shafts'
    plane, with w_2 along the output's bearing line; the links hold the output's far end at u."""
    d, eom, q0, qd0 = cardan_start()
    res = run(d, eom, q0, qd0, t_end=2.0)
    u = np.array([np.cos(BETA), np.sin(BETA), 0.0])
    w1 = np.array([global_angular_velocity(q[3:7], v[3:7]) for q, v in zip(res.q, res.qd)])
    w2 = np.array([global_angular_velocity(q[10:14], v[10:14]) for q, v in zip(res.q, res.qd)])
    theta_1 = 2.0 * np.arctan2(res.q[:, 4], res.q[:, 3])
    assert np.ptp(np.unwrap(theta_1)) > np.pi                      # more than half a turn: the ratio's full period
    ratio = np.cos(BETA) / (1.0 - np.sin(BETA) ** 2 * np.cos(theta_1) ** 2)
    scale = np.abs(w2).max()
    assert np.abs(w2 - (ratio * w1[:, 0])[:, None] * u).max() <= bound(scale)
    assert np.abs(w1[:, 1:]).max() <= bound(scale)
    ends = np.array([eom.points["output.end"](q) for q in res.q])
    assert np.abs(ends - u).max() <= bound(1.0)


def test_bad_joint_input_is_refused_by_name():
    d = cardan()
    eom = spatial_equations(d)
    with pytest.raises(SpatialDescriptionError, match="universal joint 'cross': axis 'fork' of 'output' and axis "
                                                      "'fork' of 'input' are not perpendicular.*angle 45 deg"):
        initial_state(d, eom, {"input": (-0.5, 0.0, 0.0), "output": (0.5, 0.0, 0.0)},
                      orientations={"output": wxyz(Rotation.from_euler("x", -np.pi / 4).as_matrix())})
    with pytest.raises(SpatialDescriptionError, match="length of joint 'rod' = 0.0 must be > 0"):
        d.distance("rod", ("output", "end"), (GROUND, (0.0, 0.0, 0.0)), 0.0)
    with pytest.raises(SpatialDescriptionError, match="orientation of joint 'slide' = .* is not a rotation matrix"):
        d.prismatic("slide", ("output", "end"), (GROUND, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0)),
                    [[1, 0, 0], [0, 1, 0], [0, 0, -1]])
    with pytest.raises(SpatialDescriptionError, match="joint 'tube': body 'input' has no axis 'bore'"):
        d.cylindrical("tube", ("output", "end", "fork"), ("input", "yoke", "bore"))
