"""Coulomb friction in revolute joints on the compiled backend agrees with the reference backend and the hand models.

The mechanisms are tests/test_revolute_friction.py's: a pendulum on a ground pin with friction (its hand model in the
minimal coordinate th) and a double pendulum whose elbow, a pin between two moving bars, has friction. For 'exact'
the hand model (test_revolute_friction.hand_exact) is the pendulum's with sgn(th') replaced by the frozen sliding
direction between located stops:

    (Ic + m l^2) th'' = -m g l sin th + (mu r |R|_delta + T0) e_dir      (slip; e_dir = sgn(omega), omega = -th')

and at each stop (th' = 0) the pin sticks if the torque that holds it, m g l sin th, is within its static capacity
mu_s r |R|_delta + T0 with R = (0, m g) (a_G = 0 at rest), else it slides on where gravity turns it.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import study
from study.reference_data import tolerance
from test_revolute_friction import (DELTA, DOUBLE, EPS, OUTPUT_STEP, RTOL, START, T_END, VALUES, describe,
                                    describe_double, double_state, full_state, hand_accel, hand_exact, parameter_set,
                                    pendulum)

IO = VALUES["Ic"] + VALUES["m"] * VALUES["l"] ** 2                  # the pendulum's inertia about the pin
MGL = VALUES["m"] * VALUES["g"] * VALUES["l"]
EXACT_T_END = 4.5          # the pendulum released at 1 rad stops for good at ~3.55 s (test_revolute_friction.hand_exact)
EXACT_RTOL = 1e-10


@pytest.fixture(scope="module")
def mechanisms(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pins")
    ps = parameter_set(folder, "pin_friction_double", DOUBLE, *double_state(DOUBLE, 0.8, -0.3, 0.0, 4.0), independent=[0, 1])
    return {"pendulum": pendulum(folder, *START), "elbow": study.Mechanism(describe_double(DOUBLE), ps)}


def _setup(mech, friction):
    """The compiled run's setup (kernels, options and the reference dynamics) at the mechanism's test state."""
    from study.fast import frontend   # here, not at collection: importing it compiles the kernels (cold cache)

    q, qd = full_state(*START) if mech.name == "pin_friction_pendulum" else double_state(DOUBLE, 0.8, -0.3, 0.0, 4.0)
    return frontend.setup(mech.equations(), mech, q, qd, "none", friction, EPS, "tanh")


def _states(name, rng):
    """Pendulum: th in [-1, 1], th' in [-3, 3] and at rest; elbow: both bars moving (off the velocity constraint
    too: the evaluation is defined there, and the stabilization is none)."""
    if name == "pendulum":
        return [full_state(th, w) for th, w in zip(rng.uniform(-1, 1, 4), [*rng.uniform(-3, 3, 3), 0.0])]
    out = []
    for a1, a2, w2 in zip(rng.uniform(-1, 1, 4), rng.uniform(-1, 1, 4), rng.uniform(-5, 5, 4)):
        q, qd = double_state(DOUBLE, a1, a2, 0.0, w2)
        out.append((q, qd + 0.3 * rng.standard_normal(4)))
    return out


def _relative(a, b):
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


@pytest.mark.parametrize("name", ["pendulum", "elbow"])
@pytest.mark.parametrize("friction", ["regularized", "sign"])
def test_evaluation_matches_reference(mechanisms, name, friction):
    """Same Newton iteration on the same equations: accelerations, multipliers, |R| and torques to round-off."""
    from study.fast import frontend

    mech = mechanisms[name]
    s = _setup(mech, friction)
    eom = mech.equations()
    m, r = eom.n_coordinates, eom.n_constraints
    worst = 0.0
    for k, (q, qd) in enumerate(_states(name, np.random.default_rng(11))):
        sol = s.dyn.contact_solution(0.1 * k, q, qd)
        out = frontend.accelerations(s, 0.1 * k, q, qd)
        for got, want in ((out[:m], sol.qdd), (out[m:m + r], sol.lam), (out[m + r:m + r + 1], sol.normal),
                          (out[m + r + 1:], sol.friction)):
            worst = max(worst, _relative(got, want))
    print(f"{name} {friction}: worst relative deviation {worst:.3g}")
    assert worst <= tolerance("round_off")


def _run(mech, backend, **options):
    return study.simulate(mech, backend=backend, output_step=OUTPUT_STEP, **options)


def _regularized(name, mech, backend):
    extra = {} if name == "pendulum" else dict(zip(("q0", "qd0"), double_state(DOUBLE, 0.8, -0.3, 0.0, 4.0)))
    return _run(mech, backend, t_end=T_END if name == "pendulum" else 1.0, integrator="DOP853", rtol=RTOL,
                atol=RTOL * 1e-2, friction="regularized", friction_eps=EPS, friction_sgn="tanh", **extra)


@pytest.mark.parametrize("name", ["pendulum", "elbow"])
def test_regularized_run_matches_reference(mechanisms, name):
    """Both backends take scipy's DOP853 steps at rtol 1e-9, each within adaptive_global_error_factor * rtol of the
    exact solution: states, the pin's |R| and torque, and its work agree to that bound."""
    mech = mechanisms[name]
    fast, ref = _regularized(name, mech, "compiled"), _regularized(name, mech, "reference")
    assert fast.meta["backend"] == "compiled" and np.array_equal(fast.t, ref.t)
    pin = "pin" if name == "pendulum" else "elbow"
    bound = tolerance("adaptive_global_error_factor") * RTOL
    devs = {"q": (fast.q, ref.q), "qd": (fast.qd, ref.qd), "normal": (fast.forces[f"normal_{pin}"],
            ref.forces[f"normal_{pin}"]), "friction": (fast.forces[f"friction_{pin}"], ref.forces[f"friction_{pin}"])}
    for key, (a, b) in devs.items():
        dev = np.abs(a - b).max()
        print(f"{name} regularized {key}: max dev {dev:.3g} (bound {bound * max(1.0, np.abs(b).max()):.3g})")
        assert dev <= bound * max(1.0, np.abs(b).max()), key
    e = ref.energies
    work = np.abs(fast.energies[f"work_friction_{pin}"] - e[f"work_friction_{pin}"]).max()
    assert work <= tolerance("energy_drift_factor") * RTOL * e["kinetic"].max()
    assert e[f"work_friction_{pin}"][-1] < -0.05     # the pin did dissipate


@pytest.mark.parametrize("name", ["pendulum", "elbow"])
def test_sign_with_rk4_matches_reference(mechanisms, name):
    """The plain sgn at every RK4 stage, same fixed steps on both backends: only round-off differs."""
    mech = mechanisms[name]
    extra = {} if name == "pendulum" else dict(zip(("q0", "qd0"), double_state(DOUBLE, 0.8, -0.3, 0.0, 4.0)))
    runs = [_run(mech, b, t_end=1.0, integrator="RK4", step=1e-3, friction="sign", **extra)
            for b in ("compiled", "reference")]
    dev = np.abs(runs[0].q - runs[1].q).max()
    print(f"{name} sign/RK4: max |dq| {dev:.3g}")
    assert dev <= tolerance("fast_fixed_step_agreement") * np.abs(runs[1].q).max()


def test_scipy_integrator_on_compiled_evaluations_matches_reference(mechanisms):
    """LSODA takes scipy's steps on the compiled right-hand side (its work block ends with the pin's power)."""
    mech = mechanisms["pendulum"]
    kw = dict(t_end=0.5, integrator="LSODA", rtol=RTOL, atol=RTOL * 1e-2, friction="regularized", friction_eps=EPS)
    fast, ref = _run(mech, "compiled", **kw), _run(mech, "reference", **kw)
    assert fast.meta["backend"] == "compiled"
    bound = tolerance("adaptive_global_error_factor") * RTOL
    assert np.abs(fast.q - ref.q).max() <= bound * max(1.0, np.abs(ref.q).max())
    assert np.abs(fast.energies["work_friction_pin"] - ref.energies["work_friction_pin"]).max() <= \
        tolerance("energy_drift_factor") * RTOL * ref.energies["kinetic"].max()


# --- exact ---------------------------------------------------------------------------------------------------
def _exact_setup(mech):
    """The compiled options of the exact treatment for the pendulum (the kernels and the law's compiled phases; no
    reference dynamics of the exact treatment is needed to evaluate one mode)."""
    from study.fast import frontend
    from study.solver.friction import ExactCoulomb

    s = _setup(mech, "regularized")
    ci, cf = frontend.pack_options(s.dyn.eom, s.dyn.stabilization, ExactCoulomb(), len(s.dyn.work_names), 0,
                                   frontend.pin_numbers(s.dyn))
    return dataclasses.replace(s, ci=ci, cf=cf, phases=ExactCoulomb.compiled_phases)


@pytest.mark.parametrize("w", [-2.0, 0.0, 1.5])
@pytest.mark.parametrize("direction", [1, -1])
def test_exact_sliding_pin_is_the_hand_model_with_the_frozen_direction(mechanisms, w, direction):
    """Slip in the frozen direction e_dir (whatever the velocity): the torque on the bar is +level e_dir, the hand
    model with s(th') = -e_dir. The hand Newton iterates to 1e-15, the compiled one stops at |F| <=
    pin_friction_solve_rtol * level: th'' and |R| agree to round_off."""
    from study.fast import frontend

    s = _exact_setup(mechanisms["pendulum"])
    th = 0.4
    q, qd = full_state(th, w)
    out = frontend.accelerations(s, 0.0, q, qd, (-1, direction))
    a, R = hand_accel(th, w, float(-direction))
    level = VALUES["mu"] * VALUES["r"] * math.sqrt(R[0] ** 2 + R[1] ** 2 + DELTA ** 2) + VALUES["T0"]
    assert abs(out[0] - a) <= tolerance("round_off") * abs(a)
    assert abs(out[5] - math.hypot(*R)) <= tolerance("round_off") * math.hypot(*R)
    assert abs(out[6] - (-level * direction)) <= tolerance("round_off") * level   # tau on the ground (body a)


@pytest.mark.parametrize("th", [0.3, -0.05])
def test_exact_stuck_pin_holds_the_bar(mechanisms, th):
    """Stuck at rest: th'' = 0 (omega' = 0), the pin's torque on the ground is -m g l sin th (it holds the bar
    against gravity) and R = (0, m g); th'' is compared with round_off of the gravity term m g l / I_O."""
    from study.fast import frontend

    s = _exact_setup(mechanisms["pendulum"])
    q, qd = full_state(th, 0.0)
    out = frontend.accelerations(s, 0.0, q, qd, (1, 1))
    assert abs(out[0]) <= tolerance("round_off") * MGL / IO
    assert abs(out[5] - VALUES["m"] * VALUES["g"]) <= tolerance("round_off") * VALUES["m"] * VALUES["g"]
    assert abs(out[6] - (-MGL * math.sin(th))) <= tolerance("round_off") * MGL


@pytest.fixture(scope="module")
def exact_compiled(mechanisms):
    return _run(mechanisms["pendulum"], "compiled", t_end=EXACT_T_END, integrator="DOP853", rtol=EXACT_RTOL,
                atol=EXACT_RTOL * 1e-2, friction="exact")


def test_exact_compiled_run_sticks_where_the_hand_model_does(exact_compiled):
    """Released at 1 rad the pendulum reverses at four stops (gravity beats the static capacity) and sticks at the
    fifth. Stop times agree with the hand model within the trajectories' difference (adaptive_global_error_factor *
    rtol * |th|) divided by |th''| there; once stuck, th' stays 0, the margin stays >= 0, and the energy balance
    closes: E(t) - E(0) = the pin's work (energy_drift_factor * rtol * kinetic energy)."""
    r = exact_compiled
    stops, theta = hand_exact(EXACT_T_END)
    assert [st for *_, st in stops] == [False] * 4 + [True]
    assert r.stats["events"] == len(stops)
    scale = tolerance("adaptive_global_error_factor") * EXACT_RTOL * max(1.0, np.abs(r.q[:, 0]).max())
    for t_got, (t_hand, _, rate, _) in zip(r.stats["event_times"], stops):
        assert abs(t_got - t_hand) <= scale / abs(rate), (t_got, t_hand)
    assert np.abs(r.q[:, 0] - theta(r.t)).max() <= scale
    t_stick = stops[-1][0]
    stuck = r.t > t_stick
    assert np.all(r.forces["stick_pin"][stuck] == 1) and np.all(r.forces["stick_pin"][~stuck] == 0)
    assert np.abs(r.qd[stuck, 0]).max() <= scale
    capacity = VALUES["mu"] * VALUES["r"] * np.sqrt(r.forces["normal_pin"] ** 2 + DELTA ** 2) + VALUES["T0"]
    margin = capacity - np.abs(r.forces["friction_pin"])
    assert margin[stuck].min() >= 0
    e = r.energies
    change = e["kinetic"] + e["potential"] - e["kinetic"][0] - e["potential"][0]
    residual = np.abs(change - e["work_friction_pin"]).max()
    print(f"exact compiled: stick at {r.stats['event_times'][-1]:.9f} s (hand {t_stick:.9f}), margin while stuck "
          f"{margin[stuck].min():.4g} N m, energy residual {residual:.3g} J")
    assert residual <= tolerance("energy_drift_factor") * EXACT_RTOL * e["kinetic"].max()


def test_exact_compiled_run_matches_reference(mechanisms, exact_compiled):
    """The same stops (decided by the reference's switching rule on both backends), located within
    fast_event_time_agreement, and the same trajectory within adaptive_global_error_factor * rtol."""
    fast = exact_compiled
    ref = _run(mechanisms["pendulum"], "reference", t_end=EXACT_T_END, integrator="DOP853", rtol=EXACT_RTOL,
               atol=EXACT_RTOL * 1e-2, friction="exact")
    assert fast.stats["events"] == ref.stats["events"] > 0
    dt = np.abs(np.array(fast.stats["event_times"]) - np.array(ref.stats["event_times"])).max()
    assert dt <= tolerance("fast_event_time_agreement")
    bound = tolerance("adaptive_global_error_factor") * EXACT_RTOL
    assert np.array_equal(fast.t, ref.t)
    assert np.abs(fast.q - ref.q).max() <= bound * max(1.0, np.abs(ref.q).max())
    assert np.array_equal(fast.forces["stick_pin"], ref.forces["stick_pin"])


# --- failures, refusals, cache key ---------------------------------------------------------------------------
def test_unconverged_torque_solve_raises_the_reference_error(tmp_path):
    """mu r = 3 m against the pendulum's unit-torque reaction dR/dtau ~ m l / I_O = 2 per m: the torque equation
    has no solution Newton can reach. Both the compiled evaluation and a compiled run raise the reference's
    PinFrictionError naming the joint, the time and the state of the failing evaluation."""
    from study.fast import frontend
    from study.solver.friction import PinFrictionError

    ps = parameter_set(tmp_path, "pin_friction_pendulum", dict(VALUES, mu=3.0, r=1.0), *full_state(*START),
                       independent=[0])
    mech = study.Mechanism(describe(ps), ps)
    s = _setup(mech, "regularized")
    q, qd = full_state(0.3, -2.0)
    with pytest.raises(PinFrictionError) as ref_error:
        s.dyn.contact_solution(0.25, q, qd)
    with pytest.raises(PinFrictionError) as fast_error:
        frontend.accelerations(s, 0.25, q, qd)
    assert str(fast_error.value) == str(ref_error.value) and fast_error.value.joints == ("pin",)
    with pytest.raises(PinFrictionError, match=r"the friction torques of revolute joint\(s\) 'pin' did not converge") \
            as run_error:
        study.simulate(mech, t_end=0.5, backend="compiled", friction="regularized")
    assert 0.0 < run_error.value.t < 0.5 and f"t = {run_error.value.t:.9g} s" in str(run_error.value)
    assert run_error.value.q.shape == (3,)


def test_user_equations_with_pin_friction_are_refused_by_name(mechanisms):
    eom = mechanisms["pendulum"].equations()
    q, qd = full_state(*START)
    with pytest.raises(ValueError, match=r"1 revolute joint\(s\) with friction.*backend='reference'"):
        study.simulate(eom, q, qd, t_end=0.1, backend="compiled", friction="regularized")


@pytest.mark.parametrize("change", [dict(radius=2), dict(mu_static=2), dict(mu_kinetic=2), dict(torque=2),
                                    "bodies"])
def test_generated_code_key_covers_each_pin_field(mechanisms, change):
    """The key of the generated code (study.fast.codegen.module_key) changes with every field of a pin: its
    bodies (P and Pdot qd are generated) and its coefficients, radius and torque."""
    from study.fast.codegen import module_key
    from study.model.coordinates import lower

    b = lower(mechanisms["elbow"].description, "relative")
    before = module_key(b)
    pin = b.pin_frictions[0]
    if change == "bodies":
        new = dataclasses.replace(pin, body_a=pin.body_b, body_b=pin.body_a)
    else:
        (field, factor), = change.items()
        new = dataclasses.replace(pin, **{field: factor * getattr(pin, field) + (1 if field == "torque" else 0)})
    b.pin_frictions[0] = new
    assert module_key(b) != before
    b.pin_frictions[0] = pin
    assert module_key(b) == before
