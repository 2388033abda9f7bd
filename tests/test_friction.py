"""Coulomb friction in sliding joints (study.solver.friction, SPEC sec. 1, paper 000).

Independent checks: hand-solved block motions (stick time v0 / (mu g), release under a ramp push,
reversal), 000's own corrected method for the slider-crank (study.studies.slider_crank_paper.paper_method),
a direct non-symmetric saddle-point solve, and Painleve's rod.
"""

import math

import numpy as np
import pytest

from study import EquationsOfMotion, SlidingContact, simulate
from study.mechanisms import load
from study.reference_data import tolerance
from study.solver.accelerations import make_acceleration_solver
from study.solver.friction import FrictionDynamics, FrictionLawError, PainleveError, make_friction
from study.solver.stabilization import make_stabilization
from study.studies.slider_crank_paper import holding_forces, paper_method


def tol(key):
    return tolerance(key, table="friction")


# --- hand-written models ----------------------------------------------------------------------
def block(m=1.0, g=10.0, mu_s=0.3, mu_k=0.3, resistance=0.0, push=lambda t: 0.0):
    """A block on the horizontal guide y = 0: q = (x, y), Phi = y (the normal gap), tangent +x."""
    return EquationsOfMotion(
        n_coordinates=2, n_constraints=1,
        mass=lambda q: m * np.eye(2),
        forces=lambda t, q, qd: np.array([push(t), -m * g]),
        phi=lambda q: np.array([q[1]]),
        phi_q=lambda q: np.array([[0.0, 1.0]]),
        gamma=lambda q, qd: np.zeros(1),
        contacts=(SlidingContact("floor", 0, lambda q: np.array([1.0, 0.0]), lambda q, qd: 0.0,
                                 mu_s, mu_k, resistance),),
        potential_energy=lambda q: m * g * q[1],
        applied_forces=lambda t, q, qd: {"push": np.array([push(t), 0.0])},
        name="block",
    )


def painleve_rod(mu, m=1.0, l=0.5, g=10.0):
    """Uniform rod (half-length l, centre (x, y), angle th) whose lower end A slides on the floor y = 0.

    With F = -mu s |N| at A the normal force solves N (1 + 3 cos th (cos th + s sigma mu sin th)) / m = g - l sin th th'^2
    (sigma = sgn N): for mu > 4/3 and tan th = 2 one sliding direction has no consistent sign of N and
    the other has two (Painleve 1895).
    """
    return EquationsOfMotion(
        3, 1,
        mass=lambda q: np.diag([m, m, m * (2 * l) ** 2 / 12]),
        forces=lambda t, q, qd: np.array([0.0, -m * g, 0.0]),
        phi=lambda q: np.array([q[1] - l * math.sin(q[2])]),
        phi_q=lambda q: np.array([[0.0, 1.0, -l * math.cos(q[2])]]),
        gamma=lambda q, qd: np.array([-l * math.sin(q[2]) * qd[2] ** 2]),
        contacts=(SlidingContact("floor", 0, lambda q: np.array([1.0, 0.0, l * math.sin(q[2])]),
                                 lambda q, qd: l * math.cos(q[2]) * qd[2] ** 2, mu, mu),),
        potential_energy=lambda q: m * g * q[1],
        name="painleve_rod",
    )


def friction_dynamics(eom, treatment="exact", acceleration_solver="multiplier", method="none"):
    return FrictionDynamics(eom, make_acceleration_solver(acceleration_solver), make_stabilization(method),
                            tuple(eom.applied_forces(0.0, np.zeros(eom.n_coordinates), np.zeros(eom.n_coordinates))),
                            law=make_friction(treatment))


def slider_crank_states(v):
    """States on the assembly branch cos(q1 + q2) > 0 over the crank circle, rates of both signs."""
    for q1, w1 in [(0.5235987756, 0.001), (1.3, -2.0), (2.5, 3.0), (4.0, 0.7), (5.8, -1.1)]:
        q2 = math.asin(v.l1 * math.sin(q1) / v.l2) - q1
        d12 = v.l1 * math.cos(q1) / (v.l2 * math.cos(q1 + q2)) - 1  # 000 eq. (24)
        yield np.array([q1, q2]), np.array([w1, d12 * w1])


def rel_err(a, b):
    a, b = np.atleast_1d(a), np.atleast_1d(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1.0))


# --- 000's method against the multiplier contact ---------------------------------------------------
@pytest.mark.parametrize("variant", ["seed", "sustained_sliding", "alpha_damping"])
def test_paper_method_matches_multiplier_contact(variant):
    ps, eom = load("slider_crank", variant)
    dyn = friction_dynamics(eom)
    for q, qd in slider_crank_states(ps.values):
        for s in (1.0, -1.0):
            hyps = dyn.hypotheses(0.0, q, qd, stick=[False], s=[s])
            assert len(hyps) == 2
            for h in hyps:
                paper = paper_method(ps.values, q, qd, s, h["sigma"][0])
                assert rel_err(paper.qdd, h["qdd"]) <= tol("paper_vs_multiplier")
                assert rel_err(paper.normal, h["normal"][0]) <= tol("paper_vs_multiplier")
                assert rel_err(paper.friction, h["f"][0]) <= tol("paper_vs_multiplier")
                assert paper.consistent == h["consistent"]
            assert sum(h["consistent"] for h in hyps) == 1


def test_superposition_equals_direct_saddle_point_solve():
    """[[M, J^T - s mu sigma J_t^T e_k^T], [J, 0]] [qdd; lam] = [Q - J_t^T s R; gamma], friction column moved left."""
    ps, eom = load("slider_crank", "sustained_sliding")
    dyn = friction_dynamics(eom)
    ct = eom.contacts[0]
    for q, qd in slider_crank_states(ps.values):
        for s in (1.0, -1.0):
            for h in dyn.hypotheses(0.0, q, qd, stick=[False], s=[s]):
                sigma = h["sigma"][0]
                M, J, Jt = eom.mass(q), eom.phi_q(q), ct.tangent_jacobian(q)
                K = np.block([[M, J.T], [J, np.zeros((1, 1))]])
                K[:2, 2 + ct.constraint_index] -= s * ct.mu_kinetic * sigma * Jt
                rhs = np.concatenate([eom.forces(0.0, q, qd) - Jt * s * ct.resistance, eom.gamma(q, qd)])
                x = np.linalg.solve(K, rhs)
                assert rel_err(x[:2], h["qdd"]) <= tol("superposition_vs_augmented")
                assert rel_err(-x[2], h["normal"][0]) <= tol("superposition_vs_augmented")


@pytest.mark.parametrize("solver", ["partitioned", "orthonormal"])
def test_acceleration_solvers_agree_with_friction(solver):
    ps, eom = load("slider_crank", "seed")
    ref, other = friction_dynamics(eom), friction_dynamics(eom, acceleration_solver=solver)
    for q, qd in slider_crank_states(ps.values):
        for stick, s in (([False], [1.0]), ([False], [-1.0]), ([True], [0.0])):
            a = ref.contact_solution(0.0, q, qd, stick=stick, s=s)
            b = other.contact_solution(0.0, q, qd, stick=stick, s=s)
            assert rel_err(b.qdd, a.qdd) <= tol("acceleration_solvers_agree")
            assert rel_err(b.normal, a.normal) <= tol("acceleration_solvers_agree")
            assert rel_err(b.friction, a.friction) <= tol("acceleration_solvers_agree")


def test_seed_holding_forces_match_the_stuck_solver():
    """The static balance by 000's D matrix gives the same holding force as the stick constraint."""
    ps, eom = load("slider_crank", "seed")
    q, _ = next(slider_crank_states(ps.values))
    held = friction_dynamics(eom).contact_solution(0.0, q, np.zeros(2), stick=[True], s=[0.0])
    balance = holding_forces(ps.values, q)
    assert rel_err(balance["f_required"], held.friction[0]) <= tol("paper_vs_multiplier")
    assert abs(held.friction[0]) < ps.values.F + ps.values.mu * abs(held.normal[0])  # it holds


# --- exact stick/slip against hand-solved block motions -------------------------------------------
EXACT = dict(friction="exact", rtol=1e-10, atol=1e-12)


def test_block_stops_at_v0_over_mu_g_and_sticks():
    m, g, mu, v0 = 2.0, 10.0, 0.3, 1.0
    r = simulate(block(m, g, mu, mu), [0.0, 0.0], [v0, 0.0], t_end=1.0, **EXACT)
    tr = [x for x in r.stats["friction_transitions"] if x["contact"]]
    assert r.stats["friction_transitions"][0]["initial"] == {"floor": "slip+"}
    assert [x["to"] for x in tr] == ["stick"]
    assert tr[0]["t"] == pytest.approx(v0 / (mu * g), abs=tol("event_time"))
    assert r.q[-1, 0] == pytest.approx(v0**2 / (2 * mu * g), abs=tol("block_position"))
    after = r.t > v0 / (mu * g)
    assert np.all(r.forces["stick_floor"][after] == 1.0) and np.all(r.forces["stick_floor"][~after] == 0.0)
    assert np.max(np.abs(r.qd[after, 0])) <= tol("stick_drift")
    np.testing.assert_allclose(r.forces["normal_floor"], m * g, rtol=1e-14)
    np.testing.assert_allclose(r.forces["friction_floor"][~after], -mu * m * g, rtol=1e-14)
    assert np.max(np.abs(r.forces["friction_floor"][after])) <= 1e-12  # nothing to hold
    # all the kinetic energy went into friction work
    assert r.energies["work_friction_floor"][-1] == pytest.approx(-0.5 * m * v0**2, rel=1e-9)


def test_block_leaves_stick_under_ramp_push():
    """At rest under P = k t: stick until k t* = R + mu_s m g, then slip with mu_k < mu_s."""
    m, g, mu_s, mu_k, R, k = 1.0, 10.0, 0.4, 0.3, 0.5, 2.0
    t_star = (R + mu_s * m * g) / k
    c = (R + mu_k * m * g) / k
    T = 3.0
    r = simulate(block(m, g, mu_s, mu_k, R, push=lambda t: k * t), [0.0, 0.0], [0.0, 0.0], t_end=T, **EXACT)
    assert r.stats["friction_transitions"][0]["initial"] == {"floor": "stick"}
    tr = [x for x in r.stats["friction_transitions"] if x["contact"]]
    assert [(x["from"], x["to"]) for x in tr] == [("stick", "slip+")]
    assert tr[0]["t"] == pytest.approx(t_star, abs=tol("event_time"))
    # after t*: m x'' = k (t - c), v(t*) = 0, so v = k/m [(t^2 - t*^2)/2 - c (t - t*)] and
    a = t_star
    x_T = k / m * ((T**3 - a**3) / 6 - a**2 * (T - a) / 2 - c * (T - a) ** 2 / 2)
    assert r.q[-1, 0] == pytest.approx(x_T, abs=tol("block_position"))
    stuck = r.t < t_star
    assert np.max(np.abs(r.q[stuck, 0])) <= tol("block_position")
    # in stick the guide supplies exactly -P
    np.testing.assert_allclose(r.forces["friction_floor"][stuck], -k * r.t[stuck], rtol=1e-12, atol=1e-12)


def test_block_reverses_when_it_cannot_stick():
    """v0 = 1 against a push P = -5 N > mu m g = 3 N: stops at 1/8 s, then slides back at 2 m/s^2."""
    m, g, mu, P, v0, T = 1.0, 10.0, 0.3, -5.0, 1.0, 1.0
    r = simulate(block(m, g, mu, mu, push=lambda t: P), [0.0, 0.0], [v0, 0.0], t_end=T, **EXACT)
    tr = [x for x in r.stats["friction_transitions"] if x["contact"]]
    t_rev = v0 / ((-P + mu * m * g) / m)
    assert [(x["from"], x["to"]) for x in tr] == [("slip+", "slip-")]
    assert tr[0]["t"] == pytest.approx(t_rev, abs=tol("event_time"))
    x_rev = v0 * t_rev / 2
    a_back = (P + mu * m * g) / m
    assert r.q[-1, 0] == pytest.approx(x_rev + a_back * (T - t_rev) ** 2 / 2, abs=tol("block_position"))


@pytest.mark.parametrize("reading", ["holds", "sliding_only"])
def test_block_at_rest_between_static_limit_and_kinetic_resistance(reading):
    """A push P = -4 N between mu_s m g = 3 N and R + mu_k m g = 5 N, block launched against it.

    It stops at t* = v0 m / (R + mu m g - P) = 1/9 s (hand value). 'holds': the limit R + mu_s m g = 5 N
    holds it. 'sliding_only': the limit is 3 N < 4 N, so it cannot stick, and sliding back meets
    R + mu_k m g = 5 N > 4 N, which stops it at once: no consistent mode, a FrictionLawError at t*
    (without it the integration would restart at t* forever; the slider-crank 'slip_then_stick' case
    meets the same situation at 4.434 s)."""
    m, g, mu, R, P, v0 = 1.0, 10.0, 0.3, 2.0, -4.0, 1.0
    t_stop = v0 * m / (R + mu * m * g - P)
    eom = block(m, g, mu, mu, R, push=lambda t: P)
    if reading == "holds":
        r = simulate(eom, [0.0, 0.0], [v0, 0.0], t_end=0.5, resistance_reading=reading, **EXACT)
        tr = [x for x in r.stats["friction_transitions"] if x["contact"]]
        assert [(x["from"], x["to"]) for x in tr] == [("slip+", "stick")]
        assert tr[0]["t"] == pytest.approx(t_stop, abs=tol("event_time"))
        return
    with pytest.raises(FrictionLawError, match="no consistent mode.*sliding_only") as exc:
        simulate(eom, [0.0, 0.0], [v0, 0.0], t_end=0.5, resistance_reading=reading, **EXACT)
    assert exc.value.t == pytest.approx(t_stop, abs=tol("event_time"))
    assert "|f_req| = 4 N" in str(exc.value) and "static limit 3 N" in str(exc.value)


def test_slider_crank_slip_then_stick_sliding_only_stops_with_a_clear_error():
    """A case with no consistent mode at rest: the slider comes to rest at 4.434 s needing 9.06 N, above the
    'sliding_only' static limit mu_s |N| = 4.0 N and below the kinetic force R + mu_k |N| = 9.5 N. Both
    readings slide identically until then, so the error comes at the instant the 'holds' run sticks."""
    options = dict(variant="slip_then_stick", t_end=6.0, method="projection", integrator="DOP853", rtol=1e-10,
                   atol=1e-12, friction="exact")
    with pytest.raises(FrictionLawError, match="no consistent mode") as exc:
        simulate("slider_crank", resistance_reading="sliding_only", **options)
    held = simulate("slider_crank", resistance_reading="holds", **options)
    sticks = [x["t"] for x in held.stats["friction_transitions"] if x["contact"] and x["to"] == "stick"]
    assert exc.value.t == pytest.approx(sticks[0], abs=tol("event_time"))


# --- regularized -> exact --------------------------------------------------------------------------
def test_regularized_converges_to_exact_as_eps_shrinks():
    """Block v0 = 1 under a push P = 2 N < mu m g = 3 N: exact stops at t = 1 s at x = 0.5 m and sticks;
    tanh(v/eps) creeps at v = eps atanh(P / (mu m g)) instead."""
    m, g, mu, P, v0, T = 1.0, 10.0, 0.3, 2.0, 1.0, 2.0
    eom = block(m, g, mu, mu, push=lambda t: P)
    exact = simulate(eom, [0.0, 0.0], [v0, 0.0], t_end=T, **EXACT)
    t_stop = v0 / (mu * g - P / m)
    assert exact.q[-1, 0] == pytest.approx(v0 * t_stop / 2, abs=tol("block_position"))
    errors = []
    for eps in (1e-2, 1e-3, 1e-4):
        reg = simulate(eom, [0.0, 0.0], [v0, 0.0], t_end=T, friction="regularized", friction_eps=eps,
                       integrator="LSODA")
        err = float(np.max(np.abs(reg.q[:, 0] - exact.q[:, 0])))
        errors.append(err)
        creep = eps * math.atanh(P / (mu * m * g)) * (T - t_stop)
        assert err == pytest.approx(creep, rel=tol("regularized_creep_rate"))
    assert errors[0] > errors[1] > errors[2]


@pytest.mark.parametrize("sgn", ["sat", "arctan", "sqrt"])
def test_other_smooth_sign_functions_run(sgn):
    m, g, mu = 1.0, 10.0, 0.3
    r = simulate(block(m, g, mu, mu), [0.0, 0.0], [1.0, 0.0], t_end=0.2, friction="regularized",
                 friction_eps=1e-3, friction_sgn=sgn)
    assert r.meta["friction_sgn"] == sgn
    # still sliding fast (v >> eps): the full kinetic friction acts
    np.testing.assert_allclose(r.forces["friction_floor"], -mu * m * g, rtol=2e-3)


@pytest.mark.parametrize("P,behaviour", [(2.0, "creep"), (-1.0, "chatter")])
def test_plain_sign_with_rk4_never_sticks(P, behaviour):
    """000's sgn with RK4 once the block should be at rest (|P| < mu m g): the stages straddle v = 0.
    Under P = -1 N the velocity chatters around zero; under P = 2 N it sits on a spurious fixed point
    of the RK4 step map, v* ~ h a, where the stage accelerations cancel, and the block creeps.
    Either way |v| stays within one step's velocity change, h (mu g + |P| / m), but never reaches 0."""
    m, g, mu, h, T = 1.0, 10.0, 0.3, 1e-3, 2.0
    eom = block(m, g, mu, mu, push=lambda t: P)
    band = 2 * h * (mu * g + abs(P) / m)  # reported as apparent stick inside |v| <= band
    r = simulate(eom, [0.0, 0.0], [1.0, 0.0], t_end=T, friction="sign", friction_eps=band, integrator="RK4",
                 step=h, output_step=h)
    exact = simulate(eom, [0.0, 0.0], [1.0, 0.0], t_end=T, **EXACT)
    t_stop = [x for x in exact.stats["friction_transitions"] if x["contact"]][0]["t"]
    late = r.t > t_stop + 0.1
    v = r.qd[late, 0]
    assert np.max(np.abs(v)) <= h * (mu * g + abs(P) / m)
    assert np.max(np.abs(v)) > 1e3 * tol("stick_drift")  # no true rest, unlike the exact treatment
    if behaviour == "chatter":
        assert np.count_nonzero(np.diff(np.sign(v)) != 0) > 100
    else:  # creep: the position drifts far beyond what the exact treatment keeps
        assert np.all(v > 0) and r.q[-1, 0] - exact.q[-1, 0] > 1e3 * tol("block_position")
    assert np.all(r.forces["stick_floor"][late] == 1.0)


# --- energy bookkeeping ------------------------------------------------------------------------------
def energy_scale(r):
    return max(np.max(np.abs(v)) for v in r.energies.values())


@pytest.mark.parametrize("treatment,options,key", [
    ("exact", {}, "energy_balance_adaptive"),
    ("regularized", {"friction_eps": 1e-3}, "energy_balance_adaptive"),
    ("sign", {"integrator": "RK4", "step": 1e-3}, "energy_balance_rk4_smooth"),
])
def test_energy_balance_every_treatment(treatment, options, key):
    """kinetic + potential - sum(work) stays constant; friction work is dissipation (<= 0, decreasing)."""
    r = simulate("slider_crank", variant="sustained_sliding", t_end=2.0, friction=treatment, **options)
    balance = r.energy_balance()
    assert np.max(np.abs(balance - balance[0])) <= tol(key) * energy_scale(r)
    w = r.energies["work_friction_guide"]
    assert w[-1] < 0 and np.all(np.diff(w) <= 1e-12 * energy_scale(r))


def test_energy_balance_through_stick():
    r = simulate("slider_crank", variant="slip_then_stick", t_end=5.0, friction="exact", rtol=1e-8)
    balance = r.energy_balance()
    assert np.max(np.abs(balance - balance[0])) <= tol("energy_balance_adaptive") * energy_scale(r)
    tr = [x for x in r.stats["friction_transitions"] if x["contact"]]
    assert [x["to"] for x in tr] == ["stick"] and 4.0 < tr[0]["t"] < 5.0
    stuck = r.forces["stick_guide"] == 1.0
    assert np.max(np.abs(r.qd[stuck, 0])) <= tol("stick_drift")


# --- Painleve's paradox ---------------------------------------------------------------------------
TH = math.atan(2.0)  # where 1 + 3 cos^2 - 3 mu sin cos is smallest: negative for mu > 4/3


def rod_state(direction, l=0.5):
    return np.array([0.0, l * math.sin(TH), TH]), np.array([direction, 0.0, 0.0])


@pytest.mark.parametrize("direction,n_consistent", [(1.0, 2), (-1.0, 0)])
def test_painleve_paradox_is_detected(direction, n_consistent):
    q, qd = rod_state(direction)
    with pytest.raises(PainleveError) as info:
        simulate(painleve_rod(mu=2.0), q, qd, t_end=0.1, friction="exact")
    err = info.value
    assert err.contacts == ("floor",) and err.mu == (2.0,) and err.t == 0.0 and err.consistent == n_consistent
    assert "floor" in str(err) and "mu = 2" in str(err) and "t = 0" in str(err)
    with pytest.raises(PainleveError):  # the other treatments face the same sign problem
        simulate(painleve_rod(mu=2.0), q, qd, t_end=0.1, friction="regularized", friction_eps=1e-6)


def test_rod_is_well_posed_below_four_thirds():
    for direction in (1.0, -1.0):
        q, qd = rod_state(direction)
        hyps = friction_dynamics(painleve_rod(mu=1.0)).hypotheses(0.0, q, qd, stick=[False], s=[direction])
        assert sum(h["consistent"] for h in hyps) == 1
    r = simulate(painleve_rod(mu=1.0), *rod_state(1.0), t_end=0.05, friction="exact")
    assert np.all(r.forces["normal_floor"] > 0)


# --- mechanisms and options -----------------------------------------------------------------------
@pytest.mark.parametrize("method", ["none", "baumgarte", "sliding_mode", "projection"])
def test_quick_return_guide_friction_every_stabilization(method):
    _, eom_qr = load("quick_return", "guide_friction")
    r = simulate("quick_return", variant="guide_friction", t_end=0.15, friction="exact", method=method)
    F, N = r.forces["friction_ram_guide"], r.forces["normal_ram_guide"]
    assert np.all(np.isfinite(F)) and np.all(np.isfinite(N))
    np.testing.assert_allclose(np.abs(F), 0.1 * np.abs(N), rtol=1e-12)  # always sliding: |F| = mu |N|
    tr = [x for x in r.stats["friction_transitions"] if x["contact"]]
    # the ram's velocity wiggles through zero three times near the end of its stroke (0.093, 0.114, 0.130 s)
    assert [x["to"] for x in tr] == ["slip+", "slip-", "slip+"]
    v_D = np.array([eom_qr.contacts[0].tangent_jacobian(q) @ qd for q, qd in zip(r.q, r.qd)])
    for x in tr:  # each located reversal lies where the sampled ram velocity changes sign
        k = np.searchsorted(r.t, x["t"])
        assert v_D[k - 1] * v_D[k] < 0
    assert r.energies["work_friction_ram_guide"][-1] < 0


def test_exact_friction_with_switched_cutting_law():
    """The on/off cutting law switches on v_D, the ram guide's own sliding velocity: both indicators
    cross zero at the same instant, and each reversal is located once."""
    import dataclasses

    from study.mechanisms import equations, initial_state
    from study.params import load_parameters

    ps = load_parameters("quick_return", "seed")
    ps = dataclasses.replace(ps, values=dataclasses.replace(ps.values, mu_guide=0.1))
    eom = equations(ps)
    st = initial_state(ps, eom)
    r = simulate(eom, st.q, st.qd, t_end=0.3, friction="exact")
    tr = [x for x in r.stats["friction_transitions"] if x["contact"]]
    assert [x["to"] for x in tr] == ["slip+", "slip-", "slip+", "slip-"]
    v_D = np.array([eom.contacts[0].tangent_jacobian(q) @ qd for q, qd in zip(r.q, r.qd)])
    for x in tr:  # each located reversal lies where the sampled ram velocity changes sign
        k = np.searchsorted(r.t, x["t"])
        assert v_D[k - 1] * v_D[k] < 0
    assert np.count_nonzero(np.diff(np.sign(v_D)) != 0) == len(tr)
    np.testing.assert_allclose(np.abs(r.forces["friction_ram_guide"]), 0.1 * np.abs(r.forces["normal_ram_guide"]),
                               rtol=1e-12)


def test_no_friction_ignores_contacts():
    plain = simulate("slider_crank", variant="sustained_sliding", t_end=0.5, friction="none")
    again = simulate("slider_crank", variant="sustained_sliding", t_end=0.5, friction=None)
    np.testing.assert_array_equal(plain.q, again.q)
    assert plain.forces == {} and "work_friction_guide" not in plain.energies
    assert plain.meta["friction_left_out"] == again.meta["friction_left_out"] == ["guide"]


def test_the_default_is_the_parameter_sets_friction():
    """Without friction=, the contact's friction runs (exact stick/slip), the same run as friction='exact'."""
    default = simulate("slider_crank", variant="sustained_sliding", t_end=0.5)
    exact = simulate("slider_crank", variant="sustained_sliding", t_end=0.5, friction="exact")
    np.testing.assert_array_equal(default.q, exact.q)
    assert default.meta["friction"] == "exact" and default.energies["work_friction_guide"][-1] < 0


def test_bad_friction_options():
    with pytest.raises(ValueError, match="friction = 'coulomb' is not known; valid choices: exact, regularized, sign"):
        simulate("slider_crank", t_end=0.1, friction="coulomb")
    with pytest.raises(ValueError, match="friction='sign'"):
        simulate("slider_crank", t_end=0.1, friction="regularized", friction_sgn="sign")
    with pytest.raises(ValueError, match="friction_eps"):
        simulate("slider_crank", t_end=0.1, friction="regularized", friction_eps=0.0)
    from handwritten import cartesian_pendulum
    with pytest.raises(ValueError, match="no sliding contacts"):
        simulate(cartesian_pendulum(), [1.0, 0.0], [0.0, 0.0], t_end=0.1, friction="exact")
