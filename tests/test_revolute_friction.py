"""Coulomb friction in a revolute joint: a pendulum on a ground pin with pin friction.

The mechanism: a bar (mass m, centroidal inertia Ic) hangs from a ground pin O at its point (0, l) (body frame), so its
centre of mass is r_G = (l sin th, -l cos th); vertical plane, gravity -y. In the study's description the bar is a
free body (x, y, angle th) and the pin is a revolute joint with friction (friction=Friction(mu, mu, T0), radius=r),
hence a cut joint whose two rows' multipliers are its reaction R; q = (th, x, y).

Independent reference, derived by hand here in the minimal coordinate th, not from the description. The pin reaction
on the bar, from the bar's Newton equation m a_G = R + m g_vec:

    R = m (a_G + (0, g)),   a_G = l (th'' cos th - th'^2 sin th, th'' sin th + th'^2 cos th)

and the moment equation about O (R passes through O):

    (Ic + m l^2) th'' = -m g l sin th - (mu r |R|_delta + T0) s(th'),   |R|_delta = sqrt(Rx^2 + Ry^2 + delta^2)

R depends on th'', so th'' solves an implicit scalar equation: Newton below. s = tanh(. / eps) ('regularized'),
sgn ('sign') or, for the exact law, the direction of the slip phase, whose end th' = 0 the hand model locates itself
(:func:`hand_exact`). The pin's relative rate is omega_rel = theta_ground' - theta_bar' = -th' (the description's joint
runs from ground to the bar), and the torque on the bar is -tau = -(mu r |R|_delta + T0) s(th'): the same law.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import study
import study.solver.friction.contact as contact
from study.model.coordinates import lower
from study.model.joints import DescriptionError
from study.reference_data import tolerance
from test_free_bodies import parameter_set

VALUES = dict(m=1.5, Ic=0.05, l=0.4, g=9.81, mu=0.3, r=0.1, T0=0.05)
START = (1.0, 0.0)        # th, th': released from rest at 1 rad
T_END = 1.5               # about two swings; the amplitude decays from 1 to ~0.55 rad
RTOL = 1e-9
EPS = 1e-3                # the treatment's width [rad/s] (friction_eps)
OUTPUT_STEP = 0.01
DELTA = tolerance("pin_friction_norm_width")


def describe(ps: study.ParameterSet, cut=None, radius=True, relative=False) -> study.Description:
    coords = ["th"] if relative else ["th", "x", "y"]
    d = study.Description("pin_friction_pendulum", coords, {k: getattr(ps.values, k) for k in VALUES})
    p = d.p
    th = d.q[0]
    d.ground("O", 0, 0)
    d.body("bar", p.m, p.Ic, {"pin": (0, p.l)}, angle=th, position=None if relative else (d.q[1], d.q[2]))
    d.revolute("pin", (study.GROUND, "O"), ("bar", "pin"), cut=cut, friction=study.Friction(p.mu, p.mu, p.T0),
               radius=p.r if radius else None)
    d.gravity(p.g)
    return d


def full_state(th, w, l=VALUES["l"]):
    q = np.array([th, l * math.sin(th), -l * math.cos(th)])
    return q, np.array([w, l * w * math.cos(th), l * w * math.sin(th)])


def pendulum(tmp_path, th: float, w: float) -> study.Mechanism:
    """The pendulum of the module docstring with VALUES, started at th [rad], th' = w [rad/s]."""
    q, qd = full_state(th, w)
    ps = parameter_set(tmp_path, "pin_friction_pendulum", VALUES, q, qd, [0])
    return study.Mechanism(describe(ps), ps)


#: The double pendulum of test_pin_between_two_moving_bodies_dissipates_its_work: bar 'upper' (mass m1, centroidal
#: inertia I1, half length l1) on the ground pin 'shoulder' at its point (0, l1), bar 'lower' (m2, I2, l2) on the pin
#: 'elbow' at the upper's tip (0, -l1) with its point (0, l2); the elbow has pin friction (mu, radius r).
DOUBLE = dict(m1=1.0, I1=0.03, l1=0.3, m2=0.8, I2=0.02, l2=0.25, g=9.81, mu=0.3, r=0.05)


def describe_double(values, shoulder_friction: bool = False) -> study.Description:
    """The double pendulum, q = (th1, th2, x, y) with (x, y) the lower bar's centre; with ``shoulder_friction`` the
    shoulder has the same pin friction and the upper bar is a free body too (its centre (x1, y1) appended to q)."""
    coords = ["th1", "th2", "x", "y"] + (["x1", "y1"] if shoulder_friction else [])
    d = study.Description("pin_friction_double", coords, dict(values))
    p = d.p
    th1, th2, x, y = d.q[:4]
    d.ground("O", 0, 0)
    d.body("upper", p.m1, p.I1, {"top": (0, p.l1), "tip": (0, -p.l1)}, angle=th1,
           position=(d.q[4], d.q[5]) if shoulder_friction else None)
    d.body("lower", p.m2, p.I2, {"top": (0, p.l2)}, angle=th2, position=(x, y))
    if shoulder_friction:
        d.revolute("shoulder", (study.GROUND, "O"), ("upper", "top"), friction=study.Friction(p.mu, p.mu), radius=p.r)
    else:
        d.revolute("shoulder", (study.GROUND, "O"), ("upper", "top"))
    d.revolute("elbow", ("upper", "tip"), ("lower", "top"), friction=study.Friction(p.mu, p.mu), radius=p.r)
    d.gravity(p.g)
    return d


def double_state(values, a1: float, a2: float, w1: float, w2: float, shoulder_friction: bool = False):
    """(q, qd) of :func:`describe_double` at the bar angles a1, a2 and rates w1, w2."""
    l1, l2 = values["l1"], values["l2"]
    q = [a1, a2, 2 * l1 * math.sin(a1) + l2 * math.sin(a2), -2 * l1 * math.cos(a1) - l2 * math.cos(a2)]
    qd = [w1, w2, 2 * l1 * w1 * math.cos(a1) + l2 * w2 * math.cos(a2),
          2 * l1 * w1 * math.sin(a1) + l2 * w2 * math.sin(a2)]
    if shoulder_friction:
        q += [l1 * math.sin(a1), -l1 * math.cos(a1)]
        qd += [l1 * w1 * math.cos(a1), l1 * w1 * math.sin(a1)]
    return np.array(q), np.array(qd)


@pytest.fixture(scope="module")
def mech(tmp_path_factory):
    return pendulum(tmp_path_factory.mktemp("pin"), *START)


# --- the hand model ------------------------------------------------------------------------------------
def hand_accel(th, w, s, v=VALUES, delta=DELTA):
    """(th'', R) of the module docstring: Newton on G(a) = I_O a + m g l sin th + (mu r |R(a)|_delta + T0) s."""
    m, l, g = v["m"], v["l"], v["g"]
    io, c, sn = v["Ic"] + m * l * l, math.cos(th), math.sin(th)
    k = v["mu"] * v["r"]

    def reaction(a):
        return m * l * (a * c - w * w * sn), m * (l * (a * sn + w * w * c) + g)

    a = -m * g * l * sn / io
    for _ in range(50):
        rx, ry = reaction(a)
        norm = math.sqrt(rx * rx + ry * ry + delta * delta)
        G = io * a + m * g * l * sn + (k * norm + v["T0"]) * s
        dG = io + k * s * m * l * (rx * c + ry * sn) / norm
        step = G / dG
        a -= step
        if abs(step) <= 1e-15 * (1 + abs(a)):
            return a, reaction(a)
    raise AssertionError("hand Newton did not converge")


def hand_regularized(t_grid, eps=EPS, delta=DELTA):
    def rhs(t, y):
        return [y[1], hand_accel(y[0], y[1], math.tanh(y[1] / eps), delta=delta)[0]]
    sol = solve_ivp(rhs, (t_grid[0], t_grid[-1]), START, method="DOP853", rtol=tolerance("reference_rtol"),
                    atol=tolerance("reference_atol"), t_eval=t_grid)
    assert sol.success
    return sol.y.T


def hand_rk4(t_grid, h):
    """Classical RK4 with step h and the plain sgn at every stage, sampled at t_grid (multiples of h)."""
    def f(y):
        return np.array([y[1], hand_accel(y[0], y[1], float(np.sign(y[1])))[0]])
    y, out = np.array(START, dtype=float), []
    every = int(round((t_grid[1] - t_grid[0]) / h))
    n = int(round(t_grid[-1] / h))
    out.append(y.copy())
    for i in range(1, n + 1):
        k1 = f(y); k2 = f(y + h / 2 * k1); k3 = f(y + h / 2 * k2); k4 = f(y + h * k3)  # noqa: E702
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if i % every == 0:
            out.append(y.copy())
    return np.array(out)


def run(mech, **options):
    return study.simulate(mech, t_end=T_END, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=OUTPUT_STEP,
                          friction="regularized", friction_eps=EPS, friction_sgn="tanh", **options)


@pytest.fixture(scope="module")
def regularized(mech):
    return run(mech)


def balance_residual(r):
    e = r.energies
    change = e["kinetic"] + e["potential"] - e["kinetic"][0] - e["potential"][0]
    return change - (e["work_friction_pin"] - e["work_friction_pin"][0])


# --- tests -------------------------------------------------------------------------------------------
def test_regularized_pin_friction_matches_the_hand_model(regularized):
    r = regularized
    hand = hand_regularized(r.t)
    got = np.column_stack([r.q[:, 0], r.qd[:, 0]])
    bound = tolerance("adaptive_global_error_factor") * RTOL
    for k in (0, 1):
        dev = np.abs(got[:, k] - hand[:, k]).max()
        print(f"pin friction vs hand model, column {k}: max dev {dev:.3g} "
              f"(bound {bound * np.abs(hand[:, k]).max():.3g})")
        assert dev <= bound * np.abs(hand[:, k]).max(), k
    # the friction acted: the amplitude decays well below the frictionless 1 rad
    assert np.abs(hand[-60:, 0]).max() < 0.8
    # the reported reaction and torque are the hand model's
    R = np.array([hand_accel(th, w, math.tanh(w / EPS))[1] for th, w in hand])
    tau_bar = -(VALUES["mu"] * VALUES["r"] * np.sqrt((R ** 2).sum(axis=1) + DELTA ** 2) + VALUES["T0"]) \
        * np.tanh(hand[:, 1] / EPS)
    assert np.abs(r.forces["normal_pin"] - np.hypot(*R.T)).max() <= 1e-5 * np.hypot(*R.T).max()
    # the study's friction_pin is tau on body a (ground): minus the torque on the bar
    assert np.abs(-r.forces["friction_pin"] - tau_bar).max() <= 1e-4 * np.abs(tau_bar).max() + 1e-6


def test_energy_balance_and_dissipation(regularized):
    r = regularized
    e = r.energies
    scale = tolerance("energy_drift_factor") * RTOL * e["kinetic"].max()
    residual = np.abs(balance_residual(r)).max()
    print(f"energy balance residual {residual:.3g} J (bound {scale:.3g}), "
          f"dissipated {-e['work_friction_pin'][-1]:.4g} J")
    assert residual <= scale
    w = e["work_friction_pin"]
    assert w[-1] < -0.5 and np.diff(w).max() <= scale   # dissipation -w never decreases


def test_norm_width_effect_is_as_estimated(mech, regularized, monkeypatch):
    """delta and delta/10: |R|_delta - |R| ~ delta^2 / (2 |R|), so the friction torque changes by
    dtau <= mu r delta^2 / (2 R_min) (R_min the smallest reaction of the run, ~8 N here: ~2e-9 N m) and th by at
    most dtau T^2 / (2 I_O) (~7e-9 rad over 1.5 s), plus the two runs' integration noise (10 rtol |th|). Measured:
    5.8e-10 rad, the same as the hand model's delta vs delta/10 at rtol 1e-12 (5.8e-10 rad): a real, tiny effect,
    1e-2 of the adaptive global error bound."""
    original = contact.tolerance
    monkeypatch.setattr(contact, "tolerance",
                        lambda key, table="tolerances": DELTA / 10 if key == "pin_friction_norm_width"
                        else original(key, table))
    tenth = run(mech)
    diff = np.abs(tenth.q[:, 0] - regularized.q[:, 0]).max()
    r_min = regularized.forces["normal_pin"].min()
    io = VALUES["Ic"] + VALUES["m"] * VALUES["l"] ** 2
    estimate = VALUES["mu"] * VALUES["r"] * DELTA ** 2 / (2 * r_min) * T_END ** 2 / (2 * io)
    bound = estimate + 10 * RTOL * np.abs(regularized.q[:, 0]).max()
    print(f"delta vs delta/10: max |d th| = {diff:.3g} rad (estimate {estimate:.3g}, bound {bound:.3g}); "
          f"min |R| = {r_min:.3g} N")
    assert r_min > 5.0
    assert diff <= bound


def test_sign_treatment_with_rk4_matches_the_hand_rk4(mech):
    h = 1e-3
    r = study.simulate(mech, t_end=1.0, integrator="RK4", step=h, output_step=OUTPUT_STEP, friction="sign")
    hand = hand_rk4(r.t, h)
    dev = np.abs(r.q[:, 0] - hand[:, 0]).max()
    print(f"sign/RK4 vs hand RK4: max |d th| = {dev:.3g}")
    # same steps, same law: the difference is round-off (th' changes sign once, near 0.68 s: sgn jumps inside steps)
    assert dev <= tolerance("fast_fixed_step_agreement") * np.abs(hand[:, 0]).max()


def hand_exact(t_end, v=None, delta=DELTA):
    """The exact stick/slip law in th from START: slip phases with the frozen direction s (coefficient v["mu"] =
    mu_k), each ended where th' = 0 (located by solve_ivp's event); at rest the pin holds if the torque that keeps
    th'' = 0, m g l sin th, is within mu_s r |R|_delta + T0, where at rest and held R = (0, m g); else it slides where
    gravity pushes, s = -sgn(sin th). ``v``: VALUES with mu_s = mu by default. Returns (stops, theta): the stops
    [(t, th, th'' just before, stuck)] and theta(grid), the hand model's th on a grid."""
    v = {**VALUES, "mu_s": VALUES["mu"]} if v is None else v
    mgl = v["m"] * v["g"] * v["l"]
    capacity = v["mu_s"] * v["r"] * math.hypot(v["m"] * v["g"], delta) + v["T0"]
    t, y, stops, pieces = 0.0, np.array(START, dtype=float), [], []
    s = -math.copysign(1.0, math.sin(y[0]))           # from rest at 1 rad: gravity turns the bar down, th' < 0
    while t < t_end:
        def rhs(_, z, s=s):
            return [z[1], hand_accel(z[0], z[1], s, v)[0]]

        def stop(_, z):
            return z[1]
        stop.terminal, stop.direction = True, -s      # th' returns to 0 from the side s (not its start at 0)
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=tolerance("reference_rtol"),
                        atol=tolerance("reference_atol"), events=stop, dense_output=True)
        assert sol.success
        pieces.append((t, sol.t[-1], sol.sol))
        if not sol.t_events[0].size:
            break
        t, y = float(sol.t_events[0][0]), np.array([sol.y_events[0][0][0], 0.0])
        stuck = abs(mgl * math.sin(y[0])) <= capacity
        stops.append((t, y[0], hand_accel(y[0], 0.0, s, v)[0], stuck))
        if stuck:
            pieces.append((t, t_end, lambda tt, th=y[0]: np.array([th, 0.0])))
            break
        s = -math.copysign(1.0, math.sin(y[0]))

    def theta(grid):
        out = np.empty(len(grid))
        for i, tt in enumerate(grid):
            _, _, f = next(p for p in pieces if p[0] <= tt <= p[1] + 1e-12)   # a sample at a stop, up to round-off
            out[i] = f(tt)[0]
        return out
    return stops, theta


T_EXACT = 4.0     # the study's pin_pendulum comes to rest after five swings, near 3.55 s


@pytest.fixture(scope="module")
def study_pendulum():
    """The study's case (reference/pin_pendulum.toml), its values in the hand model's names (mu = mu_k)."""
    v = vars(study.load_parameters("pin_pendulum").values)
    return {**{k: v[k] for k in ("m", "Ic", "l", "g", "r", "T0", "mu_s")}, "mu": v["mu_k"]}


@pytest.fixture(scope="module")
def exact():
    return study.simulate("pin_pendulum", t_end=T_EXACT, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2,
                          output_step=OUTPUT_STEP, friction="exact")


def test_exact_pin_comes_to_rest_when_the_hand_model_does(exact, study_pendulum):
    """The study's pin_pendulum: stick time and motion against the hand model (its own start, th = 1 rad at rest,
    as the parameter file's); the stuck pin's torque is the hand model's and within its static limit."""
    r, v = exact, study_pendulum
    assert r.q[0, 0] == START[0] and r.qd[0, 0] == START[1]
    stops_hand, theta = hand_exact(T_EXACT, v)
    assert stops_hand[-1][3] and len(stops_hand) >= 4
    t_stick = stops_hand[-1][0]
    stops = [tr for tr in r.stats["friction_transitions"] if tr.get("contact") == "pin" and tr["to"] == "stick"]
    print(f"exact pin: hand stick at {t_stick:.9f} s after {len(stops_hand)} slip phases; study (difference): "
          f"{[(round(x['t'], 9), round(x['t'] - t_stick, 12)) for x in stops]}")
    assert len(stops) == 1
    # the located stop is an event of the adaptive run: its time error follows the motion's (global) error
    assert abs(stops[0]["t"] - t_stick) <= tolerance("adaptive_global_error_factor") * RTOL * T_EXACT
    moving = r.t < t_stick
    hand = theta(r.t[moving])
    dev = np.abs(r.q[moving, 0] - hand).max()
    bound = tolerance("adaptive_global_error_factor") * RTOL * np.abs(hand).max()
    print(f"exact pin vs hand model: max |d th| = {dev:.3g} rad (bound {bound:.3g})")
    assert dev <= bound
    held = r.t > stops[0]["t"]
    assert np.all(r.forces["stick_pin"][held] == 1.0) and np.ptp(r.q[held, 0]) <= bound
    need = np.abs(r.forces["friction_pin"][held])
    limit = v["mu_s"] * v["r"] * np.sqrt(r.forces["normal_pin"][held] ** 2 + DELTA ** 2) + v["T0"]
    hold = v["m"] * v["g"] * v["l"] * np.abs(np.sin(r.q[held, 0]))   # the hand model's, at rest
    print(f"stuck pin: torque {need.max():.6g} N m (hand {hold.max():.6g}), limit {limit.max():.6g} N m")
    # held, the torque is the static balance m g l sin th at the run's own th: equal up to the solve's round-off
    # (round_off, relative); the bar rests 0.028 rad off the vertical, so the hold is a real torque, not 0 = 0
    assert np.all(need <= limit) and np.abs(need - hold).max() <= tolerance("round_off") * hold.max()
    assert hold.min() > 0.1 * limit.max()


def test_exact_pin_energy_balance(exact):
    scale = tolerance("energy_drift_factor") * RTOL * exact.energies["kinetic"].max()
    residual = np.abs(balance_residual(exact)).max()
    print(f"exact pin: energy balance residual {residual:.3g} J (bound {scale:.3g})")
    assert residual <= scale


def test_unconverged_torque_solve_names_joint_time_and_state(mech, monkeypatch):
    from study.solver.run import build_dynamics

    eom = mech.equations()
    q, qd = full_state(0.3, -2.0)
    dyn, _, _ = build_dynamics(eom, q, qd, method="none", acceleration_solver="multiplier", friction="regularized",
                               friction_eps=EPS, friction_sgn="tanh")
    sol = dyn.contact_solution(0.25, q, qd)     # converges: the hand model's th'' and reaction
    a, R = hand_accel(0.3, -2.0, math.tanh(-2.0 / EPS))
    assert abs(sol.qdd[0] - a) <= 1e-12 * abs(a) and abs(sol.normal[0] - math.hypot(*R)) <= 1e-12 * math.hypot(*R)
    monkeypatch.setattr(contact, "PIN_MAX_ITERATIONS", 1)
    with pytest.raises(study.solver.friction.PinFrictionError,
                       match=r"t = 0.25 s: the friction torques of revolute joint\(s\) 'pin' did not converge in 1 "
                             r"Newton iterations .* at q = \[ ?0\.3 .*, qd = \[-2\. "):
        dyn.contact_solution(0.25, q, qd)


def test_friction_none_ignores_the_pin_friction(mech):
    r = study.simulate(mech, t_end=0.2, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=OUTPUT_STEP,
                       friction="none")
    e = r.energies
    assert abs(e["kinetic"][-1] + e["potential"][-1] - e["kinetic"][0] - e["potential"][0]) < 1e-6


def test_description_errors(mech):
    ps = mech.parameters
    with pytest.raises(DescriptionError, match=r"joint 'pin': a revolute joint with friction is a cut joint"):
        lower(describe(ps, cut=False))
    with pytest.raises(DescriptionError, match=r"joint 'pin': friction on a revolute joint needs radius=r"):
        lower(describe(ps, radius=False))
    with pytest.raises(DescriptionError, match=r"'pin' has friction \(a cut joint"):
        lower(describe(ps, relative=True))


def test_pin_between_two_moving_bodies_dissipates_its_work():
    """A double pendulum whose elbow (a cut joint with friction between two moving bars) is the only loss: the
    torque acts on both bars, equal and opposite, so E(t) - E(0) is its work tau * omega_rel, which never grows."""
    from study.model.compile import compile_description

    eom = compile_description(lower(describe_double(DOUBLE)))
    q0, qd0 = double_state(DOUBLE, 0.8, -0.3, 0.0, 4.0)
    r = study.simulate(eom, q0, qd0, t_end=1.0, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2,
                       output_step=OUTPUT_STEP, friction="regularized", friction_eps=EPS)
    e = r.energies
    scale = tolerance("energy_drift_factor") * RTOL * e["kinetic"].max()
    change = e["kinetic"] + e["potential"] - e["kinetic"][0] - e["potential"][0]
    w = e["work_friction_elbow"]
    residual = np.abs(change - w).max()
    print(f"double pendulum: energy residual {residual:.3g} J (bound {scale:.3g}), elbow dissipated {-w[-1]:.4g} J")
    assert residual <= scale
    assert w[-1] < -0.05 and np.diff(w).max() <= scale


def describe_locked_pair(values, shoulder_friction: bool) -> study.Description:
    """A four-bar of one degree of freedom: the bars of :func:`describe_double` (both free bodies), the lower bar's
    tip tied to the ground point P by a distance L (a massless rocker); friction in the elbow, and with
    ``shoulder_friction`` in the shoulder too."""
    d = study.Description("locked_pair", ["th1", "th2", "x", "y", "x1", "y1"], dict(values))
    p = d.p
    th1, th2, x, y, x1, y1 = d.q
    d.ground("O", 0, 0)
    d.ground("P", p.px, p.py)
    d.body("upper", p.m1, p.I1, {"top": (0, p.l1), "tip": (0, -p.l1)}, angle=th1, position=(x1, y1))
    d.body("lower", p.m2, p.I2, {"top": (0, p.l2), "tip": (0, -p.l2)}, angle=th2, position=(x, y))
    pin = dict(friction=study.Friction(p.mu, p.mu), radius=p.r)
    d.revolute("shoulder", (study.GROUND, "O"), ("upper", "top"), cut=True, **(pin if shoulder_friction else {}))
    d.revolute("elbow", ("upper", "tip"), ("lower", "top"), **pin)
    d.distance("rocker", ("lower", "tip"), (study.GROUND, "P"), p.L)
    d.gravity(p.g)
    return d


@pytest.mark.parametrize("shoulder_friction", [False, True])
def test_holding_a_pin_that_locks_another_is_refused(shoulder_friction):
    """Released at rest near its hanging pose, the four-bar is held by its pin friction at once. With one friction pin
    that is a plain stick; with two, holding either stops the other as well (one degree of freedom), so the split of
    the holding torque is statically indeterminate: FrictionLawError names both, nothing is chosen silently."""
    from study.model.compile import compile_description
    from study.solver.friction import FrictionLawError

    a1, a2, rocker = 0.05, 0.05, 0.3
    values = {**DOUBLE, "mu": 0.8, "L": rocker}
    l1, l2 = values["l1"], values["l2"]
    tip = np.array([2 * l1 * math.sin(a1) + 2 * l2 * math.sin(a2), -2 * l1 * math.cos(a1) - 2 * l2 * math.cos(a2)])
    values.update(px=float(tip[0] + rocker), py=float(tip[1]))
    q0, qd0 = double_state(values, a1, a2, 0.0, 0.0, shoulder_friction=True)
    eom = compile_description(lower(describe_locked_pair(values, shoulder_friction)))
    options = dict(t_end=0.2, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=OUTPUT_STEP,
                   friction="exact")
    if not shoulder_friction:
        r = study.simulate(eom, q0, qd0, **options)
        held = tolerance("adaptive_global_error_factor") * RTOL * np.abs(r.q).max()   # moves by its error only
        assert np.all(r.forces["stick_elbow"] == 1.0) and np.ptp(r.q[:, 0]) <= held
        return
    with pytest.raises(FrictionLawError, match=r"'(shoulder|elbow)' comes to rest at t = 0 s and can be held, but "
                                               r"holding it also stops '(shoulder|elbow)'.*statically indeterminate"):
        study.simulate(eom, q0, qd0, **options)


@pytest.mark.parametrize("backend", ["reference", "compiled"])
def test_a_subnormal_start_velocity_is_rest(backend):
    """The study's pendulum released with a rate of a few subnormal ulps (what +-4 ulps of make verify's perturbation
    check put on a zero): at rest, so the same transitions as the exact start from rest, not a slip in the direction
    of the round-off's sign reversed at once."""
    mech = study.mechanisms.mechanism(study.load_parameters("pin_pendulum"))
    state = mech.initial_state()
    options = dict(t_end=1.0, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=OUTPUT_STEP,
                   friction="exact", backend=backend)
    plain = study.simulate(mech, **options)
    for sign in (1, -1):
        qd = state.qd + sign * 4 * np.spacing(0.0)
        r = study.simulate(mech, state.q, qd, **options)
        assert [(x["t"], x.get("to")) for x in r.stats["friction_transitions"][1:]] == \
            [(x["t"], x.get("to")) for x in plain.stats["friction_transitions"][1:]]
        assert r.stats["friction_transitions"][0]["initial"] == plain.stats["friction_transitions"][0]["initial"]
