"""Paper 000's slider-crank with Coulomb friction in its pins O, A, B (study.mechanisms.slider_crank_pins).

The variant is described in absolute coordinates q = [x1, y1, th1, x2, y2, th2, x3, y3] with every pin a cut joint;
paper 000's slider-crank (study.mechanisms.slider_crank) in the relative coordinates [q1, q2] with the pins as tree
joints. With the pins' coefficients set to 0 the two are the same mechanism written twice, so their runs must agree
to the integration error: each adaptive run (DOP853, rtol RTOL) carries a global error of at most
adaptive_global_error_factor * RTOL * max|x| in a quantity x (reference/tolerances.toml), their difference at most
twice that. With the pins' friction on, the energy balance must close and each pin must dissipate.

A last test builds a small mechanism whose pin reaction passes through zero, where |R|_delta = sqrt(|R|^2 + delta^2)
replaces the norm's kink: the slider-crank's pin reactions do not (the smallest is the share of the rod's weight
that A and B carry, ~0.5 N; test_pin_reactions_of_the_slider_crank_stay_away_from_zero).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import study
from study.mechanisms import mechanism
from study.model import Mechanism
from study.mechanisms import slider_crank_pins as pins
from study.model.compile import compile_description
from study.model.coordinates import lower
from study.params import load_parameters
from study.reactions import absolute_state
from study.reference_data import tolerance
from study.model.initial_state import NEWTON_TOL
from study.laws.events import BRENT_XTOL

RTOL = 1e-8
T_END = 1.0
OUTPUT_STEP = 0.01
EPS = 1e-3                 # the treatment's width: m/s in the guide, rad/s in the pins (simulate's default)
DELTA = tolerance("pin_friction_norm_width")
GLOBAL = tolerance("adaptive_global_error_factor") * RTOL    # one run's global error, relative to max|x|
SLIDER_X = 6               # x3 in the variant's q; the paper's slider x in its absolute state (x, y, theta per body)


def parameters(variant: str, **values) -> study.ParameterSet:
    ps = load_parameters("slider_crank_pins", variant)
    return dataclasses.replace(ps, values=dataclasses.replace(ps.values, **values)) if values else ps


def frictionless_pins(variant: str) -> study.ParameterSet:
    return parameters(variant, **{f"mu_{p}": 0.0 for p in pins.PINS})


def run(mech, friction: str, **options) -> study.SimulationResult:
    return study.simulate(mech, t_end=T_END, integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2,
                          output_step=OUTPUT_STEP, friction=friction, **options)


def paper_run(variant: str, friction: str) -> tuple[study.SimulationResult, np.ndarray]:
    """Paper 000's slider-crank and its slider's x at every sample (through its own generated kinematics)."""
    paper = mechanism(load_parameters("slider_crank", variant))
    r = run(paper, friction)
    x = np.array([absolute_state(paper, q, qd, qdd)[0][SLIDER_X] for q, qd, qdd in zip(r.q, r.qd, r.qdd)])
    return r, x


def assert_reproduces_the_paper(r, paper, slider_x, what):
    pairs = {"crank angle": (r.q[:, 2], paper.q[:, 0]), "slider x": (r.q[:, SLIDER_X], slider_x),
             "guide normal force": (r.forces["normal_guide"], paper.forces["normal_guide"]),
             "guide friction force": (r.forces["friction_guide"], paper.forces["friction_guide"])}
    for name, (got, expected) in pairs.items():
        dev, bound = np.abs(got - expected).max(), 2 * GLOBAL * np.abs(expected).max()
        print(f"{what}: {name}: max dev {dev:.3g} (bound {bound:.3g})")
        assert dev <= bound, (what, name, dev, bound)


def omegas(r) -> dict[str, np.ndarray]:
    """Each pin's relative rate omega_rel = theta_a' - theta_b' (first body minus second, ground's 0)."""
    w1, w2 = r.qd[:, 2], r.qd[:, 5]
    return {"O": -w1, "A": w1 - w2, "B": w2}


def energy_residual(r) -> np.ndarray:
    e = r.energies
    change = e["kinetic"] + e["potential"] - e["kinetic"][0] - e["potential"][0]
    return change - sum(w - w[0] for k, w in e.items() if k.startswith("work_"))


# --- the description and its initial state -------------------------------------------------------------
def test_initial_state_is_the_papers_mapped_to_absolute_coordinates():
    """The printed state of the parameter file is 000's printed state mapped through the paper mechanism's own
    kinematics, and Newton's consistent state is the paper's consistent state mapped (the slider's angle 0 is no
    coordinate of the variant). Each Newton solve stops at max|Phi| <= NEWTON_TOL, which leaves its dependent
    coordinates within NEWTON_TOL / sigma_min (sigma_min: smallest singular value of the rows' dependent columns),
    moved by at most l2 per radian of the paper's q2 when mapped; the rates solve linear rows (round-off)."""
    ps = load_parameters("slider_crank_pins")
    ours, paper = mechanism(ps), mechanism(load_parameters("slider_crank", ps.variant))
    keep = [i for i in range(9) if i != 8]            # crank x, y, th; rod x, y, th; slider x, y (not its angle)
    ic = paper.parameters.initial
    zero = np.zeros(2)
    x, xd, _ = absolute_state(paper, np.array(ic.printed_q), np.array(ic.printed_qd), zero)
    round_off = tolerance("round_off") * max(1.0, np.abs(x).max())
    assert np.abs(np.array(ps.initial.printed_q) - x[keep]).max() <= round_off
    assert np.abs(np.array(ps.initial.printed_qd) - xd[keep]).max() <= round_off
    mine, theirs = ours.initial_state(), paper.initial_state()
    x, xd, _ = absolute_state(paper, theirs.q, theirs.qd, zero)

    def sigma_min(m, q):
        dependent = np.delete(m.equations().phi_q(q), list(m.parameters.initial.independent), axis=1)
        return np.linalg.svd(dependent, compute_uv=False).min()

    bound = NEWTON_TOL * (1 / sigma_min(ours, mine.q) + paper.parameters.values.l2 / sigma_min(paper, theirs.q)) \
        + round_off
    dq, dqd = np.abs(mine.q - x[keep]).max(), np.abs(mine.qd - xd[keep]).max()
    print(f"consistent states: max |dq| {dq:.3g} (bound {bound:.3g}), max |dqd| {dqd:.3g} (bound {round_off:.3g})")
    assert dq <= bound and dqd <= round_off


def test_every_pin_is_a_cut_joint_with_its_radius_and_coefficient():
    ps = parameters("seed", r_O=0.03, mu_A=0.2)
    eom = mechanism(ps).equations()
    assert tuple(eom.coordinate_names) == pins.COORDINATES
    assert tuple(eom.constraint_names) == ("O_x", "O_y", "A_x", "A_y", "B_x", "B_y", "guide")
    got = {p.name: (p.radius, p.mu_kinetic, p.mu_static, p.torque) for p in eom.pin_frictions}
    assert got == {"O": (0.03, 0.1, 0.1, 0.0), "A": (0.015, 0.2, 0.2, 0.0), "B": (0.01, 0.1, 0.1, 0.0)}
    assert [j.name for j in mechanism(ps).description.pins()] == ["O", "A", "B"]
    assert Mechanism(pins.describe(ps, pin_friction=False), ps).description.pins() == []


# --- frictionless pins: paper 000's slider-crank ---------------------------------------------------------
@pytest.mark.parametrize("variant", ["sustained_sliding", "slip_then_stick"])
def test_frictionless_pins_reproduce_the_paper_regularized(variant):
    """Pins with mu = 0 (the pins' machinery on, its torques zero), the guide regularized. The variants slide
    throughout (|v_B| >> eps, so tanh is saturated and the friction force follows N). The seed is left out here:
    its regularized guide creeps inside the band |v_B| < eps, where f = (F + mu N) tanh(v_B / eps) turns a velocity
    error into a force error (F + mu N) / eps ~ 1e4 N s/m times larger, beyond this bound; the exact test runs it."""
    r = run(mechanism(frictionless_pins(variant)), "regularized")
    paper, slider_x = paper_run(variant, "regularized")
    assert_reproduces_the_paper(r, paper, slider_x, f"{variant}, regularized")
    assert all(np.all(r.forces[f"friction_{p}"] == 0.0) for p in pins.PINS)


@pytest.mark.parametrize("variant", ["seed", "sustained_sliding"])
def test_frictionless_pins_reproduce_the_paper_exact(variant):
    """The guide's exact stick/slip (the seed slides, then sticks at 3.6 ms), the variant with ideal pins
    (``describe(ps, pin_friction=False)``): the same absolute coordinates and cut joints. The stick event is located on each run's own trajectory: the times
    differ by the slider velocities' difference (<= 2 GLOBAL max|v_B|) over its deceleration there, which is its
    deceleration at t = 0 (the 3.6 ms of slip change it by 3e-5 relative: 0.127036 to 0.127037 m/s^2)."""
    ps = frictionless_pins(variant)
    r = run(Mechanism(pins.describe(ps, pin_friction=False), ps), "exact")   # the inherited resistance_reading
    paper, slider_x = paper_run(variant, "exact")
    assert_reproduces_the_paper(r, paper, slider_x, f"{variant}, exact")
    ours, theirs = r.stats["event_times"], paper.stats["event_times"]
    assert len(ours) == len(theirs) == (1 if variant == "seed" else 0)
    for a, b in zip(ours, theirs):
        bound = 2 * GLOBAL * np.abs(r.qd[:, SLIDER_X]).max() / abs(r.qdd[0, SLIDER_X])
        print(f"{variant}: stick at {a:.12g} s and {b:.12g} s (bound {bound:.3g})")
        assert abs(a - b) <= bound


def test_exact_with_zero_pin_friction_is_the_ideal_pins():
    """Pins whose friction is identically zero carry no share of a hold: the seed's guide sticks as with ideal pins."""
    r = run(mechanism(frictionless_pins("seed")), "exact")
    ideal = run(Mechanism(pins.describe(frictionless_pins("seed"), pin_friction=False), frictionless_pins("seed")),
                "exact")
    guide = [[(x["t"], x["to"]) for x in run_.stats["friction_transitions"] if x["contact"] == "guide"]
             for run_ in (r, ideal)]
    print(f"guide transitions {guide[0]} (ideal pins {guide[1]}); every event {r.stats['event_times']}")
    assert len(guide[0]) == 1 and guide[0][0][1] == "stick"
    assert guide[0][0][1] == guide[1][0][1] and abs(guide[0][0][0] - guide[1][0][0]) <= BRENT_XTOL   # located alike
    assert np.abs(r.q - ideal.q).max() <= 2 * GLOBAL * np.abs(ideal.q).max()


def test_exact_hold_of_the_seed_is_refused_as_statically_indeterminate():
    """With the pins' friction on, the seed's slider comes to rest at 3.6 ms and could be held, but holding it stops
    the crank and with it every pin (one degree of freedom): FrictionLawError names them."""
    from study.solver.friction import FrictionLawError

    with pytest.raises(FrictionLawError, match=r"'guide' comes to rest at t = 0\.0035\d+ s and can be held, but "
                                               r"holding it also stops 'O', 'A', 'B'.*statically indeterminate"):
        run(mechanism(parameters("seed")), "exact")


def test_exact_pin_friction_is_the_limit_of_the_regularized():
    """sustained_sliding with friction in the guide and the pins, exact law against the regularized one as eps -> 0:
    tanh(v/eps) differs from the frozen sgn only while |v| < a few eps (the start, where the pins turn at ~1e-3
    rad/s), so the difference shrinks with eps; the exact run's energy balance closes."""
    mech = mechanism(parameters("sustained_sliding"))
    exact = run(mech, "exact")
    residual = np.abs(energy_residual(exact)).max()
    scale = tolerance("energy_drift_factor") * RTOL * exact.energies["kinetic"].max()
    print(f"exact, pins with friction: energy residual {residual:.3g} J (bound {scale:.3g}); "
          f"events {exact.stats['event_times']}")
    assert residual <= scale
    devs = [np.abs(run(mech, "regularized", friction_eps=eps).q[:, 2] - exact.q[:, 2]).max()
            for eps in (1e-3, 1e-4, 1e-5)]
    print("max |th1(regularized) - th1(exact)| at eps 1e-3, 1e-4, 1e-5: " + ", ".join(f"{d:.3g}" for d in devs))
    # |tanh(v/eps) - sgn v| <= 2 exp(-2 |v| / eps): the laws differ only while an entry is within a few eps of rest, a
    # time that shrinks at least in proportion to eps, so each tenfold smaller eps must shrink the difference tenfold
    assert devs[1] <= devs[0] / 10 and devs[2] <= devs[1] / 10


# --- friction in the pins ------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def sliding():
    """sustained_sliding with the pins' friction, and the same with mu = 0 in the pins."""
    return (run(mechanism(parameters("sustained_sliding")), "regularized"),
            run(mechanism(frictionless_pins("sustained_sliding")), "regularized"))


def test_pin_torques_follow_the_law_from_the_reactions(sliding):
    """friction_P = tau_P = -(mu_P r_P |R_P|_delta) tanh(omega_P / eps) with omega_P the module docstring's relative
    rate and |R_P| (normal_P) the norm of the pin's two multipliers; at B that reaction is also what the slider's
    Newton equation needs: m3 a_B = R_B + (f, N) - m3 g e_y. Newton on the torques stops once |tau - law| <=
    pin_friction_solve_rtol * max(level, |tau|); recomputing the law and the balance here adds round-off."""
    r, _ = sliding
    ps = parameters("sustained_sliding")
    v, paper = ps.values, load_parameters("slider_crank", ps.variant).values
    rows = {n: i for i, n in enumerate(mechanism(ps).equations().constraint_names)}
    for pin, omega in omegas(r).items():
        R = r.lam[:, [rows[f"{pin}_x"], rows[f"{pin}_y"]]]
        assert np.abs(r.forces[f"normal_{pin}"] - np.hypot(*R.T)).max() <= tolerance("round_off") * np.abs(R).max()
        level = getattr(v, f"mu_{pin}") * getattr(v, f"r_{pin}") * np.sqrt((R ** 2).sum(axis=1) + DELTA ** 2)
        law = -level * np.tanh(omega / EPS)
        dev = np.abs(r.forces[f"friction_{pin}"] - law).max()
        bound = (tolerance("pin_friction_solve_rtol") + tolerance("round_off")) * level.max()
        print(f"pin {pin}: torque vs law: max dev {dev:.3g} N m (bound {bound:.3g})")
        assert dev <= bound, pin
    inertia, f, n = paper.m3 * r.qdd[:, SLIDER_X], r.forces["friction_guide"], r.forces["normal_guide"]
    need = np.hypot(inertia - f, paper.m3 * (r.qdd[:, 7] + paper.g) - n)
    largest = max(np.abs(inertia).max(), np.abs(f).max(), np.abs(n).max(), paper.m3 * paper.g)
    assert np.abs(r.forces["normal_B"] - need).max() <= tolerance("round_off") * largest


def test_energy_balance_closes_and_every_pin_dissipates(sliding):
    """E(t) - E(0) = work of the drive + friction work of the guide and the three pins, to the runs' energy error
    (energy_drift_factor * RTOL * the largest energy term); each pin's power tau omega <= 0 at every sample, and its
    friction work never grows."""
    r, free = sliding
    e = r.energies
    terms = [e["kinetic"], e["potential"] - e["potential"][0]] + [w for k, w in e.items() if k.startswith("work_")]
    scale = tolerance("energy_drift_factor") * RTOL * max(np.abs(x).max() for x in terms)
    residual = np.abs(energy_residual(r)).max()
    print(f"energy residual {residual:.3g} J (bound {scale:.3g}); friction work: "
          + ", ".join(f"{k[14:]} {e[k][-1]:.4g} J" for k in e if k.startswith("work_friction_")))
    assert residual <= scale
    for pin, omega in omegas(r).items():
        tau = r.forces[f"friction_{pin}"]
        power = tau * omega
        assert power.max() <= tolerance("round_off") * np.abs(tau).max() * np.abs(omega).max(), pin
        assert np.diff(e[f"work_friction_{pin}"]).max() <= scale, pin
        assert e[f"work_friction_{pin}"][-1] < 0, pin
    assert np.abs(energy_residual(free)).max() <= scale


def test_pin_friction_is_a_visible_part_of_the_motion(sliding):
    """The crank with and without the pins' friction differs by far more than the two runs' errors: the torques
    (~0.035 N m against the 10 N m drive, crank and rod inertia ~15 kg m^2) slow the crank by ~1e-3 rad in 1 s,
    the errors are 2 GLOBAL max|th1| ~ 1.4e-6 rad."""
    r, free = sliding
    diff = np.abs(r.q[:, 2] - free.q[:, 2]).max()
    bound = 2 * GLOBAL * np.abs(free.q[:, 2]).max()
    print(f"crank angle with and without pin friction: max diff {diff:.3g} rad (runs' error bound {bound:.3g})")
    assert diff >= 100 * bound
    assert r.q[-1, 2] < free.q[-1, 2]     # the pins' friction only takes energy out


def test_pin_reactions_of_the_slider_crank_stay_away_from_zero(sliding):
    """The slider-crank's own pins never come near |R| = 0: the smallest reaction, at A and B, is the part of the
    rod's weight they carry (m2 g c2 / l2 = 0.5 N at B, as much at A, the seed nearly at rest). At |R| >= 100 delta
    the smooth norm differs from |R| by <= delta^2 / (2 |R|^2) = 5e-5 relative, so its width is immaterial there;
    the next test builds a pin whose reaction does pass through zero."""
    r, _ = sliding
    seed = run(mechanism(parameters("seed")), "regularized")
    for name, result in (("sustained_sliding", r), ("seed", seed)):
        sizes = {p: (result.forces[f"normal_{p}"].min(), result.forces[f"normal_{p}"].max()) for p in pins.PINS}
        print(f"{name}: min/max |R| per pin: " + ", ".join(f"{p} {lo:.3g}/{hi:.3g} N" for p, (lo, hi) in sizes.items()))
        assert min(lo for lo, _ in sizes.values()) > 100 * DELTA


# --- a pin whose reaction passes through zero --------------------------------------------------------------
ZERO = dict(mc=1.0, mb=1.0, Jb=0.01, mu=0.2, r=0.02, F0=10.0, T=0.4)
ZERO_START = (0.0, 0.0, 5.0)        # cart x, cart velocity, bar spin [rad/s]


def zero_crossing_description() -> study.Description:
    """A cart on a frictionless horizontal rail (horizontal plane: no gravity) pushed by F0 cos(2 pi t / T), and a
    bar pinned to the cart at its centre of mass by a pin with friction, spinning. The bar's centre moves with the
    cart, so the pin's reaction on the bar is R = mb F / (mc + mb) e_x: it passes through zero whenever F does
    (t = T/4 + k T/2, on the output grid), while the bar spins at w >> eps: Jb w' = -mu r |R|_delta tanh(w / eps)."""
    d = study.Description("pin_reaction_through_zero", ["x", "xb", "yb", "th"], ZERO)
    p = d.p
    x, xb, yb, th = d.q
    d.ground("O", 0, 0)
    d.body("cart", p.mc, p.mc / 10, {"c": (0, 0)}, angle=0)
    d.body("bar", p.mb, p.Jb, {"c": (0, 0)}, angle=th, position=(xb, yb))
    d.prismatic("rail", slider=("cart", "c"), guide=(study.GROUND, "O"), axis=(1, 0), normal=(0, 1), travel=x)
    d.revolute("pin", ("cart", "c"), ("bar", "c"), friction=study.Friction(p.mu, p.mu), radius=p.r)
    d.force("push", "cart", "c", p.F0 * sp.cos(2 * sp.pi * d.t / p.T), 0)
    return d


def zero_crossing_hand(t_grid, delta=DELTA):
    """The bar's spin from the scalar law with the closed-form reaction |R(t)| = mb |F0 cos(2 pi t / T)| / (mc + mb)."""
    v = ZERO

    def rhs(t, y):
        R = v["mb"] * v["F0"] * math.cos(2 * math.pi * t / v["T"]) / (v["mc"] + v["mb"])
        return [y[1], -v["mu"] * v["r"] * math.sqrt(R * R + delta * delta) * math.tanh(y[1] / EPS) / v["Jb"]]

    sol = solve_ivp(rhs, (t_grid[0], t_grid[-1]), [0.0, ZERO_START[2]], method="DOP853",
                    rtol=tolerance("reference_rtol"), atol=tolerance("reference_atol"), t_eval=t_grid)
    assert sol.success
    return sol.y.T


def test_pin_reaction_through_zero_keeps_the_solve_and_the_energy_balance_smooth():
    eom = compile_description(lower(zero_crossing_description()))
    x0, v0, w0 = ZERO_START
    r = study.simulate(eom, np.array([x0, x0, 0.0, 0.0]), np.array([v0, v0, 0.0, w0]), t_end=T_END,
                       integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=OUTPUT_STEP,
                       friction="regularized", friction_eps=EPS)
    R = r.forces["normal_pin"]
    tau = r.forces["friction_pin"]
    i = int(np.argmin(R))
    print(f"reaction through zero: min |R| = {R[i]:.3g} N at t = {r.t[i]:.3g} s (delta {DELTA:g} N, max |R| "
          f"{R.max():.3g} N), torque there {tau[i]:.3g} N m, {r.stats['nfev']} evaluations")
    # the sample t = T/4 lies on a zero of F, so |R| there is round-off: the run passes through the smoothing band
    assert R[i] <= DELTA / 100 and R.max() >= 1e3 * DELTA
    # the law at every sample, at the crossing too (|R|_delta -> delta): tau is the torque on the cart (the pin's
    # first body), omega_rel = 0 - w; Newton's stopping rule and round-off as in the slider-crank's test
    level = ZERO["mu"] * ZERO["r"] * np.sqrt(R ** 2 + DELTA ** 2)
    assert np.all(np.isfinite(tau))
    bound = (tolerance("pin_friction_solve_rtol") + tolerance("round_off")) * level.max()
    assert np.abs(tau + level * np.tanh(-r.qd[:, 3] / EPS)).max() <= bound
    hand = zero_crossing_hand(r.t)
    for k, name in ((0, "bar angle"), (1, "bar spin")):
        got = (r.q[:, 3], r.qd[:, 3])[k]
        dev, bound = np.abs(got - hand[:, k]).max(), GLOBAL * np.abs(hand[:, k]).max()
        print(f"  {name} vs hand model: max dev {dev:.3g} (bound {bound:.3g})")
        assert dev <= bound
    e = r.energies
    scale = tolerance("energy_drift_factor") * RTOL * e["kinetic"].max()
    residual = np.abs(energy_residual(r)).max()
    print(f"  energy residual {residual:.3g} J (bound {scale:.3g}), pin dissipated {-e['work_friction_pin'][-1]:.4g} J")
    assert residual <= scale
