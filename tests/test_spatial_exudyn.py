"""Exudyn models generated from spatial descriptions (study.exudyn_models.spatial) against the in-house equations at
t = 0 and the heavy top's independent model (reference/spatial/heavy_top.toml) as the step halves.

Tolerances: reference/cross_validation.toml (the t = 0 bands and the convergence order of the planar models) and
reference/tolerances.toml ([spatial_exudyn_richardson]), each with its reason."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from study.compare import observed_orders
from study.exudyn_models import ExudynModelError
from study.exudyn_models.spatial import run_spatial
from study.reference_data import tolerance, values
from study.simulate import simulate
from study.solver.accelerations import Multiplier
from study.spatial import GROUND, SpatialDescription, initial_state, spatial_equations
from tests.test_spatial_heavy_top import TABLE, heavy_top_start
from tests.test_spatial_joints import BLOCK_TURN, block, block_start, cardan, cardan_start

WELD = Rotation.from_euler("xyz", [0.3, -0.5, 0.7]).as_matrix()   # the lump's locked orientation, any rotation


def tol(key: str) -> float:
    return tolerance(key, table="cross_validation")


def linkage() -> SpatialDescription:
    """A rod on a revolute joint to ground (axis x), an arm on a spherical joint at the rod's end, a lump welded to
    the rod at a turned orientation; gravity, a body-frame torque on the arm and a force on the rod, both of time."""
    d = SpatialDescription("linkage")
    d.body("rod", 2.0, (0.3, 0.1, 0.25), points={"hinge": (0.0, 0.0, 0.5), "end": (0.1, 0.2, -0.5),
                                                 "seat": (0.2, 0.0, -0.3)}, axes={"pin": (1.0, 0.0, 0.0)})
    d.revolute("hinge", ("rod", "hinge", "pin"), (GROUND, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0)))
    d.body("arm", 1.5, (0.2, 0.3, 0.4), points={"top": (0.0, 0.3, 0.0)})
    d.spherical("ball", ("arm", "top"), ("rod", "end"))
    d.body("lump", 0.7, (0.05, 0.06, 0.07), points={"at": (0.1, 0.1, 0.1)})
    d.fixed("weld", ("lump", "at"), ("rod", "seat"), WELD.T)
    d.gravity((0.0, 0.0, -9.81))
    d.torque("twist", "arm", (0.1, 0.2 * d.t, 0.3), frame="body")
    d.force("push", "rod", "end", (1.0, 0.0, d.t))
    return d


def moving_state(d: SpatialDescription):
    """The linkage turning about the hinge (3 rad/s, the lump with it), the arm spinning: the consistent state."""
    eom = spatial_equations(d)
    lump_rotation = WELD.T                                     # A_lump = A_rod C with A_rod = I
    lump = np.array([0.2, 0.0, -0.8]) - lump_rotation @ np.array([0.1, 0.1, 0.1])
    x, y, z, w = Rotation.from_matrix(lump_rotation).as_quat()
    omega = (3.0, 0.0, 0.0)
    q0, qd0 = initial_state(d, eom, {"rod": (0.0, 0.0, -0.5), "arm": (0.1, -0.1, -1.0), "lump": lump},
                            orientations={"lump": (w, x, y, z)},
                            angular_velocities={"rod": omega, "arm": (1.0, 2.0, -1.0), "lump": omega})
    return d, eom, q0, qd0


@pytest.fixture(scope="module")
def moving_linkage():
    return moving("linkage")


def slides():
    """The block on its prismatic guide (tests/test_spatial_joints.py) carrying a sleeve on a cylindrical joint along
    the block's own axis, under gravity, the block sliding and the sleeve spinning and sliding on it."""
    d = block()
    d.body("sleeve", 0.8, [[0.05, 0.01, 0.0], [0.01, 0.04, 0.0], [0.0, 0.0, 0.03]], points={"hub": (0.0, 0.1, 0.2)},
           axes={"bore": (0.0, 0.0, 1.0)})
    d.cylindrical("tube", ("sleeve", "hub", "bore"), ("block", "rail_end", "rail"))
    return d


def slides_start():
    _, _, q_block, qd_block = block_start()
    d = slides()
    eom = spatial_equations(d)
    rail = BLOCK_TURN @ np.array([0.0, 0.6, 0.8])
    turn = Rotation.align_vectors([rail], [[0.0, 0.0, 1.0]])[0]
    end = q_block[:3] + BLOCK_TURN @ np.array([0.1, 0.0, 0.3]) + 0.2 * rail
    x, y, z, w = turn.as_quat()
    q0, qd0 = initial_state(d, eom, {"block": q_block[:3], "sleeve": end - turn.apply([0.0, 0.1, 0.2])},
                            orientations={"block": q_block[3:7], "sleeve": (w, x, y, z)},
                            angular_velocities={"sleeve": 6.0 * rail},
                            velocities={"block": qd_block[:3], "sleeve": qd_block[:3] - 0.5 * rail})
    return d, eom, q0, qd0


def loaded_cardan_start():
    """The Cardan shaft (tests/test_spatial_joints.py) under gravity, driven by a torque of time on its input and
    braked by a body-frame torque on its output: unloaded, its joints carry no reaction at theta_1 = 0."""
    d = cardan()
    d.gravity((2.0, -3.0, -9.0))                                # tilted: every bearing and link row loaded
    d.torque("drive", "input", (2.0 + d.t, 0.0, 0.0))
    d.torque("brake", "output", (-1.0, 0.0, 0.0), frame="body")
    return cardan_start(d=d)


#: joint rows without a reaction at the mechanism's start, by its geometry (|lam| ~ 1e-16): exempt from the check
#: that every row is loaded
UNLOADED = {"linkage": {"weld_x"}}
#: mechanism -> its description, equations and moving consistent state; together every joint kind
MOVING = {"linkage": lambda: moving_state(linkage()), "slides": slides_start, "cardan": loaded_cardan_start}


@functools.cache
def moving(name: str):
    """MOVING[name]() built once in a test process: the linkage's derivation serves this file's every test."""
    return MOVING[name]()


@pytest.mark.parametrize("name", MOVING)
def test_initial_multipliers_and_accelerations_match_the_inhouse_solve(name):
    """Exudyn's initial-acceleration solve against the in-house saddle point [[M, J^T], [J, 0]], row by row (every
    joint kind's rows and, in the in-house convention, the norm rows). As for the planar models only Exudyn's
    numerically differentiated velocity term separates them (cross_validation.toml [reaction_velocity_term_relative],
    relative to the part gamma produces, here its largest entry: a row whose own gamma part is zero by coincidence
    still carries the difference; it grows as |qd|^2, 4.0 times at twice the velocities, and vanishes at rest)."""
    d, eom, q0, qd0 = moving(name)
    qdd, lam = Multiplier().solve(eom.mass(q0), eom.forces(0.0, q0, qd0), eom.phi_q(q0), eom.gamma(q0, qd0))
    qdd_g, lam_g = Multiplier().solve(eom.mass(q0), np.zeros(len(q0)), eom.phi_q(q0), eom.gamma(q0, qd0))
    r = run_spatial(d, eom, q0, qd0, 0.002, 1e-3)
    np.testing.assert_array_equal(r.q[0], q0)
    rel, vel = tol("reaction_zero_velocity_relative"), tol("reaction_velocity_term_relative")
    band = rel * np.abs(lam) + vel * np.abs(lam_g).max()
    joints = [k for k, n in enumerate(eom.constraint_names) if not n.endswith("_norm") and
              n not in UNLOADED.get(name, ())]
    assert np.all(2 * np.abs(lam[joints]) > band[joints])   # every joint row loaded: a wrong sign would show
    assert np.all(np.abs(r.lam[0] - lam) <= band), (r.lam[0], lam)
    assert np.abs(r.qdd[0] - qdd).max() <= rel * np.abs(qdd).max() + vel * np.abs(qdd_g).max()
    assert r.meta["constraint_names"] == list(eom.constraint_names) and r.stats["steps"] == 2
    # at rest the two solves are the same saddle point: only round-off separates them
    at_rest = np.zeros_like(qd0)
    qdd, lam = Multiplier().solve(eom.mass(q0), eom.forces(0.0, q0, at_rest), eom.phi_q(q0), eom.gamma(q0, at_rest))
    r = run_spatial(d, eom, q0, at_rest, 0.002, 1e-3)
    assert np.all(np.abs(r.lam[0] - lam) <= rel * np.abs(lam).max()), (r.lam[0], lam)
    assert np.abs(r.qdd[0] - qdd).max() <= rel * np.abs(qdd).max()


def test_the_explicit_solvers_and_unknown_solvers_are_refused(moving_linkage):
    d, eom, q0, qd0 = moving_linkage
    with pytest.raises(ExudynModelError, match="algebraic variables|constraints"):
        run_spatial(d, eom, q0, qd0, 0.002, 1e-3, solver="rk44")
    with pytest.raises(ValueError, match="unknown solver 'euler'"):
        run_spatial(d, eom, q0, qd0, 0.002, 1e-3, solver="euler")


def test_the_linkage_converges_to_the_reference_path_at_order_two(moving_linkage):
    """Over [spatial_linkage_horizon] at the steps h, h/2, h/4: Exudyn (index 3) against the in-house reference
    (DOP853 rtol 1e-12, projection) in q, qd and the joint multipliers: errors above the reference's floor, orders
    >= min_order; the energy balance (with the loads' work) closes at the same order."""
    d, eom, q0, qd0 = moving_linkage
    t_end, h = tolerance("spatial_linkage_horizon"), tolerance("spatial_linkage_step")
    ref = simulate(eom, q0, qd0, t_end=t_end, method="projection", integrator="DOP853",
                   rtol=tolerance("reference_rtol"), atol=tolerance("reference_atol"), output_step=t_end / 2)
    joints = [k for k, n in enumerate(eom.constraint_names) if not n.endswith("_norm")]
    steps, rows = [h, h / 2, h / 4], []
    for step in steps:
        r = run_spatial(d, eom, q0, qd0, t_end, step, output_step=t_end / 2)
        balance = r.energy_balance()
        rows.append({"dq": np.abs(r.q - ref.q).max(), "dqd": np.abs(r.qd - ref.qd).max(),
                     "dlam": np.abs(r.lam[:, joints] - ref.lam[:, joints]).max(),
                     "energy": np.abs(balance - balance[0]).max()})
    for key in rows[0]:
        errors = [row[key] for row in rows]
        assert min(errors) > tol("order_error_floor"), (key, errors)
        assert np.all(observed_orders(steps, errors) >= tol("min_order")), (key, errors)


@pytest.fixture(scope="module")
def top_runs():
    """The heavy top to t_end = 0.2 s in Exudyn at the steps of [exudyn_steps], with both implicit solvers."""
    d, eom, q0, qd0 = heavy_top_start()
    t_end = tolerance("t_end", TABLE)
    steps = values("exudyn_steps", TABLE)
    return steps, {solver: [run_spatial(d, eom, q0, qd0, t_end, h, solver=solver, output_step=t_end)
                            for h in steps] for solver in ("index3", "index2")}


@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_heavy_top_converges_to_the_independent_model_at_order_two(top_runs, solver):
    """Exudyn's Euler parameters at 0.2 s approach the independent model's at order >= min_order, and the Richardson
    extrapolation of the two finest runs lands on it within [spatial_exudyn_richardson] of the finest run's error
    (a limit other than the reference's would leave the extrapolation as far off as the runs)."""
    steps, runs = top_runs
    reference = np.array(values("independent", TABLE))
    p = np.array([r.q[-1, 3:] for r in runs[solver]])
    errors = np.abs(p - reference).max(axis=1)
    assert min(errors) > tol("order_error_floor"), errors
    assert np.all(observed_orders(steps, errors) >= tol("min_order")), errors
    extrapolated = p[-1] + (p[-1] - p[-2]) / ((steps[-2] / steps[-1]) ** 2 - 1)
    assert np.abs(extrapolated - reference).max() <= tolerance("spatial_exudyn_richardson") * errors[-1]
    if solver == "index3":
        assert max(np.abs(r.phi).max() for r in runs[solver]) <= tolerance("spatial_exudyn_phi")
