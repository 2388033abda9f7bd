"""In-house solver: acceleration solvers, stabilization methods, integrators, energy, drift."""

import dataclasses

import numpy as np
import pytest

import handwritten
from study import simulate
from study.mechanisms import equations, initial_state, load
from study.reference_data import tolerance
from study.results import SimulationResult
from study.solver.accelerations import ACCELERATION_SOLVERS, make_acceleration_solver
from study.solver.stabilization import SIGN_FUNCTIONS, make_stabilization

REF = {"integrator": "DOP853", "rtol": tolerance("reference_rtol"), "atol": tolerance("reference_atol")}


def states(name, variant="seed", t_end=1.0):
    """States along a short accurate run of a mechanism."""
    r = simulate(name, variant=variant, t_end=t_end, output_step=0.1, method="projection", **REF)
    _, eom = load(name, variant)
    return eom, [(t, q, qd) for t, q, qd in zip(r.t, r.q, r.qd)]


@pytest.mark.parametrize("name", ["slider_crank", "quick_return"])
def test_acceleration_solvers_agree(name):
    eom, samples = states(name, "smooth_cutting" if name == "quick_return" else "seed")
    tol = tolerance("round_off")
    for t, q, qd in samples:
        M, Q, J, c = eom.mass(q), eom.forces(t, q, qd), eom.phi_q(q), eom.gamma(q, qd)
        base_qdd, base_lam = make_acceleration_solver("multiplier").solve(M, Q, J, c)
        for solver in ("partitioned", "orthonormal"):
            qdd, lam = make_acceleration_solver(solver).solve(M, Q, J, c)
            np.testing.assert_allclose(qdd, base_qdd, rtol=1e3 * tol, atol=1e3 * tol * np.abs(base_qdd).max())
            np.testing.assert_allclose(lam, base_lam, rtol=1e3 * tol, atol=1e3 * tol * np.abs(base_lam).max())


def test_partition_switches_on_pendulum():
    """Cartesian pendulum swinging through the bottom: the dependent coordinate must change."""
    eom = handwritten.cartesian_pendulum()
    r = simulate(eom, [1.0, 0.0], [0.0, 0.0], 2.0, acceleration_solver="partitioned", method="projection")
    assert r.stats["partition_switches"] >= 2
    ref = simulate(eom, [1.0, 0.0], [0.0, 0.0], 2.0, acceleration_solver="multiplier", method="projection")
    np.testing.assert_allclose(r.q, ref.q, atol=1e-6)


@pytest.mark.parametrize("solver", list(ACCELERATION_SOLVERS))
@pytest.mark.parametrize("method,options", [
    ("none", {}), ("baumgarte", {}), ("baumgarte", {"alpha": 5.0, "beta": 10.0}), ("projection", {}),
    ("projection", {"weighting": "mass"}),
    *[("sliding_mode", {"sgn": s, "width": 1e-6}) for s in SIGN_FUNCTIONS if s != "sign"],
    ("sliding_mode", {"sgn": "sign"}),
])
def test_every_method_on_pendulum(method, options, solver):
    """A user's hand-written EquationsOfMotion runs through every method and solver."""
    eom = handwritten.cartesian_pendulum()
    integrator = {"integrator": "RK4", "step": 1e-3} if options.get("sgn") == "sign" else {}
    r = simulate(eom, [0.6, -0.8], [0.8, 0.6], 1.0, method=method, acceleration_solver=solver, **integrator,
                 **options)
    assert np.abs(r.phi).max() < 1e-5
    assert r.summary()["energy_error"] < 1e-4 * 9.81


@pytest.mark.parametrize("variant", ["seed", "smooth_cutting"])
@pytest.mark.parametrize("method,options", [
    ("none", {}), ("baumgarte", {}), ("projection", {}),
    *[("sliding_mode", {"sgn": s}) for s in SIGN_FUNCTIONS if s != "sign"],
])
def test_every_method_on_quick_return(method, options, variant):
    r = simulate("quick_return", variant=variant, t_end=0.5, method=method, rtol=1e-8, atol=1e-10, **options)
    assert np.abs(r.phi).max() < tolerance("constraint_drift_1s")
    assert r.summary()["energy_error_relative"] < tolerance("energy_drift_factor") * 1e-8


def test_sliding_mode_exact_sign_with_rk4_on_quick_return():
    r = simulate("quick_return", variant="smooth_cutting", t_end=0.5, method="sliding_mode", sgn="sign",
                 integrator="RK4", step=1e-3)
    assert np.abs(r.phi).max() < tolerance("constraint_drift_1s")


def test_on_off_switches_are_located():
    """Each switch is an event; at the event the switching function that crossed is zero to round-off,
    evaluated on the state the integrator restarts from, and the others keep their signs."""
    from study.solver.run import build_dynamics
    from study.solver.integrate import integrate

    ps, eom = load("quick_return", "seed")
    st = initial_state(ps, eom)
    dyn, y0, _ = build_dynamics(eom, st.q, st.qd, method="none", acceleration_solver="multiplier", friction=None,
                                friction_eps=1e-3, friction_sgn="tanh")
    m = eom.n_coordinates

    def g(t, y):
        return np.asarray(eom.indicators(t, y[:m], y[m:2 * m]))

    first = integrate(dyn.rhs, 0.0, y0, 1.0, np.array([0.0, 1.0]), method="DOP853", rtol=1e-10, atol=1e-12,
                      indicators=g)
    events = first.events
    assert len(events) >= 4 and np.all(np.diff([e["t"] for e in events]) > 0)
    # the same run again, sampled at the event times: the samples are the states at the events
    again = integrate(dyn.rhs, 0.0, y0, 1.0, np.array([0.0] + [e["t"] for e in events] + [1.0]), method="DOP853",
                      rtol=1e-10, atol=1e-12, indicators=g)
    assert [e["t"] for e in again.events] == [e["t"] for e in events]
    # scale of each switching function's rate: |dg/dt| <= |v_D'| or |v_D| (m/s^2, m/s) times the Brent tolerance
    for k, e in enumerate(events, start=1):
        gk = g(e["t"], again.y[k])
        rate = np.abs(g(e["t"] + 1e-6, again.y[k] + 1e-6 * dyn.rhs(e["t"], again.y[k], again.modes[k])) - gk) / 1e-6
        i = e["indicator"]
        assert abs(gk[i]) <= rate[i] * tolerance("switch_location_time") + tolerance("switching_function_round_off"), (e, gk)
        others = [j for j in range(len(gk)) if j != i]
        assert np.all(np.abs(gk[others]) > 0)


def energy_free_quick_return():
    ps = load("quick_return", "smooth_cutting")[0]
    free = dataclasses.replace(ps, values=dataclasses.replace(ps.values, M=0.0, F_cut=0.0))
    return free, equations(free)


def test_energy_conserved_without_drive_and_cutting():
    ps, eom = energy_free_quick_return()
    st = initial_state(ps, eom)
    rtol = 1e-9
    r = simulate(eom, st.q, st.qd, 2.0, method="projection", rtol=rtol, atol=1e-11)
    e = r.energies["kinetic"] + r.energies["potential"]
    assert set(r.energies) == {"kinetic", "potential", "work_drive", "work_cutting"}
    assert np.abs(r.energies["work_cutting"]).max() == 0.0 and np.abs(r.energies["work_drive"]).max() == 0.0
    assert np.abs(e - e[0]).max() <= tolerance("energy_drift_factor") * rtol * r.energies["kinetic"].max()


@pytest.mark.parametrize("variant", ["seed", "smooth_cutting"])
def test_energy_bookkeeping_with_drive_and_cutting(variant):
    rtol = 1e-9
    r = simulate("quick_return", variant=variant, t_end=2.0, method="projection", rtol=rtol, atol=1e-11)
    assert r.energies["work_cutting"].min() < -1e5  # the cut does work
    balance = r.energy_balance()
    assert np.abs(balance - balance[0]).max() <= tolerance("energy_drift_factor") * rtol * r.energies["kinetic"].max()


def test_drift_ordering():
    """At RK45, rtol 1e-6, atol 1e-8, 5 s, smooth cutting: none > Baumgarte (d=1, w=10) > projection."""
    drift = {}
    for method in ("none", "baumgarte", "projection"):
        r = simulate("quick_return", variant="smooth_cutting", t_end=5.0, method=method, rtol=1e-6, atol=1e-8)
        drift[method] = np.abs(r.phi).max()
    assert drift["none"] > drift["baumgarte"] > drift["projection"]


def test_rk4_converges_at_order_4():
    ps, eom = energy_free_quick_return()
    ref = simulate(eom, *_ic(ps, eom), 0.5, method="none", **REF)
    errors = []
    steps = [4e-3, 2e-3, 1e-3]
    for h in steps:
        r = simulate(eom, *_ic(ps, eom), 0.5, method="none", integrator="RK4", step=h)
        errors.append(np.abs(r.q - ref.q).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 4) <= tolerance("rk4_order_band")), orders


def _ic(ps, eom):
    st = initial_state(ps, eom)
    return st.q, st.qd


@pytest.mark.parametrize("integrator", ["RK45", "DOP853", "Radau", "LSODA"])
def test_adaptive_integrators_meet_tolerance(integrator):
    rtol = 1e-7
    ref = simulate("quick_return", variant="smooth_cutting", t_end=1.0, method="none", **REF)
    r = simulate("quick_return", variant="smooth_cutting", t_end=1.0, method="none", integrator=integrator,
                 rtol=rtol, atol=rtol * 1e-2)
    scale = np.abs(ref.q).max()
    assert np.abs(r.q - ref.q).max() <= tolerance("adaptive_global_error_factor") * rtol * scale


def test_result_round_trip(tmp_path):
    r = simulate("quick_return", variant="seed", t_end=0.2, method="baumgarte")
    path = r.save(tmp_path / "run")
    back = SimulationResult.load(path)
    for key in ("t", "q", "qd", "qdd", "lam", "phi", "phidot"):
        np.testing.assert_array_equal(getattr(back, key), getattr(r, key))
    for key in r.energies:
        np.testing.assert_array_equal(back.energies[key], r.energies[key])
    assert back.stats == r.stats and back.meta["parameter_hash"] == r.meta["parameter_hash"]
    assert list(back.to_dataframe().columns) == list(r.to_dataframe().columns)


@pytest.mark.parametrize("kwargs,match", [
    ({"method": "magic"}, "valid choices: none, baumgarte, sliding_mode, projection"),
    ({"integrator": "Euler"}, "valid choices: RK45"),
    ({"rtol": 0.0}, "rtol = 0.0 must be finite and > 0"),
    ({"atol": -1.0}, "atol = -1.0 must be finite and > 0"),
    ({"t_end": 0.0}, "t_end = 0.0 must be finite and > 0"),
    ({"integrator": "RK4"}, "RK4 is fixed-step: give step"),
    ({"integrator": "RK4", "step": -1e-3}, "step = -0.001 must be finite and > 0"),
    ({"acceleration_solver": "lu"}, "valid choices: multiplier, partitioned, orthonormal"),
    ({"method": "sliding_mode", "sgn": "sigmoid"}, "valid choices: sign, sat, tanh, arctan, sqrt"),
    ({"method": "baumgarte", "d": 2.0}, "0 < d <= 1"),
    ({"method": "projection", "integrator": "LSODA"}, "post-step projection needs"),
])
def test_bad_input_is_named(kwargs, match):
    kwargs.setdefault("t_end", 0.1)
    with pytest.raises(ValueError, match=match):
        simulate("quick_return", **kwargs)


def test_sliding_mode_with_equal_gains_is_baumgarte_plus_switching_term():
    """s = Phidot + L Phi, sdot = -K s - k sgn(s) gives Phi'' = -(L+K) Phidot - K L Phi - k sgn(s):
    Baumgarte with 2 d w = L + K and w^2 = K L, plus the switching term. With L = K = w, d = 1."""
    rng = np.random.default_rng(7)
    phi, phidot = rng.normal(size=2), rng.normal(size=2)
    sm = make_stabilization("sliding_mode", Lambda=10.0, K=10.0, k=1e-3, sgn="tanh", width=1e-8)
    bg = make_stabilization("baumgarte", d=1.0, omega=10.0)
    s = phidot + 10.0 * phi
    np.testing.assert_allclose(sm.bias(phi, phidot) - bg.bias(phi, phidot), -1e-3 * np.tanh(s / 1e-8),
                               rtol=0, atol=tolerance("round_off") * 100 * np.abs(s).max())  # terms of size ~w^2 Phi


def test_lsoda_small_starting_steps_are_not_a_stall():
    """LSODA starts with a ~1e-12 s step (measured: 9.6e-13 s on the quick-return), below the default
    min_step of a 20 s run (2e-11 s); counting a single such step as a stall would stop the sliding_mode
    study's LSODA cases at t = 1e-12 s. Only min_step_run steps in a row count as a stall."""
    from study import simulate

    r = simulate("quick_return", t_end=0.05, integrator="LSODA", rtol=1e-8, atol=1e-10, min_step=2e-11)
    assert r.t[-1] == pytest.approx(0.05)


@pytest.mark.parametrize("method,integrator,rtol,t_end", [
    ("none", "DOP853", 1e-5, 1.0),          # a step spans the ram's reversal and starts on a just-located switch
    ("projection", "RK45", 1e-4, 0.5),      # the projection moves x_D back across x_max after the cut switched on
])
def test_switches_located_at_loose_tolerances(method, integrator, rtol, t_end):
    """At rtol 1e-4 / 1e-5 a step can start on the far side of a switching surface (round-off after a
    located switch, or a post-step projection), where Brent's method alone has no bracket. Without
    projection every sample's mode must equal the signs of the switching functions evaluated on that
    sample's state (with projection the sample is projected after the mode is read, which may move it
    across a surface by the projection's correction); every switch of an accurate run (DOP853 at the
    reference tolerance) must have been located."""
    from study.solver.run import build_dynamics
    from study.solver.integrate import integrate

    ps, eom = load("quick_return", "seed")
    st = initial_state(ps, eom)
    m = eom.n_coordinates

    def g(t, y):
        return np.asarray(eom.indicators(t, y[:m], y[m:2 * m]))

    def run(method, integrator, rtol, atol):
        dyn, y0, _ = build_dynamics(eom, st.q, st.qd, method=method, acceleration_solver="multiplier", friction=None,
                                    friction_eps=1e-3, friction_sgn="tanh")
        post = None
        if dyn.stabilization.projects:
            def post(y):
                q, qd, changed = dyn.stabilization.project(eom, y[:m], y[m:2 * m])
                return (np.concatenate([q, qd, y[2 * m:]]) if changed else y), changed
        return integrate(dyn.rhs, 0.0, y0, t_end, np.linspace(0.0, t_end, 1001), method=integrator, rtol=rtol,
                         atol=atol, indicators=g, post_step=post)

    loose = run(method, integrator, rtol, rtol / 100)
    accurate = run("projection", "DOP853", tolerance("reference_rtol"), tolerance("reference_atol"))
    for t, y, mode in zip(loose.t, loose.y, loose.modes) if method == "none" else ():
        assert tuple(np.where(g(t, y) >= 0, 1, -1)) == tuple(mode), (t, g(t, y), mode)
    # every switch of the accurate run has a located counterpart (same indicator, same new sign)
    loose_switches = {(e["indicator"], e["new_sign"]) for e in loose.events}
    assert {(e["indicator"], e["new_sign"]) for e in accurate.events} <= loose_switches
    assert len(loose.events) >= len(accurate.events)


def test_method_objects_are_accepted_like_names():
    """simulate(method=Baumgarte(...)) runs the same method as simulate(method='baumgarte', ...): the same
    arrays, since the object is the one the name builds. A user's subclass that changes only ``bias`` runs on the
    reference path, and the compiled path refuses it by name (the inherited compiled form is not its bias);
    options next to an object are an error."""
    from study.solver.stabilization import Baumgarte

    by_name = simulate("quick_return", t_end=0.2, method="baumgarte", d=1.0, omega=10.0)
    by_object = simulate("quick_return", t_end=0.2, method=Baumgarte(d=1.0, omega=10.0))
    assert np.array_equal(by_name.q, by_object.q) and np.array_equal(by_name.lam, by_object.lam)

    class Doubled(Baumgarte):
        def bias(self, phi, phidot):
            return 2.0 * super().bias(phi, phidot)

    from study.mechanisms import initial_state, load

    ps, eom = load("quick_return", "seed")
    st = initial_state(ps, eom)
    off = st.q + np.array([1e-4, 0.0, 0.0])  # off the constraints, so the bias is not zero
    runs = [simulate(eom, off, st.qd, 0.2, method=m, check=False)
            for m in (Baumgarte(d=1.0, omega=10.0), Doubled(d=1.0, omega=10.0))]
    assert np.abs(runs[0].phi).max() > 1e-6 and np.abs(runs[0].q - runs[1].q).max() > 1e-8
    with pytest.raises(ValueError, match="the stabilization Doubled .* does not define its own compiled_bias"):
        simulate("quick_return", t_end=0.2, method=Doubled(d=1.0, omega=10.0), backend="compiled")
    with pytest.raises(ValueError, match="its options are its fields"):
        simulate("quick_return", t_end=0.2, method=Baumgarte(d=1.0, omega=10.0), d=2.0)


def test_a_new_method_is_one_class_for_both_backends():
    """A user's stabilization that defines ``bias`` and its compiled counterpart ``compiled_bias`` in one class
    runs on both paths, and they agree (as the built-in methods do, tests/test_fast.py)."""
    from numba import njit

    from study.kernels.signatures import BIAS
    from study.mechanisms import initial_state, load
    from study.solver.stabilization import Baumgarte

    @njit(BIAS)
    def doubled_bias(phi, phidot, cf, off, out):
        for i in range(phi.size):
            out[i] = 2.0 * (-cf[off] * phidot[i] - cf[off + 1] * phi[i])

    class Doubled(Baumgarte):   # compiled_parameters (2 d w, w^2) are Baumgarte's
        def bias(self, phi, phidot):
            return 2.0 * super().bias(phi, phidot)

        compiled_bias = staticmethod(doubled_bias)

    ps, eom = load("quick_return", "seed")
    st = initial_state(ps, eom)
    off = st.q + np.array([1e-4, 0.0, 0.0])  # off the constraints, so the bias acts
    kw = dict(variant="seed", t_end=0.2, check=False, rtol=1e-10, atol=1e-12)
    fast = simulate("quick_return", off, st.qd, method=Doubled(d=1.0, omega=10.0), backend="compiled", **kw)
    ref = simulate("quick_return", off, st.qd, method=Doubled(d=1.0, omega=10.0), **kw)
    plain = simulate("quick_return", off, st.qd, method=Baumgarte(d=1.0, omega=10.0), backend="compiled", **kw)
    bound = tolerance("adaptive_global_error_factor") * 1e-10 * np.abs(ref.q).max()
    assert np.abs(fast.q - ref.q).max() <= bound < np.abs(fast.q - plain.q).max()
