"""Consistent initial conditions (001 eqs. 6-7)."""

import numpy as np
import pytest

import handwritten
from study.mechanisms import initial_state, load
from study.reference_data import tolerance
from study.model.initial_state import InitialConditionError, consistent_initial_conditions, constraint_residuals

PRINTED_QUICK_RETURN_Q = [3.0020, 2.1628, 2.7751]      # 001 sec. 4
PRINTED_QUICK_RETURN_QD = [6.2832, 2.3656, -2.9769]


def test_quick_return_reproduces_printed_digits():
    ps, eom = load("quick_return")
    assert list(ps.initial.printed_q) == PRINTED_QUICK_RETURN_Q  # the file holds what the paper prints
    st = initial_state(ps, eom)
    assert st.q[0] == 3.0020 and st.qd[0] == pytest.approx(2 * np.pi, abs=0)
    tol = tolerance("printed_digits")
    np.testing.assert_allclose(st.q, PRINTED_QUICK_RETURN_Q, rtol=0, atol=tol)
    np.testing.assert_allclose(st.qd, PRINTED_QUICK_RETURN_QD, rtol=0, atol=tol)
    assert st.phi_residual < 1e-13 and st.velocity_residual < 1e-12


def test_slider_crank_printed_state_violates_constraints():
    ps, eom = load("slider_crank")
    phi, phidot = constraint_residuals(eom, ps.initial.printed_q, ps.initial.printed_qd)
    # y_B = l1 sin(pi/6) - l2 sin(pi/6 + 0.0834) = 0.5 - 10 sin(0.6070): the slider is 5.2 m off its guide
    assert phi[0] == pytest.approx(0.5 - 10 * np.sin(np.pi / 6 + 0.0834), rel=1e-12)
    assert abs(phi[0]) > 5.0
    assert abs(phidot[0]) > 1e-4


def test_slider_crank_consistent_branch():
    ps, eom = load("slider_crank")
    st = initial_state(ps, eom)
    v = ps.values
    expected_q2 = np.arcsin(v.l1 * np.sin(np.pi / 6) / v.l2) - np.pi / 6  # branch cos(q1+q2) > 0
    assert st.q[1] == pytest.approx(expected_q2, abs=1e-14)
    d12 = v.l1 * np.cos(st.q[0]) / (v.l2 * np.cos(st.q[0] + st.q[1])) - 1  # 000 eq. (24)
    assert st.qd[1] == pytest.approx(d12 * 0.001, rel=1e-12)
    assert np.cos(st.q[0] + st.q[1]) > 0


def test_dead_centre_is_reported():
    """Quick-return with q2 independent at the rocker's extreme: Phi_v is singular."""
    eom = handwritten.cartesian_pendulum()
    with pytest.raises(InitialConditionError, match="singular"):
        consistent_initial_conditions(eom, [1.0, 0.0], independent=[0], qd_independent=[0.0])


def test_non_convergence_is_reported():
    eom = handwritten.cartesian_pendulum(length=1.0)
    with pytest.raises(InitialConditionError, match="did not converge"):
        consistent_initial_conditions(eom, [2.0, 0.5], independent=[0], qd_independent=[0.0], max_iter=3)


def test_bad_independent_set():
    ps, eom = load("quick_return")
    with pytest.raises(ValueError, match="degrees of freedom"):
        consistent_initial_conditions(eom, ps.initial.printed_q, [0, 1], [1.0, 1.0])
