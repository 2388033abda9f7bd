"""The Exudyn models generated from the descriptions (study.exudyn_models.translate): constraints,
reactions at t = 0, index-2 drift, explicit solvers, and the guarded reaction reading of the
friction user function.

Every tolerance comes from ``reference/cross_validation.toml`` (with its reason). Quantities of the
in-house side (Phi, the multipliers at t = 0) are computed here from the in-house equations.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from cross_validation.frictionless_runs import FINE_STEP, frictionless_run
from study import mechanisms
from study.exudyn_models import ExudynModelError, initial_accelerations, run
from study.exudyn_models import settings as common
from study.exudyn_models.translate import build
from study.model.joints import Distance
from study.params import available_mechanisms, available_variants, load_parameters
from study.reference_data import tolerance
from study.results import SimulationResult
from study.solver.accelerations import Multiplier

MECHANISMS = tuple(available_mechanisms())
# The N-four-bar's largest sizes take 5-20 s each: they run with the slow tests (make verify).
LARGE = {("n_four_bar", "n20"), ("n_four_bar", "n40")}
CASES = [pytest.param(name, variant, marks=pytest.mark.slow) if (name, variant) in LARGE else (name, variant)
         for name in MECHANISMS for variant in available_variants(name)]


def tol(key: str) -> float:
    return tolerance(key, table="cross_validation")


def observed_orders(errors) -> np.ndarray:
    """log2 of successive error ratios for step sizes halving."""
    e = np.asarray(errors, dtype=float)
    return np.log2(e[:-1] / e[1:])


def inhouse_multipliers(eom, t, q, qd, extra_force=None):
    """qdd and lambda of the in-house saddle-point system at a state (plus an optional extra Q)."""
    Q = eom.forces(t, q, qd) + (0.0 if extra_force is None else extra_force)
    return Multiplier().solve(eom.mass(q), Q, eom.phi_q(q), eom.gamma(q, qd))


def gamma_share(eom, q, qd):
    """The part of lambda produced by the velocity term gamma alone (zero applied forces)."""
    m = eom.n_coordinates
    return Multiplier().solve(eom.mass(q), np.zeros(m), eom.phi_q(q), eom.gamma(q, qd))[1]


# ---------------------------------------------------------------------------------------------
# (a) every model runs; index 3 keeps the in-house Phi at round-off
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name,variant", CASES)
def test_index3_keeps_inhouse_phi_at_round_off(name, variant):
    ps, eom = mechanisms.load(name, variant)
    state = mechanisms.initial_state(ps, eom)
    scale = mechanisms.time_scale(name)                      # 500 steps over half the mechanism's time scale
    r = run(ps, 0.5 * scale, 1e-3 * scale)
    assert isinstance(r, SimulationResult)
    assert r.t.shape == (501,) and r.t[-1] == pytest.approx(0.5 * scale)
    assert r.q.shape == (501, eom.n_coordinates) and r.lam.shape == (501, eom.n_constraints)
    np.testing.assert_array_equal(r.q[0], state.q)          # the in-house consistent state, mapped back
    np.testing.assert_allclose(r.qd[0], state.qd, rtol=0, atol=1e-15 * max(1.0, np.abs(state.qd).max()))
    distance = any(isinstance(j, Distance) for j in mechanisms.description(ps).joints)
    assert np.abs(r.phi).max() <= tol("phi_newton_distance" if distance else "phi_roundoff"), \
        f"max|Phi| = {np.abs(r.phi).max():.3e}"
    assert np.abs(np.diff(r.q, axis=0)).max() < np.pi / 4    # continuous angles: no 2 pi jumps
    assert np.all(np.isfinite(r.qdd)) and np.all(np.isfinite(r.lam))
    assert r.meta["engine"] == "exudyn" and r.meta["parameter_hash"] == ps.sha256
    assert r.meta["coordinate_names"] == list(eom.coordinate_names)
    assert r.stats["steps"] == 500 and r.stats["newton_iterations"] >= 500 and r.stats["cpu_seconds"] > 0


def test_index2_drift_is_not_round_off_and_shrinks_at_order_two():
    """Index 2 enforces velocity constraints only: Phi drifts, by O(h^2) (the integrated O(h^2)
    velocity-level error), through the first cut at the steps that resolve the smooth law. The runs (the variant
    has no friction) are test_against_inhouse.py's, made once (frictionless_runs.py)."""
    h = tol("cut_steps")
    steps = [h, h / 2, h / 4]
    drift = [np.abs(frictionless_run("quick_return", "smooth_cutting", tol("cut_window"), s, "index2",
                                     FINE_STEP).phi).max() for s in steps]
    assert min(drift) > 1e3 * tol("phi_roundoff"), drift
    p = observed_orders(drift)
    assert np.all(p >= tol("min_order")), f"drift {drift}, orders {p}"


def test_output_step_samples_the_step_grid():
    ps = load_parameters("slider_crank", "sustained_sliding")
    every = run(ps, 0.1, 1e-3)
    sampled = run(ps, 0.1, 1e-3, output_step=0.01)
    np.testing.assert_allclose(sampled.t, np.linspace(0.0, 0.1, 11), rtol=0, atol=1e-15)
    for key in ("q", "qd", "qdd", "lam", "phi"):
        np.testing.assert_array_equal(getattr(sampled, key), getattr(every, key)[::10])
    for key, value in sampled.energies.items():     # work integrated at every step, then sampled
        np.testing.assert_array_equal(value, every.energies[key][::10])


@pytest.mark.parametrize("kwargs,message", [
    (dict(solver="rk45"), "valid choices: index3, index2, explicit_euler, rk44, dopri5"),
    (dict(friction="coulomb"), "valid choices: regularized, none"),
    (dict(h=0.0), "h = 0.0 must be a finite number > 0"),
    (dict(t_end=-1.0), "t_end = -1.0 must be a finite number > 0"),
    (dict(eps=0.0), "eps = 0.0 must be a finite number > 0"),
    (dict(output_step=1.5e-3), "must be a whole multiple of h"),
    (dict(t_end=0.0105), "must be a whole number of steps"),
    (dict(linear_solver="lu"), "unknown linear solver 'lu'; valid choices: dense, sparse"),
    (dict(linear_solver="sparse", ignore_singular=True), "ignore_singular = True needs the dense linear solver"),
    (dict(newton_tolerance=1.0), "newton_tolerance = 1.0 must be a number in (0, 1)"),
])
def test_bad_arguments_raise_value_error(kwargs, message):
    ps = load_parameters("slider_crank", "seed")
    args = dict(t_end=0.01, h=1e-3) | kwargs
    with pytest.raises(ValueError, match=re.escape(message)):
        run(ps, **args)


# The N-four-bar seed over 1 s crosses its first horizontal (singular) position at ~0.714 s. Its multipliers are left
# out there: at the crossing Phi_q loses rank and the split of the reactions among the joints is not determined by
# the Newton residual (the two linear solvers differ by 3.2e-4 N of 28 N one sample after it). The four-bar
# (the description-only mechanism, no singular position) checks the multipliers too.
@pytest.mark.parametrize("name,variant,t_end,keys", [("n_four_bar", "seed", 1.0, ("q", "qd")),
                                                     ("four_bar", "seed", 0.5, ("q", "qd", "lam"))])
def test_sparse_and_dense_linear_solvers_agree_to_the_newton_tolerance(name, variant, t_end, keys):
    """Exudyn's dense inverse and Eigen's sparse LU solve the same Newton systems: each step is accepted once its
    residual is below the Newton tolerance, so the runs differ by at most that relative amount per step (the bound
    of the python/tuned configurations, reference/tolerances.toml exudyn_configuration_agreement_per_step)."""
    ps = load_parameters(name, variant)
    h = 1e-3
    dense, sparse = (run(ps, t_end, h, output_step=0.01, linear_solver=ls) for ls in ("dense", "sparse"))
    assert (dense.meta["linear_solver"], sparse.meta["linear_solver"]) == ("dense", "sparse")
    assert dense.meta["newton_tolerance"] == sparse.meta["newton_tolerance"] == common.NEWTON_TOLERANCE
    assert "EigenSparse" in sparse.meta["linear_solver_description"]
    allowed = tolerance("exudyn_configuration_agreement_per_step") * round(t_end / h)
    for key in keys:
        a, b = getattr(dense, key), getattr(sparse, key)
        assert np.max(np.abs(b - a)) <= allowed * np.max(np.abs(a)), key


def test_the_sparse_solver_reuses_its_analyzed_pattern_without_changing_a_bit(monkeypatch):
    """The sparse runs reuse the analyzed pattern of the Newton matrix (settings.simulation_settings), which only saves
    the ordering's analysis: across the N-four-bar's singular crossing (~0.714 s) the run is the same bit for bit as
    with a fresh analysis at every factorization."""
    ps = load_parameters("n_four_bar", "seed")
    reused = run(ps, 1.0, 1e-3, output_step=0.01, linear_solver="sparse")
    settings_of = common.simulation_settings

    def fresh_analysis(*args, **kwargs):
        s = settings_of(*args, **kwargs)
        assert s.linearSolver.reuseAnalyzedPattern
        s.linearSolver.reuseAnalyzedPattern = False
        return s
    monkeypatch.setattr(common, "simulation_settings", fresh_analysis)
    fresh = run(ps, 1.0, 1e-3, output_step=0.01, linear_solver="sparse")
    for key in ("q", "qd", "qdd", "lam"):
        assert np.array_equal(getattr(reused, key), getattr(fresh, key)), key
    assert reused.stats["newton_iterations"] == fresh.stats["newton_iterations"]


def test_no_solution_folder_is_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run(load_parameters("quick_return", "guide_friction"), 0.01, 1e-3)
    run(load_parameters("slider_crank", "seed"), 0.01, 1e-3, solver="index2")
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------------
# (b) reactions at t = 0 against the in-house multipliers
# ---------------------------------------------------------------------------------------------
def test_initial_reactions_match_inhouse_multipliers_quick_return():
    """Frictionless quick-return at its consistent initial state (crank at 2 pi rad/s).

    In-house lam1 is the block-on-rocker row (rocker pushes the block with -lam1 n), lam2 the
    ram-guide row f2 = h2 - y_D (guide pushes the ram with (0, lam2)). The remaining discrepancy is
    Exudyn's numerically differentiated velocity term (see reaction_velocity_term_relative).
    """
    ps, eom = mechanisms.load("quick_return", "smooth_cutting")
    s = mechanisms.initial_state(ps, eom)
    _, lam = inhouse_multipliers(eom, 0.0, s.q, s.qd)
    bound = tol("reaction_velocity_term_relative") * np.abs(gamma_share(eom, s.q, s.qd))
    r = run(ps, 0.01, 1e-3)
    exudyn_normal = np.array([r.forces["joint_block_on_rocker_n"][0], r.forces["normal_ram_guide"][0]])
    assert np.all(np.abs(r.lam[0] - lam) <= bound), f"Exudyn {r.lam[0]}, in-house {lam}, bound {bound}"
    assert np.all(np.abs(exudyn_normal - (-lam)) <= bound)
    qdd0, lam0 = initial_accelerations(ps, s.q, s.qd)     # the same solve, without stepping
    np.testing.assert_array_equal(lam0, r.lam[0])
    np.testing.assert_array_equal(qdd0, r.qdd[0])


@pytest.mark.parametrize("name,variant,kwargs", [
    ("quick_return", "smooth_cutting", {}),
    ("quick_return", "seed", {}),
    ("slider_crank", "seed", dict(friction="none")),
    ("four_bar", "seed", {}),
])
def test_initial_reactions_at_zero_velocity_agree_to_round_off(name, variant, kwargs):
    """Without velocity terms both codes solve the same linear system: only round-off remains."""
    ps, eom = mechanisms.load(name, variant)
    q = mechanisms.initial_state(ps, eom).q
    qd = np.zeros_like(q)
    qdd, lam = inhouse_multipliers(eom, 0.0, q, qd)
    qdd_x, lam_x = initial_accelerations(ps, q, qd, **kwargs)
    rel = tol("reaction_zero_velocity_relative")
    np.testing.assert_allclose(lam_x, lam, rtol=rel, atol=0)
    np.testing.assert_allclose(qdd_x, qdd, rtol=0, atol=rel * np.abs(qdd).max())


@pytest.mark.parametrize("name,variant,kwargs", [
    ("quick_return", "smooth_cutting", {}),
    ("slider_crank", "sustained_sliding", dict(friction="none")),
    ("four_bar", "seed", {}),
    ("a01_pendulum", "seed", {}),     # a distance constraint: its Exudyn output is a scalar
])
def test_initial_accelerations_and_multipliers_match_inhouse(name, variant, kwargs):
    """Every mechanism at its consistent initial state (velocities on, frictionless): Exudyn's
    initial-acceleration solve against the in-house saddle-point solve. Only Exudyn's numerically
    differentiated velocity term separates them (reaction_velocity_term_relative, taken relative to
    the part of lambda and of qdd that the velocity term gamma produces)."""
    ps, eom = mechanisms.load(name, variant)
    s = mechanisms.initial_state(ps, eom)
    qdd, lam = inhouse_multipliers(eom, 0.0, s.q, s.qd)
    qdd_g, lam_g = Multiplier().solve(eom.mass(s.q), np.zeros(eom.n_coordinates), eom.phi_q(s.q),
                                      eom.gamma(s.q, s.qd))
    qdd_x, lam_x = initial_accelerations(ps, s.q, s.qd, **kwargs)
    rel, vel = tol("reaction_zero_velocity_relative"), tol("reaction_velocity_term_relative")
    assert np.all(np.abs(lam_x - lam) <= rel * np.abs(lam) + vel * np.abs(lam_g)), f"Exudyn {lam_x}, in-house {lam}"
    bound = rel * np.abs(qdd).max() + vel * np.abs(qdd_g).max()
    assert np.abs(qdd_x - qdd).max() <= bound, f"Exudyn {qdd_x}, in-house {qdd}"


def test_initial_state_with_friction_slider_crank():
    """Slider-crank at t = 0 with friction: Exudyn's seeded initial solve against an in-house fixed
    point of M qdd + Phi_q^T lam = Q + t_q^T F_t(N), N = -lam, F_t = -(F + mu|N|) tanh(v_B/eps)."""
    ps, eom = mechanisms.load("slider_crank", "sustained_sliding")
    s = mechanisms.initial_state(ps, eom)
    contact = eom.contacts[0]
    jt, v_b = contact.tangent_jacobian(s.q), float(contact.tangent_jacobian(s.q) @ s.qd)
    eps = common.DEFAULT_EPS
    lam = inhouse_multipliers(eom, 0.0, s.q, s.qd)[1]
    for _ in range(50):
        f_t = -(contact.resistance + contact.mu_kinetic * abs(lam[0])) * np.tanh(v_b / eps)
        qdd, lam = inhouse_multipliers(eom, 0.0, s.q, s.qd, jt * f_t)
    r = run(ps, 0.01, 1e-3)
    bound = tol("reaction_zero_velocity_relative") * np.abs(lam) + \
        tol("reaction_velocity_term_relative") * np.abs(gamma_share(eom, s.q, s.qd))
    assert np.all(np.abs(r.lam[0] - lam) <= bound), f"Exudyn {r.lam[0]}, in-house {lam}"
    coulomb = -contact.mu_kinetic * abs(lam[0]) * np.tanh(v_b / eps)
    assert r.forces["friction_guide"][0] == pytest.approx(coulomb, rel=tol("reaction_zero_velocity_relative"))
    assert r.stats["seed_iterations"] >= 2


# (c) the convergence order of the smooth quick-return through the cut is checked against the in-house
# reference in test_against_inhouse.py (not against a finer Exudyn run, which would compare Exudyn with itself)


# ---------------------------------------------------------------------------------------------
# (d) Exudyn's explicit solvers refuse the constrained models
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", MECHANISMS)
@pytest.mark.parametrize("solver", common.EXPLICIT_SOLVERS)
def test_explicit_solvers_refuse_joint_constraints(name, solver):
    ps, eom = mechanisms.load(name, "seed")
    s = mechanisms.initial_state(ps, eom)
    with pytest.raises(ExudynModelError, match=r"^SolverExplicit: explicit integrator detected object (\d+) which "
                                               r"contains constraints that cannot be solved; aborting solver") as exc:
        run(ps, 0.01, 1e-3, solver=solver)
    built = build(ps, s.q, s.qd)
    first_joint = int(built.model.joints[built.d.joints[0].name][0])   # the first constraint object
    assert int(re.search(r"object (\d+)", str(exc.value)).group(1)) == first_joint


# ---------------------------------------------------------------------------------------------
# (e) the friction user function uses the converged normal force (the guard works)
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("variant", ["seed", "sustained_sliding", "slip_then_stick"])
def test_slider_crank_friction_uses_converged_normal_force(variant):
    """friction_guide / resistance_guide = mu |N| / F at every sample, N the converged reaction.

    Both parts share tanh(v_B/eps), so the relation holds independently of v_B; the unguarded zero
    first iterate would give friction 0, a one-step lag a ~5e-5 relative error.
    """
    ps = load_parameters("slider_crank", variant)
    r = run(ps, 0.5, 1e-3)
    v = ps.values
    n = r.forces["normal_guide"]
    expected = v.mu * np.abs(n) * r.forces["resistance_guide"] / v.F
    err = np.abs(r.forces["friction_guide"] - expected) / (v.mu * np.abs(n))
    assert err.max() <= tol("friction_relation_relative"), f"max relative deviation {err.max():.3e}"
    assert np.all(np.abs(r.forces["friction_guide"]) > 0)
    # the zero first iterate really occurred at every step and was replaced by the guard
    assert r.stats["friction_guard_substitutions"] >= r.stats["steps"]


def test_quick_return_guide_friction_uses_converged_normal_force():
    ps = load_parameters("quick_return", "guide_friction")
    v = ps.values
    r = run(ps, 0.5, 1e-3)
    q, qd = r.q, r.qd
    v_d = -v.l2 * np.sin(q[:, 1]) * qd[:, 1] - v.l3 * np.sin(q[:, 2]) * qd[:, 2]
    limit = v.mu_guide * np.abs(r.forces["normal_ram_guide"])
    friction = r.forces["friction_ram_guide"]
    rel = tol("friction_relation_relative")
    assert np.all(np.abs(friction) <= limit * (1 + rel))
    fast = np.abs(v_d) >= tol("friction_saturation_speed")
    assert fast.sum() > 0.9 * len(v_d)
    np.testing.assert_allclose(friction[fast], -np.sign(v_d[fast]) * limit[fast], rtol=rel, atol=0)
    assert r.stats["friction_guard_substitutions"] >= r.stats["steps"]
