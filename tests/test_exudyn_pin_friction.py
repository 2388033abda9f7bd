"""Coulomb friction in revolute joints in the Exudyn models, against the in-house reference path.

The Exudyn model of a pin with friction (study.exudyn_models.guards.PinFrictionTorque) applies the regularized torque
tau = -(mu_k r sqrt(|R|^2 + delta^2) + T0) tanh(omega_rel/eps) on the joint's body a and -tau on its body b, |R|
read from Exudyn's own joint reaction through the ReactionGuard. On models generated from the same descriptions,
it must converge to the in-house reference path (DOP853 at reference_rtol with projection, friction='regularized',
the same eps) at h, h/2, h/4 with the observed order of its solvers (min_order, reference/cross_validation.toml):

* the pendulum of tests/test_revolute_friction.py (a bar on a ground pin with friction mu r = 0.03 m and T0 =
  0.05 N m, so mu r |R| + T0 = 0.3 ... 0.8 N m against m g l / 10 = 0.59 N m): body a is ground, the torque acts
  on the bar alone;
* its double pendulum with friction in both pins: the shoulder (ground to the upper bar) and the elbow (between
  the two moving bars, equal and opposite torques).

Both runs start slipping and stay so over their horizon: |omega_rel| >= 1.8 rad/s >> eps, where tanh is +-1 to
round-off and the law is smooth along the motion, so the steps are in the asymptotic range. Released from rest, the
band |omega_rel| < eps at t = 0 is crossed in ~eps/|th''| = 6e-5 s, inside the first step of every h: that leaves
an O(h) error (measured on the pendulum from rest at 60 deg, index 2: orders 1.02, 1.11 in q), hence the starts
below. The energy balance E(t) - E(0) = sum of the pins' work (the pair's power tau omega_rel integrated) holds
for the exact motion; for Exudyn's it closes at the solvers' order: its residual is a global O(h^2) error (the
integrator's energy error and the trapezoidal work quadrature, study.exudyn_models.solve.WORK_NOTE), so the
residual must fall at the observed order min_order from h to h/4, above the accuracy floor like every error.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import study
from study.compare import observed_orders
from study.reference_data import tolerance
from test_free_bodies import parameter_set
from test_revolute_friction import DOUBLE, describe_double, double_state, pendulum

pytest.importorskip("exudyn")

EPS = tolerance("friction_eps", table="cross_validation")
STEPS = [2e-3, 1e-3, 5e-4]
OUTPUT_STEP = 0.01
#: Index 3's multipliers carry an O(h) start-up transient (generalized-alpha at position level), as on the moving
#: guide (tests/test_moving_guide_friction.py): the pendulum's frictionless |R| has orders 1.09, 1.00 over 0.5 s and
#: 7.1, 2.00 after 0.1 s; the friction torque, which follows |R|, inherits it (measured orders: pendulum 1.09, 1.00;
#: double pendulum 1.16, 1.05 shoulder, 1.18, 1.07 elbow). So index 3 is held to order 2 in q and qd, index 2
#: (velocity-level constraints) in the friction torques and reactions as well.
QUANTITIES = {"index2": ("q", "qd", "friction", "normal"), "index3": ("q", "qd")}

# The cases: (mechanism builder, horizon [s], pins). The pendulum from 60 deg at th' = -1 rad/s swings through the
# bottom, th' from -1 to -4.1 rad/s, no reversal within 0.5 s. The double pendulum (DOUBLE) from (0.8, -0.3) rad at
# (-2, 6) rad/s: omega_rel of the shoulder between 2 and 4.6 rad/s, of the elbow between -14.4 and -1.8 rad/s within
# 0.3 s (first reversals at 0.345 s, elbow, and 0.485 s, shoulder).
T_PENDULUM, T_DOUBLE = 0.5, 0.3


def double_mechanism(tmp_path) -> study.Mechanism:
    q, qd = double_state(DOUBLE, 0.8, -0.3, -2.0, 6.0, shoulder_friction=True)
    ps = parameter_set(tmp_path, "pin_friction_double", DOUBLE, q, qd, [0, 1])
    return study.Mechanism(describe_double({k: getattr(ps.values, k) for k in DOUBLE}, shoulder_friction=True), ps)


CASES = {
    "pendulum": (lambda tmp: pendulum(tmp, math.pi / 3, -1.0), T_PENDULUM, ("pin",)),
    "double": (double_mechanism, T_DOUBLE, ("shoulder", "elbow")),
}


def reference(mech, t_end: float, **law) -> study.SimulationResult:
    return study.simulate(mech, t_end=t_end, method="projection", integrator="DOP853", rtol=tolerance("reference_rtol"),
                          atol=tolerance("reference_atol"), output_step=OUTPUT_STEP, backend="reference", **law)


def balance_residual(r: study.SimulationResult, pins) -> np.ndarray:
    e = r.energies
    change = e["kinetic"] + e["potential"] - e["kinetic"][0] - e["potential"][0]
    return change - sum(e[f"work_friction_{p}"] - e[f"work_friction_{p}"][0] for p in pins)


def assert_orders(errors: dict[str, list[float]]) -> None:
    """Every error above the accuracy floor, every observed order over STEPS >= min_order."""
    low, floor = (tolerance(key, table="cross_validation") for key in ("min_order", "order_error_floor"))
    for key, e in errors.items():
        p = observed_orders(STEPS, e)
        print(f"{key}: errors {', '.join(f'{x:.3g}' for x in e)}; observed orders {', '.join(f'{x:.3f}' for x in p)}")
        assert min(e) > floor, f"{key}: errors {e} reach the accuracy floor {floor}"
        assert np.all(p >= low), f"{key}: errors {e}, observed orders {p} (min_order {low})"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Per case: the mechanism, its in-house reference and Exudyn's runs {solver: [result at each of STEPS]}."""
    out = {}
    for name, (make, t_end, pins) in CASES.items():
        mech = make(tmp_path_factory.mktemp(name))
        ref = reference(mech, t_end, friction="regularized", friction_eps=EPS, friction_sgn="tanh")
        exudyn = {solver: [study.exudyn_run(mech, t_end, h, solver=solver, output_step=OUTPUT_STEP,
                                            friction="regularized", eps=EPS) for h in STEPS]
                  for solver in QUANTITIES}
        out[name] = (mech, t_end, pins, ref, exudyn)
    return out


@pytest.mark.parametrize("name", CASES)
def test_the_pins_slip_throughout_and_friction_shapes_the_motion(runs, name):
    """The premise of the order tests: every pin slips (|omega_rel| > 100 eps, the law smooth along the motion) and
    dissipates a sizeable share of the motion's energy (over a quarter of the largest kinetic energy), so a missing,
    lagging or mis-signed torque shows far above the discretization errors."""
    mech, _, pins, ref, _ = runs[name]
    eom = mech.equations()
    for p in pins:
        pin = next(x for x in eom.pin_frictions if x.name == p)
        omega = np.array([np.asarray(pin.rate_jacobian(q), dtype=float) @ qd for q, qd in zip(ref.q, ref.qd)])
        assert np.abs(omega).min() > 100 * EPS, (p, np.abs(omega).min())
    dissipated = -sum(ref.energies[f"work_friction_{p}"][-1] for p in pins)
    print(f"{name}: dissipated {dissipated:.4g} J, max kinetic energy {ref.energies['kinetic'].max():.4g} J")
    assert dissipated > 0.25 * ref.energies["kinetic"].max()


@pytest.mark.parametrize("solver", QUANTITIES)
@pytest.mark.parametrize("name", CASES)
def test_exudyn_pin_friction_converges_at_order_two(runs, name, solver):
    """q, qd (and with index 2 every pin's friction torque tau and reaction |R|) converge to the in-house reference
    at h, h/2, h/4; the guard replaced the zero first Newton iterate of the reaction at every step."""
    _, _, pins, ref, exudyn = runs[name]
    errors: dict[str, list[float]] = {}
    for x in exudyn[solver]:
        assert np.abs(x.t - ref.t).max() <= 1e-12   # the same output grid (multiples of 0.01 s, up to round-off)
        assert x.stats["friction_guard_substitutions"] >= x.stats["steps"]
        for key in QUANTITIES[solver]:
            if key in ("q", "qd"):
                errors.setdefault(key, []).append(float(np.abs(getattr(x, key) - getattr(ref, key)).max()))
                continue
            for p in pins:
                k = f"{key}_{p}"
                errors.setdefault(k, []).append(float(np.abs(x.forces[k] - ref.forces[k]).max()))
    assert_orders(errors)


@pytest.mark.parametrize("solver", QUANTITIES)
@pytest.mark.parametrize("name", CASES)
def test_exudyn_energy_balance_closes_at_order_two(runs, name, solver):
    """E(t) - E(0) - sum of the pins' friction work: zero for the exact motion, Exudyn's global O(h^2) error for its
    own (module docstring); the in-house reference's residual (measured 6e-12 J, 2e-12 J) is far below every Exudyn
    residual."""
    _, _, pins, ref, exudyn = runs[name]
    residual = [float(np.abs(balance_residual(x, pins)).max()) for x in exudyn[solver]]
    print(f"{name} {solver}: reference residual {np.abs(balance_residual(ref, pins)).max():.3g} J")
    assert_orders({"energy balance residual": residual})


@pytest.mark.parametrize("name", CASES)
def test_seeded_initial_accelerations_carry_the_pin_friction(runs, name):
    """At t = 0 Exudyn sees zero multipliers, so the pins' friction needs the seeded |R|
    (study.exudyn_models.guards.seed_reaction_guards). Its initial-acceleration solve must then give the in-house
    qdd and lam at the initial state (the reference's first sample), within the bounds of the frictionless initial
    solves (tests/cross_validation/test_exudyn_models.py): round-off of the saddle-point solve
    (reaction_zero_velocity_relative) plus Exudyn's numerically differentiated velocity term
    (reaction_velocity_term_relative of the part gamma produces; through |R| it moves the friction torque by mu r
    times that, 0.03 of it here). Unseeded, the friction would be missing: it changes qdd by 1.0 (pendulum) and
    1.8 rad/s^2 (double pendulum), 1e6 times the bound. Measured: at most 0.17 of the bound."""
    from study.exudyn_models import initial_accelerations
    from study.solver.accelerations import Multiplier

    mech, _, _, ref, _ = runs[name]
    eom, s = mech.equations(), mech.initial_state()
    qdd_x, lam_x = initial_accelerations(mech, s.q, s.qd, eps=EPS)
    qdd_g, lam_g = Multiplier().solve(eom.mass(s.q), np.zeros(eom.n_coordinates), eom.phi_q(s.q),
                                      eom.gamma(s.q, s.qd))
    rel, vel = (tolerance(k, table="cross_validation") for k in ("reaction_zero_velocity_relative",
                                                                 "reaction_velocity_term_relative"))
    qdd, lam = ref.qdd[0], ref.lam[0]
    assert np.all(np.abs(lam_x - lam) <= rel * np.abs(lam) + vel * np.abs(lam_g)), f"Exudyn {lam_x}, in-house {lam}"
    bound = rel * np.abs(qdd).max() + vel * np.abs(qdd_g).max()
    assert np.abs(qdd_x - qdd).max() <= bound, f"Exudyn {qdd_x}, in-house {qdd}, bound {bound}"


def test_friction_none_leaves_the_pin_torque_out(runs):
    """friction='none': no torque, no work, and the frictionless motion of the in-house reference at order 2."""
    mech, t_end, _, _, _ = runs["pendulum"]
    ref = reference(mech, t_end, friction="none")
    errors: dict[str, list[float]] = {"q": [], "qd": []}
    for h in STEPS:
        x = study.exudyn_run(mech, t_end, h, solver="index2", output_step=OUTPUT_STEP, friction="none", eps=EPS)
        assert not np.any(x.forces["friction_pin"]) and not np.any(x.energies["work_friction_pin"])
        errors["q"].append(float(np.abs(x.q - ref.q).max()))
        errors["qd"].append(float(np.abs(x.qd - ref.qd).max()))
    assert_orders(errors)


@pytest.mark.parametrize("mode", ["exact", "sign"])
def test_exact_and_sign_are_not_exudyn_modes(runs, mode):
    mech = runs["pendulum"][0]
    with pytest.raises(ValueError, match=rf"unknown friction mode '{mode}'; valid choices: regularized, none"):
        study.exudyn_run(mech, 0.01, 1e-3, friction=mode)
