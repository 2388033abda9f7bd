"""The catalogue's friction_carriage (study/spatial/friction_carriage.py: friction in a prismatic guide and in a
revolute axle) in Exudyn against the in-house equations WITH the friction (study.spatial.friction: the axle's position
rows in body b's joint frame, ``axle_tx``, ``_ty``, ``_tz``; the friction a pin's generalized force, not part of
``eom.forces``), on both sides the regularized law of width [eps] (reference/spatial/friction_carriage.toml).

Tolerances: reference/cross_validation.toml (the t = 0 bands of tests/test_spatial_exudyn.py, min_order,
order_error_floor, index3_reaction_floor_relative) and reference/spatial/friction_carriage.toml, each with its
reason."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from study.compare import observed_orders
from study.exudyn_models.spatial import run_spatial
from study.mechanisms import named_mechanism
from study.reference_data import tolerance
from study.simulate import simulate
from study.solver.accelerations import Multiplier
from study.spatial import GROUND, SpatialDescription, initial_state, spatial_equations

CARRIAGE = "spatial/friction_carriage"
EPS = tolerance("eps", CARRIAGE)
#: joint rows without a reaction at the start, by the geometry: the guide's lock about its own axis, the axle's
#: thrust (the axle is horizontal, across the guide) and its two moment rows (the wheel is centred on its hub)
UNLOADED = {"guide_rx", "axle_tz", "axle_f", "axle_g"}


def tol(key: str) -> float:
    return tolerance(key, table="cross_validation")


@pytest.fixture(scope="module")
def carriage():
    m = named_mechanism("friction_carriage")
    state = m.initial_state()
    return m.description, m.equations(), state.q, state.qd


def inhouse(eom, q0, qd0, t_end: float, output_step: float):
    """The in-house regularized run at the reference tolerance."""
    return simulate(eom, q0, qd0, t_end=t_end, method="projection", integrator="DOP853",
                    rtol=tolerance("reference_rtol"), atol=tolerance("reference_atol"), output_step=output_step,
                    friction="regularized", friction_eps=EPS)


def initial_bands(eom, q0, qd0, ref):
    """The t = 0 bands of tests/test_spatial_exudyn.py around the in-house run ``ref``: reaction_zero_velocity_relative
    of each multiplier plus reaction_velocity_term_relative of the largest multiplier that gamma produces; the same
    for the accelerations (their largest entries)."""
    qdd_g, lam_g = Multiplier().solve(eom.mass(q0), np.zeros(len(q0)), eom.phi_q(q0), eom.gamma(q0, qd0))
    rel, vel = tol("reaction_zero_velocity_relative"), tol("reaction_velocity_term_relative")
    return (rel * np.abs(ref.lam[0]) + vel * np.abs(lam_g).max(),
            rel * np.abs(ref.qdd[0]).max() + vel * np.abs(qdd_g).max())


def test_initial_multipliers_with_joint_friction_match_the_inhouse_solve(carriage):
    """At t = 0, row by row (the axle's rows in body b's joint frame, both norm rows in the in-house convention) and
    in the accelerations, Exudyn's initial-acceleration solve against the in-house one with the same friction law
    (both joints sliding: the friction at the consistent reactions). The band is that of tests/test_spatial_exudyn.py
    (reaction_zero_velocity_relative, and reaction_velocity_term_relative of the part gamma produces). A global
    multiplier renamed instead of turned into the joint frame, a friction force missing or on the wrong side, or the
    friction's part of the norm rows left out falls outside it (the frictionless solve does)."""
    d, eom, q0, qd0 = carriage
    ref = inhouse(eom, q0, qd0, 0.002, 0.002)
    r = run_spatial(d, eom, q0, qd0, 0.002, 1e-3, eps=EPS)
    qdd_0, lam_0 = Multiplier().solve(eom.mass(q0), eom.forces(0.0, q0, qd0), eom.phi_q(q0), eom.gamma(q0, qd0))
    band, qdd_band = initial_bands(eom, q0, qd0, ref)
    lam = ref.lam[0]
    loaded = [k for k, n in enumerate(eom.constraint_names) if not n.endswith("_norm") and n not in UNLOADED]
    assert np.all(2 * np.abs(lam[loaded]) > band[loaded])    # every loaded row: a wrong sign or frame would show
    assert np.all(np.abs(r.lam[0] - lam) <= band), (r.lam[0], lam)
    assert np.any(np.abs(r.lam[0] - lam_0) > band)          # the friction shows: the frictionless solve is outside
    assert np.abs(r.qdd[0] - ref.qdd[0]).max() <= qdd_band < np.abs(r.qdd[0] - qdd_0).max()
    for key in ("normal_guide", "friction_guide", "normal_axle", "friction_axle"):
        assert abs(r.forces[key][0] - ref.forces[key][0]) <= max(band), key


@pytest.mark.parametrize("ground_first", [False, True], ids=["ground_as_body_b", "ground_as_body_a"])
def test_a_pin_to_ground_maps_its_joint_frame_rows_either_way_round(ground_first):
    """A wheel on a revolute joint with friction to ground (axle horizontal along no global axis, a thrust along it,
    turning at 20 rad/s), ground as the joint's body b or its body a: the rows' frame is then ground's or the
    wheel's, and Exudyn's global multipliers turn into it from the wheel's centre's gradient (body a) or minus it
    (body b). At t = 0 every row and the friction torque match the in-house solve within the bands above."""
    axle = np.array([np.cos(0.5), np.sin(0.5), 0.0])
    hub = np.array([0.1, 0.2, 0.3])
    d = SpatialDescription("friction_wheel")
    d.body("wheel", 2.0, (0.04, 0.04, 0.05), points={"hub": (0.0, 0.0, 0.0)}, axes={"axle": (0, 0, 1)})
    pair = [("wheel", "hub", "axle"), (GROUND, tuple(hub), tuple(axle))]
    d.revolute("bearing", *(pair[::-1] if ground_first else pair))
    d.gravity((0.0, 0.0, -9.81))
    d.force("thrust", "wheel", "hub", tuple(30.0 * axle))
    d.friction("bearing", 0.3, 0.2, radius=0.05)
    eom = spatial_equations(d)
    x, y, z, w = Rotation.align_vectors([axle], [[0.0, 0.0, 1.0]])[0].as_quat()
    q0, qd0 = initial_state(d, eom, {"wheel": hub}, orientations={"wheel": (w, x, y, z)},
                            angular_velocities={"wheel": 20.0 * axle})
    ref = inhouse(eom, q0, qd0, 0.002, 0.002)
    r = run_spatial(d, eom, q0, qd0, 0.002, 1e-3, eps=EPS)
    band, qdd_band = initial_bands(eom, q0, qd0, ref)
    assert np.all(np.abs(r.lam[0] - ref.lam[0]) <= band), (r.lam[0], ref.lam[0])
    assert np.abs(r.qdd[0] - ref.qdd[0]).max() <= qdd_band
    assert abs(r.forces["friction_bearing"][0] - ref.forces["friction_bearing"][0]) <= max(band)
    assert np.abs(ref.lam[0, :3]).max() > 10.0       # the position rows carry the weight and the thrust


@pytest.fixture(scope="module")
def reference(carriage):
    _, eom, q0, qd0 = carriage
    t_end = tolerance("test_horizon", CARRIAGE)
    return inhouse(eom, q0, qd0, t_end, t_end / 4)


def errors(r, ref) -> dict[str, float]:
    """max|Exudyn - in-house| of each compared quantity on the common samples; Exudyn's own energy balance error."""
    joints = [k for k, n in enumerate(ref.meta["constraint_names"]) if not n.endswith("_norm")]
    out = {"q": np.abs(r.q - ref.q).max(), "qd": np.abs(r.qd - ref.qd).max(),
           "lam": np.abs(r.lam[:, joints] - ref.lam[:, joints]).max()}
    out.update({k: np.abs(r.forces[k] - ref.forces[k]).max() for k in
                ("friction_guide", "normal_axle", "friction_axle", "normal_guide")})
    out.update({k: np.abs(r.energies[k] - ref.energies[k]).max() for k in
                ("work_friction_guide", "work_friction_axle")})
    balance = r.energy_balance()
    out["energy"] = np.abs(balance - balance[0]).max()
    return out


@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_the_regularized_carriage_converges_to_the_inhouse_run_at_order_two(carriage, reference, solver):
    """Over [test_horizon] (the climb, the reversal through the band, sliding back) at h, h/2, h/4: q, qd, the joint
    rows' multipliers, the friction forces, the axle's normal force, both frictions' work and Exudyn's own energy
    balance (with the friction's work) converge at order >= min_order, every error above order_error_floor. The
    guide's normal force is the weight across the guide throughout (constant): no discretization error, so it
    stays within index3_reaction_floor_relative of itself at every step."""
    d, eom, q0, qd0 = carriage
    t_end, h = tolerance("test_horizon", CARRIAGE), tolerance("test_step", CARRIAGE)
    steps = [h, h / 2, h / 4]
    rows = [errors(run_spatial(d, eom, q0, qd0, t_end, step, solver=solver, output_step=t_end / 4, eps=EPS),
                   reference) for step in steps]
    normal = np.abs(reference.forces["normal_guide"]).max()
    assert max(row.pop("normal_guide") for row in rows) <= tol("index3_reaction_floor_relative") * normal
    for key in rows[0]:
        e = [row[key] for row in rows]
        assert min(e) > tol("order_error_floor"), (key, e)
        assert np.all(observed_orders(steps, e) >= tol("min_order")), (key, e)
