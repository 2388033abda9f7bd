"""The examples: users' mechanisms that no file of study/ names, each run through the public API (``import study``)
as its own script does.

Independent references, derived by hand: the oscillating cylinder's loop closure at its initial state and its
energy conservation; the Scotch yoke's energy integral, which fixes the crank's rate by its angle; the cart-pendulum's
hold once the rail's friction has stopped the cart (a pendulum about a fixed pivot, and the force the rail must
supply), its energy balance with the friction's dissipation, and the five-bar's loop closure at its initial state
and its energy conservation. The stabilization methods must follow the same motion, both backends agree, and Exudyn,
on models generated from the same descriptions, converges to the in-house reference at order 2 (min_order).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

import study
from study.reference_data import tolerance

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
RTOL = 1e-10


def example(name: str):
    """The example's script, imported from its own folder like a user's file."""
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / name / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def assert_conservative_methods_agree(results) -> None:
    """The methods that add no forces of their own beyond the constraints' (none, Baumgarte, projection) conserve
    the energy and follow the projection run's motion within twice the adaptive runs' global error bound."""
    kinetic = max(r.energies["kinetic"].max() for r in results.values())
    for method in ("none", "baumgarte", "projection"):
        energy = results[method].energies["kinetic"] + results[method].energies["potential"]
        assert np.abs(energy - energy[0]).max() <= tolerance("energy_drift_factor") * RTOL * kinetic, method
    reference = results["projection"].q
    bound = 2 * tolerance("adaptive_global_error_factor") * RTOL * np.abs(reference).max()
    for method in ("none", "baumgarte"):
        assert np.abs(results[method].q - reference).max() <= bound, method


def test_oscillating_cylinder_through_every_method():
    """1 s at rtol 1e-10: every method runs; the consistent initial state is the hand-solved closure; the methods
    that add no forces of their own beyond the constraints' (none, Baumgarte, projection) conserve the energy and
    follow the projection run's motion within twice the adaptive runs' global error bound. (The sliding mode's
    sgn term, at its default gains, moves the motion by ~1e-7 rad here: a property of that law, not of the run.)"""
    results = example("oscillating_cylinder").run(t_end=1.0, rtol=RTOL)
    rc, d = 0.1, 0.3   # the example's parameter file
    assert np.allclose(results["none"].q[0], [np.pi / 2, np.arctan2(rc, -d), np.hypot(rc, d)], rtol=0, atol=1e-12)
    assert_conservative_methods_agree(results)
    assert set(results) == {"none", "baumgarte", "sliding_mode", "projection"}


def test_scotch_yoke_follows_its_energy_integral():
    """1 s at rtol 1e-10, no loads: the crank's rate is fixed by the crank's angle through the kinetic energy,
    I(th) th'^2 = const with I = mc rc^2/3 + mb rc^2 + my rc^2 sin^2(th) (the block turns with nothing, the yoke
    moves at -rc sin(th) th'), derived by hand. The runs that add no forces of their own (none, Baumgarte,
    projection) keep it within the adaptive runs' global error bound; the slot keeps the yoke at x = rc cos(th)."""
    results = example("scotch_yoke").run(t_end=1.0, rtol=RTOL)
    rc, mc, mb, my = 0.15, 1.2, 0.3, 2.5   # the example's parameter file

    def inertia(th):
        return mc * rc ** 2 / 3 + mb * rc ** 2 + my * rc ** 2 * np.sin(th) ** 2

    for method in ("none", "baumgarte", "projection"):
        th, rate = results[method].q[:, 0], results[method].qd[:, 0]
        exact = rate[0] * np.sqrt(inertia(th[0]) / inertia(th))
        bound = tolerance("adaptive_global_error_factor") * RTOL * np.abs(rate).max()
        assert np.abs(rate - exact).max() <= bound, method
        assert np.abs(results[method].q[:, 1] - rc * np.cos(th)).max() <= bound * rc, method


# --- the cart-pendulum with rail friction and the five-bar (examples/cart_pendulum, examples/five_bar) -------------
# Both through the public API only: study.load_mechanism on the example's file, study.simulate on either backend,
# study.exudyn_run. Exudyn is compared on common samples every EXUDYN_OUTPUT_STEP (no interpolation), at three steps
# halving, and the observed order log2(e(h) / e(h/2)) must reach min_order (reference/cross_validation.toml).
EXUDYN_OUTPUT_STEP = 0.01
# The five-bar's steps [s]: its cranks reach ~21 rad/s (released from rest, they swing through the bottom), so the
# largest step turns a crank by <= 0.02 rad and a crank turn (~0.3 s) takes >= 300 steps: the leading O(h^2) error
# term dominates (measured orders 1.999 in q, qd and the pin C's multipliers). Each step divides the output step.
FIVE_BAR_STEPS = (1e-3, 5e-4, 2.5e-4)
# The cart-pendulum's regularized rail friction -mu |N| tanh(v/eps), the SAME eps on both sides. Once the cart has
# come to rest the law holds it by a viscous creep whose slope mu |N| / eps acts on the cart (~2 kg): with
# eps = 1e-2 m/s the time constant is 2 kg * 1e-2 / (0.2 * 27.5 N) = 3.6 ms, i.e. 1.8 to 7 steps of CART_STEPS, so
# the steps resolve it. With the study's friction_eps (1e-3, chosen for the slider-crank's 16 kg) it is 0.36 ms,
# below every step: the observed order in qd fell to 1.32 (h = 2e-3 -> 1e-3) and index 3's Newton iteration failed
# at h = 6.25e-5 (t = 0.175 s), so this example takes its own eps, as the quick-return does (quick_return_friction_eps).
CART_EPS = 1e-2
CART_STEPS = (2e-3, 1e-3, 5e-4)


def user_mechanism(name: str) -> study.Mechanism:
    """The example's file through study.load_mechanism, as ``study validate`` takes it."""
    return study.load_mechanism(EXAMPLES / name / f"{name}.py")


def accurate(mech, t_end: float, **options) -> study.SimulationResult:
    return study.simulate(mech, t_end=t_end, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, **options)


def first_stick(r: study.SimulationResult) -> float:
    """The time of the run's first located slip -> stick transition."""
    return next(x["t"] for x in r.stats["friction_transitions"] if x["contact"] and x["to"] == "stick")


def assert_exudyn_converges(mech, t_end: float, steps, quantities, **law) -> None:
    """Exudyn (index 3) at each step against the in-house reference (DOP853 at reference_rtol with projection, the
    same friction law): every error above the accuracy floor, every observed order >= min_order."""
    inhouse = {"friction": "regularized", "friction_eps": law["eps"]} if law else {}
    ref = study.simulate(mech, t_end=t_end, method="projection", integrator="DOP853", rtol=tolerance("reference_rtol"),
                         atol=tolerance("reference_atol"), output_step=EXUDYN_OUTPUT_STEP, **inhouse)
    errors = {k: [] for k in quantities}
    for h in steps:
        ex = study.exudyn_run(mech, t_end, h, solver="index3", output_step=EXUDYN_OUTPUT_STEP,
                              friction="regularized" if law else "none", **law)
        assert np.array_equal(np.round(ex.t / EXUDYN_OUTPUT_STEP), np.round(ref.t / EXUDYN_OUTPUT_STEP))
        for k in quantities:
            a, b = (getattr(ex, k), getattr(ref, k)) if k in ("q", "qd", "lam") else (ex.forces[k], ref.forces[k])
            errors[k].append(float(np.abs(a - b).max()))
    low, floor = (tolerance(key, table="cross_validation") for key in ("min_order", "order_error_floor"))
    for k, e in errors.items():
        e = np.array(e)
        assert e.min() > floor, f"{k}: errors {e} reach the accuracy floor {floor}"
        orders = np.log(e[:-1] / e[1:]) / np.log(np.array(steps[:-1]) / np.array(steps[1:]))
        assert np.all(orders >= low), f"{k}: errors {e}, observed orders {orders}"


def test_cart_pendulum_slides_then_sticks_and_holds():
    """The exact law, 1 s at rtol 1e-10: launched at 0.5 m/s with the pendulum at 60 deg, the cart slides (friction
    -mu N), comes to rest, sticks, and stays stuck. Independent reference, derived by hand: while stuck the pendulum
    (a uniform rod, centre a = lp/2 below the hinge, I_O = mp lp^2/3) swings about a fixed pivot, th'' =
    -mp g a sin(th) / I_O, and the rail must supply the hinge's pull, F = mp a (cos th th'' - sin th th'^2) along x
    and N = (mc + mp) g + mp a (sin th th'' + cos th th'^2) normal to it. That needed force stays within
    mu_s N all along, so the law must never release the cart; the recorded forces are that balance to round-off."""
    mech = user_mechanism("cart_pendulum")
    v = mech.parameters.values
    assert mech.equations().constraint_names == ("rail",)       # the gap row; the cart's angle is 0 (no angle row)
    r = accurate(mech, 1.0, friction="exact")
    assert r.stats["friction_transitions"][0]["initial"] == {"rail": "slip+"}
    assert [(x["from"], x["to"]) for x in r.stats["friction_transitions"] if x["contact"]] == [("slip+", "stick")]
    t_stick = first_stick(r)
    stuck = r.t > t_stick
    assert 0.1 < t_stick < 0.9                                   # it slides a while, then holds for a while
    assert np.all(r.forces["stick_rail"][stuck] == 1.0) and np.all(r.forces["stick_rail"][~stuck] == 0.0)
    assert np.abs(r.qd[stuck, 0]).max() <= tolerance("stick_drift", table="friction")
    F, N = r.forces["friction_rail"], r.forces["normal_rail"]
    np.testing.assert_allclose(F[~stuck], -v.mu * N[~stuck], rtol=1e-12)   # sliding forward: F = -mu N
    a, inertia = v.lp / 2, v.mp * v.lp ** 2 / 3
    th, rate = r.q[stuck, 2], r.qd[stuck, 2]
    accel = -v.mp * v.g * a * np.sin(th) / inertia
    F_hand = v.mp * a * (np.cos(th) * accel - np.sin(th) * rate ** 2)
    N_hand = (v.mc + v.mp) * v.g + v.mp * a * (np.sin(th) * accel + np.cos(th) * rate ** 2)
    assert np.all(np.abs(F_hand) < v.mu * N_hand)               # within the static limit: it must stay stuck
    scale = tolerance("round_off") * np.abs(N).max()
    assert np.abs(F[stuck] - F_hand).max() <= scale and np.abs(N[stuck] - N_hand).max() <= scale
    assert np.abs(F[stuck]).max() > 0.3 * v.mu * np.abs(N[stuck]).max()   # the hold does real work, not 0 = 0
    # the stuck pendulum's own energy integral, I_O th'^2 / 2 - mp g a cos th
    energy = inertia * rate ** 2 / 2 - v.mp * v.g * a * np.cos(th)
    assert np.abs(energy - energy[0]).max() <= tolerance("energy_drift_factor") * RTOL * r.energies["kinetic"].max()


def test_cart_pendulum_energy_balance_is_the_friction_dissipation():
    """Every stabilization method with the exact law, 1 s at rtol 1e-10: E(t) - E(0) = W_friction(t) within the
    accurate runs' energy bound (energy_drift_factor * rtol * kinetic scale); the dissipation -W_friction is never
    negative, never decreases, grows while the cart slides and stays constant once it sticks (no slip, no work)."""
    results = example("cart_pendulum").run(t_end=1.0, rtol=RTOL)
    for method, r in results.items():
        energy = r.energies["kinetic"] + r.energies["potential"]
        dissipation = -r.energies["work_friction_rail"]
        bound = tolerance("energy_drift_factor") * RTOL * r.energies["kinetic"].max()
        assert np.abs(energy - energy[0] + dissipation).max() <= bound, method
        assert dissipation[0] == 0.0 and np.all(np.diff(dissipation) >= 0), method
        stuck = r.t > first_stick(r)
        assert np.all(dissipation[stuck] == dissipation[stuck][0]), method
        assert dissipation[-1] > 0, method
    assert set(results) == {"none", "baumgarte", "sliding_mode", "projection"}


def test_cart_pendulum_backends_agree():
    """The exact law on both backends, 1 s at rtol 1e-10: the motions agree within the adaptive runs' global error
    bound, and the located stick times within fast_event_time_agreement."""
    mech = user_mechanism("cart_pendulum")
    runs = {backend: accurate(mech, 1.0, friction="exact", backend=backend) for backend in ("reference", "compiled")}
    ref, fast = runs["reference"], runs["compiled"]
    assert np.array_equal(ref.t, fast.t)
    bound = tolerance("adaptive_global_error_factor") * RTOL * np.abs(ref.q).max()
    assert np.abs(ref.q - fast.q).max() <= bound
    assert abs(first_stick(ref) - first_stick(fast)) <= tolerance("fast_event_time_agreement")
    assert np.array_equal(ref.forces["stick_rail"], fast.forces["stick_rail"])


def test_cart_pendulum_with_a_turning_cart_moves_alike():
    """The same example with the cart's angle a coordinate (describe(ps, turning=True): q = [x, y, ph, th], the
    rail's two rows holding y and ph): the same motion within twice the adaptive runs' global error bound, the same
    stick time, and ph stays 0. (Exudyn cannot take this form: see the example's docstring.)"""
    module, mech = example("cart_pendulum"), user_mechanism("cart_pendulum")
    eom = study.equations_of(module.describe(mech.parameters, turning=True))
    assert eom.constraint_names == ("rail", "rail_angle") and eom.n_coordinates == 4
    state = mech.initial_state()
    lift = lambda x: np.insert(np.asarray(x, dtype=float), 2, 0.0, axis=-1)   # noqa: E731  [x, y, th] -> [x, y, 0, th]
    flat, turning = accurate(mech, 1.0, friction="exact"), accurate(eom, 1.0, q0=lift(state.q), qd0=lift(state.qd),
                                                                     friction="exact")
    bound = 2 * tolerance("adaptive_global_error_factor") * RTOL * np.abs(flat.q).max()
    assert np.abs(turning.q - lift(flat.q)).max() <= bound
    assert abs(first_stick(flat) - first_stick(turning)) <= tolerance("fast_event_time_agreement")


def test_cart_pendulum_exudyn_converges_at_second_order():
    """Exudyn index 3 with the regularized rail friction (CART_EPS on both sides), 1 s through the cart's stop and
    hold: q, qd, the friction and the normal force converge to the in-house reference at order >= min_order."""
    assert_exudyn_converges(user_mechanism("cart_pendulum"), 1.0, CART_STEPS,
                            ("q", "qd", "friction_rail", "normal_rail"), eps=CART_EPS)


def test_five_bar_conserves_energy_through_every_method():
    """1 s at rtol 1e-10 from rest: every method runs; the consistent initial state closes the loop, derived by hand
    (l1 e(th1) + l2 e(th2) = (d, 0) + l4 e(th4) + l3 e(th3), on the branch sin(th2 - th3) > 0, with the cranks'
    angles of the parameter file); the methods that add no forces of their own (none, Baumgarte, projection) keep
    kinetic + potential energy within energy_drift_factor * rtol * kinetic scale and follow the projection run's
    motion within twice the adaptive runs' global error bound."""
    results = example("five_bar").run(t_end=1.0, rtol=RTOL)
    v = user_mechanism("five_bar").parameters.values
    th1, th2, th3, th4 = results["none"].q[0]
    e = lambda a: np.array([np.cos(a), np.sin(a)])   # noqa: E731
    gap = v.l1 * e(th1) + v.l2 * e(th2) - np.array([v.d, 0.0]) - v.l4 * e(th4) - v.l3 * e(th3)
    assert np.abs(gap).max() <= tolerance("round_off") and np.sin(th2 - th3) > 0
    assert (th1, th4) == (2.2, -0.4) and np.all(results["none"].qd[0] == 0.0)
    assert max(r.energies["kinetic"].max() for r in results.values()) > 1.0   # it swings: ~6 J of kinetic energy
    assert_conservative_methods_agree(results)


def test_five_bar_backends_agree():
    """1 s at rtol 1e-10 on both backends: within the adaptive runs' global error bound; energy conserved on both."""
    mech = user_mechanism("five_bar")
    ref, fast = (accurate(mech, 1.0, backend=backend) for backend in ("reference", "compiled"))
    assert np.array_equal(ref.t, fast.t)
    assert np.abs(ref.q - fast.q).max() <= tolerance("adaptive_global_error_factor") * RTOL * np.abs(ref.q).max()
    for r in (ref, fast):
        energy = r.energies["kinetic"] + r.energies["potential"]
        assert np.abs(energy - energy[0]).max() <= tolerance("energy_drift_factor") * RTOL * r.energies["kinetic"].max()


def test_five_bar_exudyn_converges_at_second_order():
    """Exudyn index 3, 1 s from rest (the cranks swing through the bottom at up to ~21 rad/s): q, qd and the pin C's
    multipliers converge to the in-house reference at order >= min_order."""
    assert_exudyn_converges(user_mechanism("five_bar"), 1.0, FIVE_BAR_STEPS, ("q", "qd", "lam"))
