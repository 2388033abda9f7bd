"""Free bodies (placed by coordinates of their own) and spring-dampers between points, in both engines.

Independent references: a body hanging from a ground point on a spring-damper, released on the vertical through
it, moves as the linear damped oscillator m u'' + c u' + k u = 0 about y_e = -L0 - m g / k (solved by hand
below); a pendulum hung from a frame that floats on two spring-dampers has no closed form, and there Exudyn's
solvers, on a model generated from the same description, must converge to the in-house reference at their
order 2 (``min_order``), and the energy must balance with the dampers' work.
"""

from __future__ import annotations

import numpy as np
import pytest

import study
from study.reference_data import tolerance

M, J, K, C, L0, G = 2.0, 0.05, 400.0, 3.0, 0.5, 9.81
RTOL = 1e-10


def parameter_set(tmp_path, name: str, values: dict, q, qd, independent) -> study.ParameterSet:
    """A test mechanism's parameter file (values, printed q(0), qd(0), the independent coordinates' start), written
    to ``tmp_path`` and loaded."""
    lines = [f'[meta]\nmechanism = "{name}"\npaper = "none: a test mechanism"\ndescription = "test"\n']
    for k, v in values.items():
        lines.append(f'[parameters.{k}]\nvalue = {v!r}\nunit = "-"\nsource = "test"\nrule = "positive"\n'
                     f'doc = "{k}"\n')
    lines.append(f"[initial_conditions.printed]\nq = {list(map(float, q))}\nqd = {list(map(float, qd))}\n"
                 f'source = "test"\n')
    lines.append(f"[initial_conditions.consistent]\nindependent = {list(independent)}\n"
                 f"q_independent = {[float(q[i]) for i in independent]}\n"
                 f"qd_independent = {[float(qd[i]) for i in independent]}\n"
                 f'branch = "none"\nsource = "test"\n')
    lines.append('[variants.seed]\nnote = "test"\n')
    (tmp_path / f"{name}.toml").write_text("\n".join(lines))
    return study.load_parameters(name, reference_dir=tmp_path)


def hanging_mass(ps) -> study.Description:
    d = study.Description("hanging_mass", ["x", "y", "th"], {k: getattr(ps.values, k) for k in "mJkcLg"})
    p = d.p
    x, y, th = d.q
    d.ground("O", 0, 0)
    d.body("mass", p.m, p.J, {"c": (0, 0)}, angle=th, position=(x, y))
    d.spring_damper("hanger", (study.GROUND, "O"), ("mass", "c"), p.k, p.c, p.L)
    d.gravity(p.g)
    return d


def test_free_body_on_a_spring_damper_is_the_damped_oscillator(tmp_path):
    y0, v0 = -0.8, 0.3
    ps = parameter_set(tmp_path, "hanging_mass", dict(m=M, J=J, k=K, c=C, L=L0, g=G), [0.0, y0, 0.0], [0.0, v0, 0.0],
                     [0, 1, 2])
    mech = study.Mechanism(hanging_mass(ps), ps)
    assert mech.equations().n_constraints == 0
    r = study.simulate(mech, t_end=2.0, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=0.01)
    omega, zeta = np.sqrt(K / M), C / (2 * np.sqrt(K * M))
    wd = omega * np.sqrt(1 - zeta ** 2)
    u0 = y0 - (-L0 - M * G / K)
    u = np.exp(-zeta * omega * r.t) * (u0 * np.cos(wd * r.t) + (v0 + zeta * omega * u0) / wd * np.sin(wd * r.t))
    bound = tolerance("adaptive_global_error_factor") * RTOL
    assert np.abs(r.q[:, 1] - (u - L0 - M * G / K)).max() <= bound
    assert np.abs(r.q[:, [0, 2]]).max() == 0.0          # nothing pushes it off the vertical or turns it
    balance = r.energy_balance()                        # the damper's work is in it: the balance holds
    assert np.abs(balance - balance[0]).max() <= tolerance("energy_drift_factor") * RTOL * r.energies["kinetic"].max()
    assert r.energies["work_hanger_b"][-1] < 0          # the damper dissipates


def floating_frame(ps) -> study.Description:
    """A frame floating on two spring-dampers to ground, a pendulum pinned to it."""
    d = study.Description("floating_frame", ["x", "y", "phi", "th"], {k: getattr(ps.values, k) for k in
                                                                     ("mf", "Jf", "w", "k", "c", "L", "mp", "lp", "g")})
    p = d.p
    x, y, phi, th = d.q
    d.ground("A", -1, 1)
    d.ground("B", 1, 1)
    d.body("frame", p.mf, p.Jf, {"left": (-p.w / 2, 0), "right": (p.w / 2, 0), "pin": (0, 0)}, angle=phi,
           position=(x, y))
    d.body("pendulum", p.mp, p.mp * p.lp ** 2 / 12, {"top": (-p.lp / 2, 0)}, angle=th)
    d.revolute("pin", ("frame", "pin"), ("pendulum", "top"))
    d.spring_damper("left_mount", (study.GROUND, "A"), ("frame", "left"), p.k, p.c, p.L)
    d.spring_damper("right_mount", (study.GROUND, "B"), ("frame", "right"), p.k, p.c, p.L)
    d.gravity(p.g)
    return d


@pytest.fixture(scope="module")
def frame_validation(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("frame")
    values = dict(mf=3.0, Jf=0.2, w=1.0, k=300.0, c=2.0, L=0.5, mp=1.0, lp=0.6, g=G)
    ps = parameter_set(tmp, "floating_frame", values, [0.0, 0.3, 0.05, -1.0], [0.1, 0.0, 0.0, 2.0], [0, 1, 2, 3])
    mech = study.Mechanism(floating_frame(ps), ps)
    return mech, study.validate(mech, study.ValidationSettings(t_end=0.5), tmp / "report", say=lambda _: None)


def test_floating_frame_exudyn_converges_at_second_order(frame_validation):
    mech, tables = frame_validation
    assert mech.equations().n_constraints == 0      # the pendulum is placed from the free frame (a tree joint)
    orders = tables["exudyn_orders"]
    assert orders["above_error_floor"].all() and len(orders) == 4
    assert (orders["min_order"] >= tolerance("min_order", table="cross_validation")).all(), orders.to_string()


def test_floating_frame_energy_balances_with_the_dampers_work(frame_validation):
    mech, tables = frame_validation
    r = study.simulate(mech, t_end=0.5, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=0.01)
    balance = r.energy_balance()
    assert np.abs(balance - balance[0]).max() <= tolerance("energy_drift_factor") * RTOL * r.energies["kinetic"].max()
    assert min(r.energies[f"work_{m}_b"][-1] for m in ("left_mount", "right_mount")) < 0
    assert set(tables["reactions"]["reaction"]) == {"joint_pin_x", "joint_pin_y"}


def test_floating_frame_initial_accelerations_through_body_poses(frame_validation):
    """Exudyn's initial accelerations map back through every body's pose, pose'' = J qdd + dJ/dt qd
    (study.exudyn_models.kinematics.Kinematics.rates): the frame's own rows give x'', y'' directly, the pendulum's
    rows give them with its centripetal term dJ/dt qd (2 rad/s here), so an error in that term leaves the rows
    inconsistent and moves the least-squares x'', y''. Bounds as for every mechanism's initial solve
    (reference/cross_validation.toml: reaction_zero_velocity_relative, reaction_velocity_term_relative)."""
    from study.exudyn_models import initial_accelerations

    mech, _ = frame_validation
    s = mech.initial_state()

    def inhouse(qd):
        return study.simulate(mech, s.q, qd, 0.01, output_step=0.01, integrator="DOP853", rtol=RTOL,
                              atol=RTOL * 1e-2).qdd[0]

    qdd = inhouse(s.qd)
    qdd_v = qdd - inhouse(np.zeros_like(s.qd))   # the part of qdd the velocities produce (Exudyn's pin joint: gamma)
    qdd_x = initial_accelerations(mech, s.q, s.qd)[0]
    bound = (tolerance("reaction_zero_velocity_relative", table="cross_validation") * np.abs(qdd).max()
             + tolerance("reaction_velocity_term_relative", table="cross_validation") * np.abs(qdd_v).max())
    assert np.abs(qdd_x - qdd).max() <= bound, f"Exudyn {qdd_x}, in-house {qdd}"


def cartesian_pendulum_description(ps) -> study.Description:
    """A point mass on a massless rod in Cartesian coordinates: a free body that does not turn, a distance joint."""
    d = study.Description("cartesian_pendulum", ["x", "y"], {k: getattr(ps.values, k) for k in ("m", "L", "g")})
    p = d.p
    x, y = d.q
    d.ground("O", 0, 0)
    d.body("bob", p.m, p.m, {"c": (0, 0)}, angle=0, position=(x, y))   # the angle is no coordinate: J never enters
    d.distance("rod", (study.GROUND, "O"), ("bob", "c"), p.L)
    d.gravity(p.g)
    return d


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pendulum")
    ps = parameter_set(tmp, "cartesian_pendulum", dict(m=1.0, L=1.0, g=G), [0.6, -0.8], [0.8, 0.6], [0])
    return study.Mechanism(cartesian_pendulum_description(ps), ps)


def test_distance_joint_is_the_hand_written_cartesian_pendulum(pendulum):
    """The description's equations against tests/handwritten.py's Cartesian pendulum (Phi = (x^2 + y^2 - L^2)/2 there,
    |r| - L here, so its multiplier is L times ours): the same motion, and lam = the rod's tension."""
    from handwritten import cartesian_pendulum

    s = pendulum.initial_state()
    kw = dict(t_end=2.0, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=0.01, method="projection")
    ours, hand = study.simulate(pendulum, **kw), study.simulate(cartesian_pendulum(1.0, 1.0, G), s.q, s.qd, **kw)
    bound = 2 * tolerance("adaptive_global_error_factor") * RTOL
    assert np.abs(ours.q - hand.q).max() <= bound
    assert np.abs(ours.lam[:, 0] - hand.lam[:, 0]).max() <= bound * np.abs(hand.lam).max()
    speed2 = (ours.qd ** 2).sum(axis=1)   # tension = m v^2 / L + m g cos(angle from the downward vertical)
    assert np.allclose(study.joint_reactions(pendulum, ours)["joint_rod_tension"], speed2 - G * ours.q[:, 1],
                       rtol=0, atol=bound * 100)


def test_distance_joint_in_exudyn(pendulum, tmp_path):
    """Exudyn's DistanceConstraint from the same description: second order towards the in-house reference in q, qd;
    its force, read as the row's multiplier (the rod's tension), converges to the in-house tension at first order
    (generalized-alpha's multipliers; measured 1.00). A sign or scale error in the reading would leave an O(1)
    difference that does not shrink with h. The order band 1 +- 0.2 follows min_order's argument (the next error
    term within -13 % of the leading one) for a first-order quantity."""
    tables = study.validate(pendulum, study.ValidationSettings(t_end=0.5), tmp_path, say=lambda _: None)
    orders = tables["exudyn_orders"]
    assert len(orders) == 4 and orders["above_error_floor"].all()
    assert (orders["min_order"] >= tolerance("min_order", table="cross_validation")).all(), orders.to_string()
    reference = study.simulate(pendulum, t_end=0.5, output_step=0.01, integrator="DOP853", rtol=1e-12, atol=1e-14,
                               method="projection")
    inhouse = study.joint_reactions(pendulum, reference)["joint_rod_tension"]
    errors = [np.abs(study.exudyn_run(pendulum, 0.5, h, output_step=0.01).forces["joint_rod_tension"] - inhouse).max()
              for h in (1e-3, 5e-4)]
    assert 0.8 <= np.log2(errors[0] / errors[1]) <= 1.2, errors
