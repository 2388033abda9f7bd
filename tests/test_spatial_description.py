"""The spatial description's checks, its rotation matrices and the Euler-parameter equations of study.spatial."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from study.model.joints import Description
from study.reference_data import tolerance
from study.spatial import GROUND, SpatialDescription, SpatialDescriptionError, initial_state, spatial_equations
from study.spatial.derive import rotational_velocity_terms
from study.spatial.rotations import g_matrix, rotation
from tests.test_spatial_heavy_top import quaternion_matrix

RNG = np.random.default_rng(36)


def unit(v) -> np.ndarray:
    return np.asarray(v, dtype=float) / np.linalg.norm(v)


def test_rotation_is_the_quaternion_matrix_and_g_gives_the_body_angular_velocity():
    """A = E G^T against the matrix written out entry by entry; skew(w') = A^T A_dot with w' = 2 G p_dot."""
    p, w_body = unit(RNG.normal(size=4)), RNG.normal(size=3)
    a = np.array(rotation(list(p)).tolist(), dtype=float)
    assert np.abs(a - quaternion_matrix(p)).max() <= tolerance("round_off")
    g = np.array(g_matrix(list(p)).tolist(), dtype=float)
    p_dot = 0.5 * g.T @ w_body
    h = 1e-6
    a_dot = (quaternion_matrix(p + h * p_dot) - quaternion_matrix(p - h * p_dot)) / (2 * h)
    skew = a.T @ a_dot
    assert np.abs(np.array([skew[2, 1], skew[0, 2], skew[1, 0]]) - w_body).max() <= \
        tolerance("finite_difference_jacobian") * np.abs(w_body).max()


def test_the_velocity_terms_are_lagranges_for_a_full_inertia_tensor():
    """d/dt(dT/dp_dot) - dT/dp - M p_ddot = -8 G_dot^T J' G_dot p for T = 2 p_dot^T G^T J' G p_dot, symbolically."""
    p, pd = sp.Matrix(sp.symbols("e0:4", real=True)), sp.Matrix(sp.symbols("ed0:4", real=True))
    j = sp.Matrix(3, 3, lambda i, k: sp.Symbol(f"J{min(i, k)}{max(i, k)}", real=True))
    g = g_matrix(list(p))
    kinetic = 2 * (pd.T * g.T * j * g * pd)[0]
    momentum = sp.Matrix([kinetic]).jacobian(pd).T
    lagrange = momentum.jacobian(p) * pd - sp.Matrix([kinetic]).jacobian(p).T
    assert (lagrange - rotational_velocity_terms(j, p, pd)).expand() == sp.zeros(4, 1)


@pytest.mark.parametrize("inertia, words", [
    ((1.0, 2.0, -1.0), "not positive definite"),
    ([[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "not symmetric"),
    ((1.0, 1.0, 3.0), "exceeds the sum of the other two"),
    (2.0, "planar body's scalar inertia"),
])
def test_a_bad_inertia_tensor_is_refused_by_name(inertia, words):
    d = SpatialDescription("m")
    with pytest.raises(SpatialDescriptionError, match=f"inertia of body 'wheel'.*{words}"):
        d.body("wheel", 1.0, inertia)


def test_bad_points_axes_and_masses_are_refused_by_name():
    d = SpatialDescription("m")
    with pytest.raises(SpatialDescriptionError, match=r"axis 'spin' of body 'a' = \(0, 0, 0\) is a zero vector"):
        d.body("a", 1.0, (1, 1, 1), axes={"spin": (0, 0, 0)})
    with pytest.raises(SpatialDescriptionError, match=r"point 'tip' of body 'b'.*has 2 entries.*planar"):
        d.body("b", 1.0, (1, 1, 1), points={"tip": (0, 1)})
    with pytest.raises(SpatialDescriptionError, match="mass of body 'c' = 0"):
        d.body("c", 0.0, (1, 1, 1))
    d.body("d", 1.0, (1, 1, 1), points={"tip": (0, 1, 0)}, axes={"x": (1, 0, 0)})
    with pytest.raises(SpatialDescriptionError, match="used twice"):
        d.body("d", 1.0, (1, 1, 1))
    with pytest.raises(SpatialDescriptionError, match="joint 'j': body 'd' has no point 'toe'"):
        d.spherical("j", ("d", "toe"), (GROUND, (0, 0, 0)))
    with pytest.raises(SpatialDescriptionError, match="ground axis of joint 'k'.*zero vector"):
        d.revolute("k", ("d", "tip", "x"), (GROUND, (0, 0, 0), (0, 0, 0)))
    with pytest.raises(SpatialDescriptionError, match=r"force 'f'.*uses \['x'\]"):
        d.force("f", "d", "tip", (0, 0, sp.Symbol("x")))


def test_a_planar_description_is_never_run_as_a_spatial_one():
    planar = Description("pendulum", ["theta"], {"m": 1.0})
    with pytest.raises(SpatialDescriptionError, match="'pendulum' is a Description, not a SpatialDescription"):
        spatial_equations(planar)


def pendulum(frame_axis=(1.0, 0.0, 0.0)) -> SpatialDescription:
    """A body hanging from a revolute joint about the global x axis, its centre of mass 0.5 below the hinge."""
    d = SpatialDescription("pendulum")
    d.body("rod", 2.0, (0.3, 0.1, 0.25), points={"hinge": (0.0, 0.0, 0.5)}, axes={"pin": frame_axis})
    d.revolute("hinge", ("rod", "hinge", "pin"), (GROUND, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0)))
    d.gravity((0.0, 0.0, -9.81))
    return d


def test_the_initial_state_refuses_bad_euler_parameters_and_angular_velocities():
    d = pendulum()
    eom = spatial_equations(d)
    where = {"rod": (0.0, 0.0, -0.5)}
    with pytest.raises(SpatialDescriptionError, match=r"Euler parameters of body 'rod' = \[1.0, 0.1, 0.0, 0.0\] have "
                                                      r"norm 1.00499"):
        initial_state(d, eom, where, orientations={"rod": (1.0, 0.1, 0.0, 0.0)})
    with pytest.raises(SpatialDescriptionError, match="angular velocity of body 'rod' = .* has 2 entries"):
        initial_state(d, eom, where, angular_velocities={"rod": (1.0, 2.0)})
    with pytest.raises(SpatialDescriptionError, match="angular velocities violate the joints: the velocity of hinge_"):
        initial_state(d, eom, where, angular_velocities={"rod": (0.0, 1.0, 0.0)})
    with pytest.raises(SpatialDescriptionError, match="frame = 'local'"):
        initial_state(d, eom, where, frame="local")


def test_a_revolute_pendulum_follows_its_planar_equation():
    """theta'' = -m g l sin(theta) / (J_x + m l^2) about the hinge, integrated here directly."""
    from scipy.integrate import solve_ivp

    from study.simulate import simulate
    d = pendulum()
    eom = spatial_equations(d)
    q0, qd0 = initial_state(d, eom, {"rod": (0.0, 0.0, -0.5)}, angular_velocities={"rod": (3.0, 0.0, 0.0)},
                            frame="body")
    rtol = 1e-10
    res = simulate(eom, q0, qd0, t_end=1.0, integrator="DOP853", rtol=rtol, atol=rtol * 1e-2, output_step=0.1)
    k = 2.0 * 9.81 * 0.5 / (0.3 + 2.0 * 0.25)
    exact = solve_ivp(lambda t, y: [y[1], -k * np.sin(y[0])], (0, 1), [0.0, 3.0], method="DOP853", rtol=1e-13,
                      atol=1e-15, t_eval=res.t).y[0]
    theta = 2 * np.arctan2(res.q[:, 4], res.q[:, 3])
    assert np.abs(theta - exact).max() <= tolerance("adaptive_global_error_factor") * rtol * np.abs(exact).max()
    assert np.abs(res.q[:, 5:7]).max() <= tolerance("adaptive_global_error_factor") * rtol   # no turn off the pin


def test_a_welded_body_stays_and_a_free_body_follows_its_loads():
    """Fixed to ground under gravity: at rest. Free, with a body-frame torque about its z axis and a force at its
    centre: theta = w0 t + tau t^2 / (2 J_z), r = f t^2 / (2 m)."""
    from study.simulate import simulate
    d = SpatialDescription("two")
    d.body("weld", 1.0, (1, 1, 1), points={"o": (0.0, 0.0, 0.0)})
    d.fixed("weld_joint", ("weld", "o"), (GROUND, (1.0, 2.0, 3.0)))
    d.body("free", 2.0, (0.5, 0.5, 0.8), points={"c": (0.0, 0.0, 0.0)})
    d.gravity((0.0, 0.0, -9.81))
    d.torque("spin", "free", (0.0, 0.0, 1.6), frame="body")
    d.force("push", "free", "c", (0.0, 2.0, 2.0 * 9.81))   # lifts the free body's weight, pushes along y
    eom = spatial_equations(d)
    q0, qd0 = initial_state(d, eom, {"weld": (1.0, 2.0, 3.0), "free": (0.0, 0.0, 0.0)},
                            angular_velocities={"free": (0.0, 0.0, 2.0)})
    rtol = 1e-10
    res = simulate(eom, q0, qd0, t_end=1.0, integrator="DOP853", rtol=rtol, atol=rtol * 1e-2, output_step=0.25)
    bound = tolerance("adaptive_global_error_factor") * rtol
    assert np.abs(res.q[:, :7] - q0[:7]).max() <= bound
    theta = 2.0 * res.t + 1.6 * res.t ** 2 / (2 * 0.8)
    expected_p = np.stack([np.cos(theta / 2), 0 * theta, 0 * theta, np.sin(theta / 2)], axis=1)
    assert np.abs(res.q[:, 10:] - expected_p).max() <= bound * theta.max()
    assert np.abs(res.q[:, 8] - res.t ** 2 / 2).max() <= bound


def test_the_equations_are_derived_once_per_content():
    """Two descriptions with the same content (its declared redundancy aside) share one derivation in a process;
    a changed one, even the same object changed after a first call, is derived anew."""
    first, again = spatial_equations(pendulum()), spatial_equations(pendulum())
    assert again.system is first.system and again.key == first.key
    redundant = pendulum()
    redundant.redundant_rows(1, "declared for the test")
    declared = spatial_equations(redundant)
    assert declared.system is first.system and declared.redundant_rows == 1 and first.redundant_rows == 0
    other = pendulum(frame_axis=(0.0, 1.0, 0.0))
    assert spatial_equations(other).key != first.key
    moon = pendulum()
    assert spatial_equations(moon).key == first.key
    moon.gravity((0.0, 0.0, -1.62))
    assert spatial_equations(moon).key not in (first.key, spatial_equations(other).key)
