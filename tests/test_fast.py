"""The compiled fast path (study.fast) agrees with the reference path.

Only agreement is tested here, never speed (the benchmark ``python -m study.bench`` measures it).
The first run compiles the kernels (cached on disk under the cache folder afterwards).
"""

import numpy as np
import pytest

from handwritten import cartesian_pendulum
from study.mechanisms import initial_state, load, mechanism as mechanism_of
from study.reference_data import tolerance
from study.simulate import simulate

RTOL, ATOL = 1e-10, 1e-12  # tight, so both paths are close to the exact solution


def _setup(mechanism, variant, method="none", friction=None, **options):
    from study.fast import frontend   # here, not at collection: importing it compiles the loop (on a cold cache)

    ps, eom = load(mechanism, variant)
    st = initial_state(ps, eom)
    s = frontend.setup(eom, mechanism_of(ps), st.q, st.qd, method, friction, 1e-3, "tanh", **options)
    return s, st


def _accelerations(s, t, q, qd, mode=()):
    from study.fast import frontend

    return frontend.accelerations(s, t, q, qd, mode)


def _relative(a, b):
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


@pytest.mark.parametrize("method, options", [
    ("none", {}), ("baumgarte", {"d": 0.7, "omega": 20.0}), ("sliding_mode", {"sgn": "sqrt", "width": 1e-3}),
])
def test_quick_return_acceleration_matches_reference(method, options):
    s, st = _setup("quick_return", "smooth_cutting", method, **options)
    rng = np.random.default_rng(7)
    for _ in range(3):  # off the constraint manifold too, so the stabilization terms are non-zero
        q, qd = st.q + 1e-3 * rng.standard_normal(3), st.qd + 1e-2 * rng.standard_normal(3)
        t = float(rng.uniform(0, 5))
        qdd_ref, lam_ref = s.dyn.evaluate(t, q, qd)
        out = _accelerations(s, t, q, qd)
        assert _relative(out[:3], qdd_ref) <= tolerance("round_off")
        assert _relative(out[3:5], lam_ref) <= tolerance("round_off")


def test_on_off_cutting_law_in_every_mode_matches_reference():
    s, st = _setup("quick_return", "seed")
    for mode in [(-1, 1, 1), (1, 1, 1), (-1, -1, 1), (-1, 1, -1)]:
        qdd_ref, lam_ref = s.dyn.evaluate(0.3, st.q, st.qd, mode)
        out = _accelerations(s, 0.3, st.q, st.qd, mode)
        assert _relative(out[:3], qdd_ref) <= tolerance("round_off")


@pytest.mark.parametrize("friction, mode", [("regularized", ()), ("sign", ()), ("exact", (-1, 1)), ("exact", (1, 1))])
def test_slider_crank_friction_solve_matches_reference(friction, mode):
    s, st = _setup("slider_crank", "sustained_sliding", friction=friction)
    qd = st.qd * 300.0  # sliding clearly, so every law has a non-zero friction force
    sol = s.dyn.contact_solution(0.0, st.q, qd, mode or None)
    out = _accelerations(s, 0.0, st.q, qd, mode)
    for got, want in ((out[:2], sol.qdd), (out[2:3], sol.lam), (out[3:4], sol.normal), (out[4:5], sol.friction)):
        assert _relative(got, want) <= tolerance("round_off")


def _both(**kw):
    return simulate(backend="compiled", **kw), simulate(**kw)


def _agree(fast, ref, rtol):
    # same error control; round-off may flip an accept/reject decision, so steps are not compared
    assert fast.t.shape == ref.t.shape and np.array_equal(fast.t, ref.t)
    factor = tolerance("adaptive_global_error_factor") * rtol
    assert np.abs(fast.q - ref.q).max() <= factor * max(1.0, np.abs(ref.q).max())
    assert np.abs(fast.qd - ref.qd).max() <= factor * max(1.0, np.abs(ref.qd).max())


@pytest.mark.parametrize("integrator, method, options", [
    ("DOP853", "none", {}), ("RK45", "baumgarte", {}), ("RK45", "sliding_mode", {"sgn": "tanh"}),
    ("DOP853", "projection", {"weighting": "mass"}),
])
def test_quick_return_smooth_trajectory_matches_reference(integrator, method, options):
    fast, ref = _both(eom_or_mechanism="quick_return", variant="smooth_cutting", t_end=1.0, integrator=integrator,
                      rtol=RTOL, atol=ATOL, method=method, **options)
    _agree(fast, ref, RTOL)
    # projection counts are not compared: whether max|Phi| exceeds 1e-12 after a step is round-off
    assert np.abs(fast.phi - ref.phi).max() <= tolerance("adaptive_global_error_factor") * RTOL


def test_rk4_matches_reference():
    fast, ref = _both(eom_or_mechanism="quick_return", variant="smooth_cutting", t_end=0.3, integrator="RK4",
                      step=1e-3)
    assert np.abs(fast.q - ref.q).max() <= tolerance("fast_fixed_step_agreement") * np.abs(ref.q).max()


def test_on_off_switches_located_at_the_same_times():
    fast, ref = _both(eom_or_mechanism="quick_return", variant="seed", t_end=1.2, integrator="DOP853",
                      rtol=RTOL, atol=ATOL)
    assert fast.stats["events"] == ref.stats["events"] > 0
    dt = np.abs(np.array(fast.stats["event_times"]) - np.array(ref.stats["event_times"])).max()
    assert dt <= tolerance("fast_event_time_agreement")
    _agree(fast, ref, RTOL)


# slip_then_stick sticks at 4.43 s: 5 s includes that located stick event (exact law)
@pytest.mark.parametrize("variant, friction, t_end", [("sustained_sliding", "regularized", 3.0),
                                                     ("slip_then_stick", "exact", 5.0)])
def test_slider_crank_friction_trajectory_matches_reference(variant, friction, t_end):
    fast, ref = _both(eom_or_mechanism="slider_crank", variant=variant, t_end=t_end, integrator="DOP853",
                      rtol=RTOL, atol=ATOL, friction=friction)
    assert fast.stats["events"] == ref.stats["events"]
    if friction == "exact":
        assert ref.stats["events"] > 0
        dt = np.abs(np.array(fast.stats["event_times"]) - np.array(ref.stats["event_times"])).max()
        assert dt <= tolerance("fast_event_time_agreement")
    _agree(fast, ref, RTOL)
    key = "friction_guide"
    assert np.abs(fast.forces[key] - ref.forces[key]).max() <= tolerance("adaptive_global_error_factor") * RTOL * \
        max(1.0, np.abs(ref.forces[key]).max())


@pytest.mark.parametrize("mechanism, variant, integrator, options", [
    ("quick_return", "seed", "LSODA", {"method": "sliding_mode", "sgn": "sat"}),   # switching loads
    ("slider_crank", "slip_then_stick", "Radau", {"friction": "exact"}),           # stick/slip switches
    ("slider_crank", "sustained_sliding", "LSODA", {"friction": "regularized", "method": "baumgarte"}),
])
def test_scipy_integrators_on_compiled_evaluations_match_reference(mechanism, variant, integrator, options):
    """Radau and LSODA take scipy's steps on the compiled kernels: the run is the reference run to round-off
    in the evaluations, amplified at most as the error control allows; the same switches are found."""
    fast, ref = _both(eom_or_mechanism=mechanism, variant=variant, t_end=0.5, integrator=integrator, rtol=RTOL,
                      atol=ATOL, **options)
    assert fast.meta["backend"] == "compiled" and fast.stats["nfev"] > 0
    assert fast.stats["events"] == ref.stats["events"]
    _agree(fast, ref, RTOL)


@pytest.mark.parametrize("kwargs, word", [
    ({"acceleration_solver": "partitioned"}, "acceleration_solver"),
    ({"integrator": "ALI3P", "step": 1e-3}, "integrator"),
    ({"progress": print}, "progress"),
])
def test_unsupported_options_are_refused_by_name(kwargs, word):
    with pytest.raises(ValueError, match=word):
        simulate("quick_return", variant="smooth_cutting", t_end=0.1, backend="compiled", **kwargs)


PENDULUM = cartesian_pendulum()   # one object: its kernels compile once (frontend.user_model)


@pytest.mark.parametrize("integrator, method", [("DOP853", "none"), ("RK45", "projection"), ("RK4", "baumgarte")])
def test_user_equations_that_numba_compiles_run_compiled(integrator, method):
    """A user's plain callables (the Cartesian pendulum, typed by hand) run in the compiled loop."""
    eom = PENDULUM
    q0, qd0 = np.array([1.0, 0.0]), np.array([0.0, 0.5])
    kw = dict(t_end=2.0, integrator=integrator, method=method,
              **(dict(step=1e-3) if integrator == "RK4" else dict(rtol=RTOL, atol=ATOL)))
    fast, ref = simulate(eom, q0, qd0, backend="compiled", **kw), simulate(eom, q0, qd0, **kw)
    assert fast.meta["backend"] == "compiled" and fast.stats["nfev"] > 0
    if integrator == "RK4":
        assert np.abs(fast.q - ref.q).max() <= tolerance("fast_fixed_step_agreement") * np.abs(ref.q).max()
    else:
        _agree(fast, ref, RTOL)


def test_user_equations_numba_cannot_compile_are_refused_with_the_reason():
    from types import SimpleNamespace

    from handwritten import slider_crank

    v = SimpleNamespace(**load("slider_crank", "seed")[0].values.__dict__)   # closures over an object
    eom = slider_crank(v)
    ps, generated = load("slider_crank", "seed")
    st = initial_state(ps, generated)
    with pytest.raises(ValueError, match=r"numba cannot compile the EquationsOfMotion 'slider_crank_by_hand' \(.+\).*"
                                         r"backend='reference'"):
        simulate(eom, st.q, st.qd, t_end=0.1, backend="compiled")


def test_user_equations_with_what_only_generated_kernels_cover_are_refused_by_name():
    ps, eom = load("quick_return", "smooth_cutting")   # its cutting force is a load whose work is tracked
    st = initial_state(ps, eom)
    with pytest.raises(ValueError, match=r"applied loads with tracked work \(applied_forces\).*backend='reference'"):
        simulate(eom, st.q, st.qd, t_end=0.1, backend="compiled")


def test_unknown_backend():
    with pytest.raises(ValueError, match="backend"):
        simulate("quick_return", t_end=0.1, backend="gpu")


def test_evaluation_bound_stops_within_one_step_attempt():
    """The compiled loop checks its evaluation count before each step attempt and after each accepted step, so
    it stops with at least max_evaluations and fewer than max_evaluations + one attempt's evaluations (RK45: 6
    stages, the last reused as the next step's first; the bound is checked at step boundaries, not inside)."""
    from study.errors import RunBoundError

    with pytest.raises(RunBoundError, match="reached max_evaluations = 100") as info:
        simulate("quick_return", variant="smooth_cutting", t_end=2.0, integrator="RK45", rtol=1e-6,
                 backend="compiled", max_evaluations=100)
    assert 100 <= info.value.details["evaluations"] < 100 + 6
    assert 0.0 < info.value.t < 2.0


def test_stall_bound_stops_where_the_reference_path_stops():
    """Both backends stop after min_step_run accepted steps in a row below min_step with a RunBoundError. The
    two loops are separate implementations of the same step control (the compiled one is checked step by step
    against the reference above), so they stop after the same number of accepted steps, at the same time to the
    trajectories' agreement (adaptive_global_error_factor * rtol, relative)."""
    from study.errors import RunBoundError

    stops = {}
    for backend in ("reference", "compiled"):
        with pytest.raises(RunBoundError, match="50 steps in a row below min_step = 0.05") as info:
            simulate("quick_return", variant="smooth_cutting", t_end=2.0, integrator="RK45", rtol=1e-6,
                     backend=backend, min_step=0.05)
        stops[backend] = info.value.t, info.value.details["steps"]
    assert stops["compiled"][1] == stops["reference"][1]
    rel = tolerance("adaptive_global_error_factor") * 1e-6  # the runs' rtol
    assert stops["compiled"][0] == pytest.approx(stops["reference"][0], rel=rel)


def test_non_finite_values_stop_the_run_on_both_paths():
    """RK4 with a step far too large for the quick-return (h = 0.05 s against a crank period of ~0.6 s) blows
    up. Both paths must stop with NonFiniteError naming a time inside the run. When the blow-up is detected is
    not asserted: the growth is exponential, so the step at which a value first overflows is decided by the last
    bits of everything before it and differs between hosts and between the two paths."""
    from study.errors import NonFiniteError

    t_end = 2.0
    for backend in ("reference", "compiled"):
        with pytest.raises(NonFiniteError, match="non-finite") as info:
            simulate("quick_return", t_end=t_end, integrator="RK4", step=0.05, backend=backend)
        assert 0.0 < info.value.t < t_end, (backend, info.value.t)
        assert f"t = {info.value.t:.9g} s" in str(info.value), (backend, str(info.value))


@pytest.mark.parametrize("integrator, rtol", [("DOP853", 1e-4), ("RK45", 1e-4), ("DOP853", 1e-5)])
def test_switches_at_loose_tolerances_as_on_the_reference_path(integrator, rtol):
    """At loose tolerances a step can start on the far side of a switching surface (it is zero there up to
    round-off right after a located switch). The compiled loop must apply the reference loop's rule
    (study.laws.events.crossing_finder) there: a root outside the step (t = 0) would restart the run at that root
    until the step collapses. Both paths must locate the same switches, and their runs, each within
    adaptive_global_error_factor * rtol * max|q| of the exact solution, within twice that of each other."""
    runs = {b: simulate("quick_return", variant="seed", t_end=2.0, integrator=integrator, rtol=rtol, backend=b)
            for b in ("reference", "compiled")}
    ref, fast = runs["reference"], runs["compiled"]
    assert fast.stats["events"] == ref.stats["events"] > 0
    bound = 2 * tolerance("adaptive_global_error_factor") * rtol * np.abs(ref.q).max()
    assert np.abs(fast.q - ref.q).max() <= bound


def test_what_the_compiled_backend_cannot_do_is_refused_before_it_compiles():
    """Importing the compiled frontend compiles its kernels (a minute on a cold cache); a refused run must not pay
    it. A fresh interpreter, so that no other test has imported the frontend."""
    import subprocess
    import sys

    code = ("import sys, study\n"
            "try:\n"
            "    study.simulate('quick_return', backend='compiled', acceleration_solver='augmented_lagrangian')\n"
            "except ValueError as exc:\n"
            "    print(exc)\n"
            "print('study.fast.frontend' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout
    assert "does not support acceleration_solver='augmented_lagrangian'" in out and out.split()[-1] == "False"
