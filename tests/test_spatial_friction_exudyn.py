"""The Exudyn model of Coulomb friction in spatial joints (study.exudyn_models.spatial_friction) against closed-form
physics: a block sliding on a prismatic guide along a general 3D axis, and a wheel braked by the friction of its
bearing (issue 36 item 6).

Every Exudyn result here is mapped with the equations of the same description without its frictions
(:func:`frictionless`), so that the checks are against closed forms and saddle points written without
study.spatial.friction: friction adds neither a coordinate nor a constraint row, so these equations have the same
coordinates, Phi and applied loads (a revolute's position rows are the gap's global components, ``_x``, ``_y``,
``_z``); only their forces lack the friction, which the mapping adds to the norm rows itself. The mapping with the
equations WITH the friction (a revolute's rows in its joint frame) is tests/test_spatial_friction_carriage.py's. Tolerances: reference/tolerances.toml ([spatial_friction_*]) and reference/cross_validation.toml, each
with its reason."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import sympy as sp
from scipy.spatial.transform import Rotation

from study.compare import observed_orders
from study.exudyn_models.settings import DEFAULT_EPS
from study.exudyn_models.spatial import run, run_spatial
from study.reference_data import tolerance
from study.solver.accelerations import Multiplier
from study.spatial import GROUND, SpatialDescription, SpatialMechanism, initial_state, spatial_equations

U = np.array([1.0, 2.0, 2.0]) / 3.0                      # the guide's axis, global
G = np.array([1.0, -2.0, -9.81])                          # gravity: across the guide along both of its frame's axes
TURN = Rotation.from_euler("xyz", [0.2, 0.4, -0.3]).as_matrix()   # the block's locked orientation
SHOE = np.array([0.0, 0.1, -0.2])                         # the block's point on the guide, off its centre of mass
MASS, MU, RESISTANCE = 2.0, 0.3, 0.5                      # the block [kg], mu_k, F0 [N]
S0 = 0.3                                                  # the shoe's start along the guide [m]
PRESS, RATE = 0.5, 7.0                                    # the varying transverse force: c and omega [rad/s]
RAIL_BASE, RAIL_MOUNT = np.array([0.0, 0.2, 0.1]), np.array([0.2, -0.1, 0.0])   # the welded rail's points
AXLE = np.array([np.cos(0.5), np.sin(0.5), 0.0])          # the wheel's axle: horizontal, along no global axis
HUB = np.array([0.1, 0.2, 0.3])
WHEEL_MASS, WHEEL_AXIAL, WHEEL_MU, PIN, OMEGA0 = 2.0, 0.05, 0.2, 0.05, 20.0   # kg, kg m^2, mu_k, r [m], rad/s
WHEEL_TURN = Rotation.align_vectors([AXLE], [[0.0, 0.0, 1.0]])[0]    # the body's z axis onto the axle
DELTA = tolerance("pin_friction_norm_width")              # the law's smooth norm |x|_delta = sqrt(x^2 + delta^2)


def tol(key: str) -> float:
    return tolerance(key, table="cross_validation")


def wxyz(rotation: Rotation) -> np.ndarray:
    x, y, z, w = rotation.as_quat()
    return np.array([w, x, y, z])


def frictionless(d: SpatialDescription) -> SpatialDescription:
    """The same description without its frictions: its equations map the Exudyn result (module docstring)."""
    bare = copy.copy(d)
    bare.frictions = {}
    return bare


def across() -> np.ndarray:
    """g_perp, the part of gravity across the guide."""
    return G - (G @ U) * U


def block(press: float = 0.0, friction: bool = True, rail: bool = False) -> SpatialDescription:
    """A block on a prismatic guide along U through the origin, its shoe off its centre of mass, under G; with
    ``press`` a force press sin(RATE t) m g_perp at its centre (the normal force m |g_perp| (1 + press sin(RATE t)));
    with ``rail`` the guide is a rail welded to ground at a turned orientation (a guide body that carries the
    friction's reaction)."""
    d = SpatialDescription("friction_block" + ("_rail" if rail else ""))
    d.body("block", MASS, (0.1, 0.2, 0.25), points={"shoe": tuple(SHOE), "centre": (0.0, 0.0, 0.0)})
    guide, locked = (GROUND, (0.0, 0.0, 0.0), tuple(U)), TURN
    if rail:   # the rail's frame is TURN, its base at the origin: the block keeps the rail's orientation
        d.body("rail", 5.0, (0.3, 0.4, 0.5), points={"base": tuple(RAIL_BASE), "mount": tuple(RAIL_MOUNT)},
               axes={"track": tuple(TURN.T @ U)})
        d.fixed("weld", ("rail", "mount"), (GROUND, tuple(TURN @ (RAIL_MOUNT - RAIL_BASE))), TURN)
        guide, locked = ("rail", "base", "track"), np.eye(3)
    d.prismatic("slide", ("block", "shoe"), guide, locked)
    d.gravity(G)
    if press:
        d.force("press", "block", "centre", tuple(press * MASS * float(c) * sp.sin(RATE * d.t) for c in across()))
    if friction:
        d.friction("slide", MU + 0.1, MU, resistance=RESISTANCE)
    return d


def block_start(d: SpatialDescription, v0: float, rail: bool = False):
    eom = spatial_equations(frictionless(d))
    positions = {"block": S0 * U - TURN @ SHOE}
    orientations = {"block": wxyz(Rotation.from_matrix(TURN))}
    if rail:   # the rail's base on the guide line through the origin, its frame turned by TURN
        positions["rail"] = -TURN @ RAIL_BASE
        orientations["rail"] = orientations["block"]
    q0, qd0 = initial_state(d, eom, positions, orientations=orientations, velocities={"block": v0 * U})
    return eom, q0, qd0


def slide(q: np.ndarray) -> np.ndarray:
    """The shoe's place along the guide, from the block's centre (its orientation held by the guide)."""
    return (q[:, :3] + TURN @ SHOE) @ U


def level(normal) -> np.ndarray:
    """The friction's level mu_k |N|_delta + F0 [N] at the normal force N."""
    return MU * np.sqrt(np.asarray(normal) ** 2 + DELTA ** 2) + RESISTANCE


@pytest.mark.parametrize("v0", [-0.5, 3.5])
def test_a_block_sliding_under_constant_loads_follows_the_closed_form(v0):
    """s(t) = s0 + v0 t + a t^2/2, a = g.u - sgn(v0) (mu_k |m g_perp|_delta + F0) / m, sliding down and speeding up
    (v0 < 0) or sliding up and slowing (v0 > 0, still at 1.5 m/s at the end), never near the tanh band. Generalized-alpha integrates a
    constant acceleration exactly, so no step size separates the runs: the closed form holds at two steps to
    [spatial_friction_exact_quadratic] (the order is measured under a varying load below). The normal force is the
    weight across the guide, the recorded friction the law at the converged normal of the same step."""
    t_end, h = tolerance("spatial_friction_block_horizon"), tolerance("spatial_friction_block_step")
    d = block()
    eom, q0, qd0 = block_start(d, v0)
    normal = MASS * np.linalg.norm(across())
    a = G @ U - np.sign(v0) * level(normal) / MASS
    for step in (h, h / 2):
        r = run_spatial(d, eom, q0, qd0, t_end, step)
        s = S0 + v0 * r.t + 0.5 * a * r.t ** 2
        assert np.all(np.sign(v0) * (v0 + a * r.t) > tol("friction_saturation_speed"))   # tanh(v/eps) = sgn v
        assert np.abs(slide(r.q) - s).max() <= tolerance("spatial_friction_exact_quadratic"), (step, v0)
        assert np.abs(r.q[:, 3:] - q0[3:]).max() <= tolerance("spatial_friction_exact_quadratic")
        assert np.abs(r.forces["normal_slide"] - normal).max() <= tol("index3_reaction_floor_relative") * normal
        law = -np.sign(v0) * level(r.forces["normal_slide"])
        assert np.abs(r.forces["friction_slide"] - law).max() <= tol("friction_relation_relative") * abs(law).max()
        assert r.meta["friction"] == "regularized" and r.meta["eps"] == DEFAULT_EPS


@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_a_block_under_a_varying_normal_force_converges_at_order_two(solver):
    """With the transverse force press sin(RATE t) m g_perp the normal force is m |g_perp| (1 + press sin(RATE t))
    and s(t) = s0 + v0 t + a0 t^2/2 + mu_k |g_perp| press (t/RATE - sin(RATE t)/RATE^2) (v0 < 0, a0 the constant
    part). At the steps h, h/2, h/4 Exudyn's errors (both implicit solvers) in s and in the energy balance (kinetic + potential - the
    works of the force and of the friction) are above the floor and fall at order >= min_order; a friction read
    one step late would leave an O(h) error. The recorded friction is the law at the converged normal of its step."""
    t_end, h = tolerance("spatial_friction_block_horizon"), tolerance("spatial_friction_block_step")
    v0, g_perp = -0.5, np.linalg.norm(across())
    d = block(press=PRESS)
    eom, q0, qd0 = block_start(d, v0)
    a0 = G @ U + level(MASS * g_perp) / MASS
    steps, errors, energy = [h, h / 2, h / 4], [], []
    for step in steps:
        r = run_spatial(d, eom, q0, qd0, t_end, step, solver=solver)
        t = r.t
        s = S0 + v0 * t + 0.5 * a0 * t ** 2 + MU * g_perp * PRESS * (t / RATE - np.sin(RATE * t) / RATE ** 2)
        errors.append(np.abs(slide(r.q) - s).max())
        balance = r.energy_balance()
        energy.append(np.abs(balance - balance[0]).max())
        normal = MASS * g_perp * (1 + PRESS * np.sin(RATE * t))
        assert np.abs(r.forces["normal_slide"] - normal).max() <= tol("index3_reaction_floor_relative") * normal.max()
        law = level(r.forces["normal_slide"])       # sliding down (v < 0): the friction pushes up, +level
        assert np.abs(r.forces["friction_slide"] - law).max() <= tol("friction_relation_relative") * law.max()
    for name, e in (("s", errors), ("energy", energy)):
        assert min(e) > tol("order_error_floor"), (name, e)
        assert np.all(observed_orders(steps, e) >= tol("min_order")), (name, e)


def test_friction_none_is_the_frictionless_model():
    """friction='none' leaves the friction out: the block slides as under gravity alone, s0 + v0 t + (g.u) t^2/2,
    exactly (a constant acceleration); the normal force is still reported, the friction and its work are 0."""
    t_end, h = tolerance("spatial_friction_block_horizon"), tolerance("spatial_friction_block_step")
    d = block()
    eom, q0, qd0 = block_start(d, 1.0)
    r = run_spatial(d, eom, q0, qd0, t_end, h, friction="none")
    s = S0 + r.t + 0.5 * (G @ U) * r.t ** 2
    assert np.abs(slide(r.q) - s).max() <= tolerance("spatial_friction_exact_quadratic")
    normal = MASS * np.linalg.norm(across())
    assert np.abs(r.forces["normal_slide"] - normal).max() <= tol("index3_reaction_floor_relative") * normal
    assert not r.forces["friction_slide"].any() and not r.energies["work_friction_slide"].any()
    assert r.meta["friction"] == "none"


def point_jacobian(eom, name: str, q: np.ndarray) -> np.ndarray:
    """d(position of point ``name``)/dq by central differences: exact to round-off, the position r + A(p) s' being
    quadratic in q."""
    step = 1e-3
    columns = [(eom.points[name](q + step * e) - eom.points[name](q - step * e)) / (2 * step) for e in np.eye(len(q))]
    return np.array(columns).T


@pytest.mark.parametrize("rail", [False, True], ids=["ground_guide", "welded_rail"])
def test_initial_multipliers_with_friction_match_the_saddle_point(rail):
    """At t = 0 Exudyn's multipliers (every joint row and, in the in-house convention, the norm rows) and
    accelerations solve the saddle point [[M, J^T], [J, 0]] of the frictionless equations with the friction force
    f u at the shoe (and -f u at the rail's point under it, the rail welded at a turned orientation), f =
    -sgn(v0) (mu_k |m g_perp|_delta + F0): the friction is applied where the law says, with the seeded normal
    force, in the rail's frame; the norm rows carry its part along p. Band: reaction_zero_velocity_relative."""
    v0 = 1.5
    d = block(rail=rail)
    eom, q0, qd0 = block_start(d, v0, rail)
    force = -np.sign(v0) * level(MASS * np.linalg.norm(across())) * U
    applied = point_jacobian(eom, "block.shoe", q0).T @ force
    if rail:
        applied -= point_jacobian(eom, "rail.base", q0).T @ force
    qdd, lam = Multiplier().solve(eom.mass(q0), eom.forces(0.0, q0, qd0) + applied, eom.phi_q(q0),
                                  eom.gamma(q0, qd0))
    r = run_spatial(d, eom, q0, qd0, 0.002, 1e-3)
    rel = tol("reaction_zero_velocity_relative")
    assert np.abs(r.lam[0] - lam).max() <= rel * np.abs(lam).max(), (r.lam[0], lam)
    assert np.abs(r.qdd[0] - qdd).max() <= rel * np.abs(qdd).max()


def wheel(thrust: float) -> SpatialDescription:
    """A disc centred on its axle (axle horizontal, not along a global axis), on a revolute joint with ground whose
    pin has radius R; with ``thrust`` a constant force along the axle at the hub."""
    d = SpatialDescription("friction_wheel" + ("_thrust" if thrust else ""))
    d.body("wheel", WHEEL_MASS, (0.04, 0.04, WHEEL_AXIAL), points={"hub": (0.0, 0.0, 0.0)}, axes={"axle": (0, 0, 1)})
    d.revolute("bearing", ("wheel", "hub", "axle"), (GROUND, tuple(HUB), tuple(AXLE)))
    d.gravity((0.0, 0.0, -9.81))
    if thrust:
        d.force("thrust", "wheel", "hub", tuple(thrust * AXLE))
    d.friction("bearing", 0.3, WHEEL_MU, radius=PIN)
    return d



def wheel_omega(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """omega = 2 E(p) p_dot (global) from the Euler parameters and their rates, one row per sample."""
    e0, e1, e2, e3 = q[:, 3:].T
    e_matrix = np.array([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])
    return 2 * np.einsum("ijn,nj->ni", e_matrix, qd[:, 3:])


@pytest.mark.parametrize("thrust", [0.0, 30.0])
def test_a_wheel_braked_by_its_bearing_converges_at_order_two(thrust):
    """R_t = m g (the weight across the axle; the disc is centred, so no other transverse load), the friction torque
    mu_k r |m g|_delta about the axle: omega(t) = omega0 - alpha t, alpha = mu_k r |m g|_delta / I_axle, and the Euler
    parameters those of the turn theta(t) = omega0 t - alpha t^2 / 2 about the axle. At the steps h, h/2, h/4 the
    errors in p and in omega fall at order >= min_order above the floor, and so does the energy balance's (with
    the friction's work). A thrust of 30 N along the axle loads the joint axially (its multipliers carry it) and
    changes nothing: friction on the whole reaction would brake 1.8 times harder, an O(1) error."""
    t_end, h = tolerance("spatial_friction_wheel_horizon"), tolerance("spatial_friction_wheel_step")
    d = wheel(thrust)
    eom = spatial_equations(frictionless(d))
    q0, qd0 = initial_state(d, eom, {"wheel": HUB}, orientations={"wheel": wxyz(WHEEL_TURN)},
                            angular_velocities={"wheel": OMEGA0 * AXLE})
    weight = WHEEL_MASS * 9.81
    alpha = WHEEL_MU * PIN * np.sqrt(weight ** 2 + DELTA ** 2) / WHEEL_AXIAL
    steps, errors = [h, h / 2, h / 4], {"p": [], "omega": [], "energy": []}
    bearing = [eom.constraint_names.index(f"bearing_{c}") for c in "xyz"]
    for step in steps:
        r = run_spatial(d, eom, q0, qd0, t_end, step, output_step=t_end / 5)
        theta = OMEGA0 * r.t - 0.5 * alpha * r.t ** 2
        p = np.array([wxyz(Rotation.from_rotvec(angle * AXLE) * WHEEL_TURN) for angle in theta])
        p *= np.sign(np.sum(p * r.q[:, 3:], axis=1))[:, None]        # p and -p are the same orientation
        omega = wheel_omega(r.q, r.qd)
        assert np.all(omega @ AXLE > tol("friction_saturation_speed"))   # turning throughout: tanh(omega/eps) = 1
        errors["p"].append(np.abs(r.q[:, 3:] - p).max())
        errors["omega"].append(np.abs(omega - np.outer(OMEGA0 - alpha * r.t, AXLE)).max())
        balance = r.energy_balance()
        errors["energy"].append(np.abs(balance - balance[0]).max())
        floor = tol("index3_reaction_floor_relative") * np.hypot(weight, thrust)
        assert np.abs(r.forces["normal_bearing"] - weight).max() <= floor
        assert np.abs(np.abs(r.lam[:, bearing] @ AXLE) - thrust).max() <= floor
    for name, e in errors.items():
        assert min(e) > tol("order_error_floor"), (name, e)
        assert np.all(observed_orders(steps, e) >= tol("min_order")), (name, e)


def spinner() -> SpatialDescription:
    """A carrier on a revolute joint to ground about a tilted axis, and a rotor on a revolute joint to the carrier,
    off its centre, about an axis across the carrier's: both pins with friction (the rotor's between two moving
    bodies), under gravity."""
    d = SpatialDescription("friction_spinner")
    d.body("carrier", 3.0, (0.2, 0.3, 0.35), points={"pivot": (0.0, 0.0, -0.3), "seat": (0.25, 0.1, 0.2)},
           axes={"spin": (0.0, 0.0, 1.0), "cross": (1.0, 1.0, 0.5)})
    d.body("rotor", 1.0, (0.02, 0.03, 0.04), points={"hub": (0.05, 0.0, 0.1)}, axes={"axle": (0.0, 0.0, 1.0)})
    d.revolute("mount", ("carrier", "pivot", "spin"), (GROUND, (0.0, 0.0, 0.0), (0.0, 0.6, 0.8)))
    d.revolute("spindle", ("rotor", "hub", "axle"), ("carrier", "seat", "cross"))
    d.gravity((0.5, 0.0, -9.81))
    d.friction("mount", 0.3, 0.2, resistance=0.1, radius=0.03)
    d.friction("spindle", 0.4, 0.3, resistance=0.05, radius=0.02)
    return d


def spinner_start(d: SpatialDescription):
    """The carrier at 3 rad/s about its pin, the rotor at 10 rad/s about its own relative to it: the consistent
    state (the centres' velocities follow from the joints)."""
    eom = spatial_equations(frictionless(d))
    carrier = Rotation.align_vectors([[0.0, 0.6, 0.8]], [[0.0, 0.0, 1.0]])[0]
    cross = carrier.apply(np.array([1.0, 1.0, 0.5]) / 1.5)
    rotor = Rotation.align_vectors([cross], [[0.0, 0.0, 1.0]])[0]
    spin = 3.0 * np.array([0.0, 0.6, 0.8])
    seat = carrier.apply([0.0, 0.0, 0.3]) + carrier.apply([0.25, 0.1, 0.2])
    q0, qd0 = initial_state(d, eom, {"carrier": carrier.apply([0.0, 0.0, 0.3]),
                                     "rotor": seat - rotor.apply([0.05, 0.0, 0.1])},
                            orientations={"carrier": wxyz(carrier), "rotor": wxyz(rotor)},
                            angular_velocities={"carrier": spin, "rotor": spin + 10.0 * cross})
    return eom, q0, qd0


def e_matrices(q: np.ndarray) -> list[np.ndarray]:
    """E(p) of every body at q (omega = 2 E p_dot; a global torque n has the generalized force 2 E^T n on p)."""
    out = []
    for k in range(3, len(q), 7):
        e0, e1, e2, e3 = q[k:k + 4]
        out.append(np.array([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]]))
    return out


def pin_saddle_point(d: SpatialDescription, eom, q0: np.ndarray, qd0: np.ndarray):
    """The saddle point of the frictionless equations with every pin's friction torque pair as an applied load, the
    law at the transverse reaction it produces (a fixed point: the torques change the reactions): tau = -(mu_k r
    |R_t|_delta + T0) tanh(omega_rel/eps) about u = A_b h_b on body a, -tau u on body b, R_t the part of the
    joint's force rows' multipliers across u."""
    bodies, e = list(d.bodies), e_matrices(q0)
    omega = {b: 2 * e[i] @ qd0[7 * i + 3:7 * i + 7] for i, b in enumerate(bodies)}
    pins = []
    for j in d.joints:
        f = d.frictions[j.name]
        axis = np.array(d.bodies[j.body_b].axes[j.axis_b]) if j.body_b != GROUND else np.array(j.axis_b)
        if j.body_b != GROUND:
            i = bodies.index(j.body_b)
            axis = Rotation.from_quat(np.roll(q0[7 * i + 3:7 * i + 7], -1)).apply(axis)
        rate = axis @ (omega[j.body_a] - omega.get(j.body_b, 0.0))
        rows = [eom.constraint_names.index(f"{j.name}_{c}") for c in "xyz"]
        pins.append((j, f, axis, rate, rows))
    applied, previous = np.zeros(len(q0)), None
    for _ in range(50):
        qdd, lam = Multiplier().solve(eom.mass(q0), eom.forces(0.0, q0, qd0) + applied, eom.phi_q(q0),
                                      eom.gamma(q0, qd0))
        applied = np.zeros(len(q0))
        for j, f, axis, rate, rows in pins:
            across = lam[rows] - (lam[rows] @ axis) * axis
            tau = -(f.mu_kinetic * f.radius * np.sqrt(across @ across + DELTA ** 2) + f.resistance) * \
                np.tanh(rate / DEFAULT_EPS)
            for body, sign in ((j.body_a, 1.0), (j.body_b, -1.0)):
                if body != GROUND:
                    i = bodies.index(body)
                    applied[7 * i + 3:7 * i + 7] += 2 * e[i].T @ (sign * tau * axis)
        if previous is not None and np.array_equal(lam, previous):
            return qdd, lam
        previous = lam
    raise AssertionError(f"the pins' friction and reactions did not settle in 50 passes: {lam - previous}")


def test_initial_multipliers_of_pins_with_friction_match_the_saddle_point():
    """At t = 0, with both pins turning (the rotor's relative to the moving carrier), Exudyn's multipliers and
    accelerations solve the saddle point with each pin's friction torque pair at its own transverse reaction
    (:func:`pin_saddle_point`): the torque about the carrier's turned axis, on both bodies, with the sign of the
    relative rate. Band: as tests/test_spatial_exudyn.py (reaction_zero_velocity_relative of the multipliers, and
    reaction_velocity_term_relative of the part that the velocity terms gamma produce)."""
    d = spinner()
    eom, q0, qd0 = spinner_start(d)
    qdd, lam = pin_saddle_point(d, eom, q0, qd0)
    qdd_g, lam_g = Multiplier().solve(eom.mass(q0), np.zeros(len(q0)), eom.phi_q(q0), eom.gamma(q0, qd0))
    qdd_0, lam_0 = Multiplier().solve(eom.mass(q0), eom.forces(0.0, q0, qd0), eom.phi_q(q0), eom.gamma(q0, qd0))
    r = run_spatial(d, eom, q0, qd0, 0.002, 1e-3)
    rel, vel = tol("reaction_zero_velocity_relative"), tol("reaction_velocity_term_relative")
    band = rel * np.abs(lam).max() + vel * np.abs(lam_g).max()
    assert np.abs(r.lam[0] - lam).max() <= band, (r.lam[0], lam)
    assert np.abs(r.lam[0] - lam_0).max() > band          # the friction shows: the frictionless solve is outside
    band = rel * np.abs(qdd).max() + vel * np.abs(qdd_g).max()
    assert np.abs(r.qdd[0] - qdd).max() <= band < np.abs(r.qdd[0] - qdd_0).max()


@pytest.mark.parametrize("friction, eps, frictions, culprit", [
    ("exact", DEFAULT_EPS, True, "friction = 'exact': the Exudyn model of friction_block's joint friction"),
    ("sign", DEFAULT_EPS, True, "has the regularized law only"),
    ("none", 1e-2, True, "eps = 0.01: friction = 'none' leaves the friction of friction_block's joints out"),
    ("regularized", -1.0, True, "eps = -1.0 must be a finite number > 0"),
    ("exact", DEFAULT_EPS, False, "friction = 'exact': friction_block is spatial and has no friction entries"),
    ("regularized", 1e-2, False, "eps = 0.01: friction_block is spatial and has no friction entries"),
])
def test_friction_options_that_mean_nothing_are_refused_by_name(friction, eps, frictions, culprit):
    """Before any work: the mechanism's run refuses them before its equations are derived."""
    d = block(friction=frictions)
    mech = SpatialMechanism(d, positions={"block": S0 * U - TURN @ SHOE},
                            orientations={"block": wxyz(Rotation.from_matrix(TURN))})
    with pytest.raises(ValueError, match=culprit.replace("(", r"\(").replace(")", r"\)")):
        run(mech, 0.002, 1e-3, friction=friction, eps=eps)
