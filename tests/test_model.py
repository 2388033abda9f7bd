"""Builder-derived equations: Jacobians, mass matrix, agreement with hand-written equations."""

import itertools

import numpy as np
import pytest

import handwritten
from study.mechanisms import initial_state, load
from study.reference_data import tolerance
from study.model.initial_state import consistent_initial_conditions

RNG_SEED = 20261121  # recorded seed of the random configurations


def configurations(eom, ps, count=12):
    """Assembled configurations along the crank's full turn, with random independent rates."""
    rng = np.random.default_rng(RNG_SEED)
    start = initial_state(ps, eom)
    out, guess = [], start.q.copy()
    for angle in np.linspace(start.q[0], start.q[0] + 2 * np.pi, count, endpoint=False):
        guess[0] = angle
        st = consistent_initial_conditions(eom, guess, [0], [rng.normal()])
        guess = st.q.copy()
        out.append((st.q, st.qd))
    return out


def fd_jacobian(f, x, h=1e-6):
    cols = [(f(x + h * e) - f(x - h * e)) / (2 * h) for e in np.eye(len(x))]
    return np.stack(cols, axis=-1)


@pytest.fixture(params=["slider_crank", "quick_return"])
def mechanism(request):
    return load(request.param, "seed")


def test_phi_q_matches_finite_differences(mechanism):
    ps, eom = mechanism
    tol = tolerance("finite_difference_jacobian")
    for q, qd in configurations(eom, ps):
        np.testing.assert_allclose(eom.phi_q(q), fd_jacobian(eom.phi, q), rtol=tol, atol=tol)


def test_gamma_matches_finite_differences(mechanism):
    ps, eom = mechanism
    tol = tolerance("finite_difference_jacobian")
    for q, qd in configurations(eom, ps):
        d_jqd = fd_jacobian(lambda x: eom.phi_q(x) @ qd, q)
        np.testing.assert_allclose(eom.gamma(q, qd), -d_jqd @ qd, rtol=tol, atol=tol * np.abs(qd).max() ** 2)


def test_potential_gradient_matches_finite_differences(mechanism):
    ps, eom = mechanism
    tol = tolerance("finite_difference_jacobian")
    zero = np.zeros(eom.n_coordinates)
    for q, _ in configurations(eom, ps):
        # forces at rest with the drive and loads removed is -dV/dq
        applied = sum(eom.applied_forces(0.0, q, zero).values(), zero)
        grad = -(eom.forces(0.0, q, zero) - applied)
        fd = fd_jacobian(lambda x: np.array([eom.potential_energy(x)]), q)[0]
        np.testing.assert_allclose(grad, fd, rtol=tol, atol=tol * np.abs(fd).max())


def test_mass_symmetric_positive_definite(mechanism):
    ps, eom = mechanism
    for q, _ in configurations(eom, ps, count=36):
        m = eom.mass(q)
        np.testing.assert_array_equal(m, m.T)
        assert np.linalg.eigvalsh(m).min() > tolerance("spd_min_eigenvalue")


def test_velocity_terms_from_kinetic_energy(mechanism):
    """C qd from the builder equals the Lagrange form d/dt(M qd) - dT/dq evaluated by differences."""
    ps, eom = mechanism
    tol = tolerance("finite_difference_jacobian")
    zero = np.zeros(eom.n_coordinates)
    for q, qd in configurations(eom, ps):
        dm = fd_jacobian(eom.mass, q)  # (m, m, m): dM/dq_k in the last axis
        mdot_qd = np.einsum("ijk,k,j->i", dm, qd, qd)
        dt_dq = 0.5 * np.einsum("ijk,i,j->k", dm, qd, qd)
        expected = mdot_qd - dt_dq
        got = -(eom.forces(0.0, q, qd) - eom.forces(0.0, q, zero))
        scale = np.abs(eom.mass(q)).max() * np.abs(qd).max() ** 2  # size of the terms that cancel
        np.testing.assert_allclose(got, expected, rtol=tol, atol=tol * scale)


@pytest.mark.parametrize("name,by_hand", [("slider_crank", handwritten.slider_crank),
                                          ("quick_return", handwritten.quick_return)])
def test_builder_agrees_with_handwritten(name, by_hand):
    """Same mechanism, written by hand from the corrected textbook formulas: agreement to round-off.

    The slider-crank's contact forces (F, friction) are not in ``forces``; the quick-return is
    compared with the cutting force off (variant loads compared separately below).
    """
    ps, eom = load(name, "smooth_cutting" if name == "quick_return" else "seed")
    hand = by_hand(ps.values)
    tol = tolerance("round_off")
    for q, qd in configurations(eom, ps):
        scale = np.abs(eom.mass(q)).max()
        np.testing.assert_allclose(eom.mass(q), hand.mass(q), rtol=tol, atol=tol * scale)
        np.testing.assert_allclose(eom.phi(q), hand.phi(q), atol=tol)
        np.testing.assert_allclose(eom.phi_q(q), hand.phi_q(q), rtol=tol, atol=tol)
        np.testing.assert_allclose(eom.gamma(q, qd), hand.gamma(q, qd), rtol=tol, atol=tol * 100)
        ours = eom.forces(0.0, q, qd) - eom.applied_forces(0.0, q, qd).get("cutting", 0.0)
        theirs = hand.forces(0.0, q, qd)
        np.testing.assert_allclose(ours, theirs, rtol=tol, atol=tol * np.abs(theirs).max())


def test_cutting_force_generalized_like_paper_b_matrix():
    """The builder's cutting load equals 001's B column [0, -l2 sin q2, -l3 sin q3] times F_x."""
    ps, eom = load("quick_return", "smooth_cutting")
    v = ps.values
    hand = handwritten.quick_return(v, cutting_force=lambda t, x, vx: handwritten.smooth_cutting_force(v, x, vx))
    tol = tolerance("round_off")
    for q, qd in configurations(eom, ps):
        theirs = hand.forces(0.0, q, qd)
        np.testing.assert_allclose(eom.forces(0.0, q, qd), theirs, rtol=tol, atol=tol * np.abs(theirs).max())


def test_on_off_cutting_law_indicators_and_modes():
    """The three switching functions against hand kinematics of D (x_D = l2 cos q2 + l3 cos q3), and the
    cut's generalized force F_cut dx_D/dq in the one mode that switches it on (v_D < 0 inside the window)."""
    ps, eom = load("quick_return", "seed")
    st = initial_state(ps, eom)
    g_tol = tolerance("switching_function_round_off")
    for q, qd in [(st.q, st.qd), (st.q, -st.qd)]:          # the ram moving either way
        v_d, lo, hi = eom.indicators(0.0, q, qd)
        x_d = ps.l2 * np.cos(q[1]) + ps.l3 * np.cos(q[2])
        v_hand = -ps.l2 * np.sin(q[1]) * qd[1] - ps.l3 * np.sin(q[2]) * qd[2]
        assert abs(v_d - v_hand) <= g_tol and v_hand != 0.0
        assert abs(lo - (x_d - ps.x_cut_min)) <= g_tol and abs(hi - (ps.x_cut_max - x_d)) <= g_tol
    dx_dq = np.array([0.0, -ps.l2 * np.sin(st.q[1]), -ps.l3 * np.sin(st.q[2])])
    for mode in itertools.product((-1, 1), repeat=3):
        cut = eom.applied_forces(0.0, st.q, st.qd, mode=mode)["cutting"]
        if mode == (-1, 1, 1):
            np.testing.assert_allclose(cut, ps.F_cut * dx_dq, rtol=tolerance("round_off"), atol=0)
        else:
            assert not np.any(cut), mode


def test_generated_code_is_cached(tmp_path, monkeypatch):
    from study.mechanisms import builder
    from study.model import compile as comp
    from study.params import load_parameters

    monkeypatch.setenv("STUDY_CACHE_DIR", str(tmp_path))
    ps = load_parameters("quick_return")
    calls = []
    real = comp.derive
    monkeypatch.setattr(comp, "derive", lambda b: calls.append(1) or real(b))
    comp.compile_description(builder(ps))
    comp.compile_description(builder(ps))
    assert len(calls) == 1
    assert len(list((tmp_path / "codegen").glob("quick_return_*.py"))) == 1


@pytest.mark.parametrize("change", ["axis", "mu"])
def test_a_contacts_geometry_and_law_reach_the_generated_codes_key(change):
    """The generated modules are cached by description_key: a fixed guide's axis (the sign of J_t) and its friction
    coefficients must change it, or a cached module with the old contact would be reused."""
    from study.mechanisms import builder
    from study.model.compile import description_key
    from study.params import load_parameters

    ps = load_parameters("slider_crank", "sustained_sliding")
    b = builder(ps)
    before = description_key(b)
    c = b.contacts[0]
    flipped = {"axis": {"tangent": tuple(-x for x in c.tangent)}, "mu": {"mu_kinetic": 2 * c.mu_kinetic}}[change]
    b.contacts[0] = type(c)(**{**vars(c), **flipped})
    assert description_key(b) != before
