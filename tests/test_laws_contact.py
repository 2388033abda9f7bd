"""The contact and pin solve at its one home (study.laws.contact), on problems solved by hand.

The numbers are chosen so that every intermediate value is exact in binary floating point: the expected values are
compared with ==.
"""

import numpy as np
import pytest

from study.laws.contact import (CONVERGED, OK, PAINLEVE_MANY, PAINLEVE_NONE, SCRATCH_ROWS, STEP_FAILED, STEPPED,
                                active_entries, contact_forces, pin_newton_step)
from study.reference_data import tolerance


def solve(qdd, lam, U, L, Jt, stick, s, mu_k, resistance):
    """contact_forces on one contact whose normal force is -lam[0]; (status, qdd, lam, f, normal)."""
    qdd, lam = np.array(qdd, dtype=float), np.array(lam, dtype=float)
    n = len(stick)
    stick, s = np.array(stick, dtype=bool), np.array(s, dtype=float)
    active = np.zeros(n, dtype=np.int64)
    n_act = active_entries(stick, s, active)
    f, normal = np.zeros(n), np.zeros(n)
    status = contact_forces(active, n_act, stick, s, np.array(Jt, dtype=float), np.zeros(n), qdd, lam,
                            np.array(U, dtype=float), np.array(L, dtype=float), np.zeros(n, dtype=np.int64),
                            np.array(mu_k, dtype=float), np.array(resistance, dtype=float), np.zeros((n, n)),
                            np.zeros(n, dtype=np.int64), np.zeros((SCRATCH_ROWS, n)), f, normal)
    return status, qdd, lam, f, normal


def test_block_sliding_on_a_floor():
    """A block of mass 2 kg in (x, y), y = 0 held by lambda, g = 10, pushed by 3 N along +x while sliding to +x:
    N = m g = 20 N, f = -(R + mu N) = -(1 + 0.5 * 20) = -11 N, x'' = (3 - 11) / 2 = -4 m/s^2; the floor's
    multiplier is unchanged (a tangential force does not load the floor: L = 0)."""
    status, qdd, lam, f, normal = solve(qdd=[1.5, 0.0], lam=[-20.0], U=[[0.5], [0.0]], L=[[0.0]], Jt=[[1.0, 0.0]],
                                        stick=[False], s=[1.0], mu_k=[0.5], resistance=[1.0])
    assert status == OK
    assert f[0] == -11.0 and normal[0] == 20.0
    assert qdd.tolist() == [-4.0, 0.0] and lam.tolist() == [-20.0]


def test_stuck_block_is_held_by_its_friction():
    """The same block at rest and stuck: f holds x'' = 0, so f = -3 N (the push's opposite), with no sign assumed."""
    status, qdd, _, f, normal = solve(qdd=[1.5, 0.0], lam=[-20.0], U=[[0.5], [0.0]], L=[[0.0]], Jt=[[1.0, 0.0]],
                                      stick=[True], s=[0.0], mu_k=[0.5], resistance=[1.0])
    assert status == OK
    assert f[0] == -3.0 and normal[0] == 20.0 and qdd.tolist() == [0.0, 0.0]


# One contact whose normal force responds to its own friction force, N = -(lambda_a + ell f) with lambda_a = -1, mu = 1,
# s = +1, R = 0. Sign hypothesis sigma: f = -sigma N, so N = 1 / (1 - sigma ell): sigma = +1 is consistent (N > 0)
# for ell < 1, sigma = -1 (N < 0) for ell < -1.
@pytest.mark.parametrize("ell, expected", [(0.5, OK), (2.0, PAINLEVE_NONE), (-2.0, PAINLEVE_MANY)])
def test_normal_force_sign_hypotheses(ell, expected):
    status, _, _, f, normal = solve(qdd=[0.0], lam=[-1.0], U=[[1.0]], L=[[ell]], Jt=[[1.0]], stick=[False],
                                    s=[1.0], mu_k=[1.0], resistance=[0.0])
    assert status == expected
    if expected == OK:   # N = 1 / (1 - 0.5) = 2, f = -N
        assert normal[0] == 2.0 and f[0] == -2.0


def pin_step(tau, dlam):
    """One pin with reaction R = (0, 4) N, mu r = 0.5 m, T0 = 0.5 N m, sliding with s = +1, delta = 0: the level
    T0 + mu r |R| is 2.5 N m."""
    tau = np.array([tau], dtype=float)
    outcome = pin_newton_step(np.array([0.0, 4.0]), np.array([0, 1], dtype=np.int64), np.array([dlam]), tau,
                              np.array([1.0]), np.array([0.5]), np.array([0.5]), 0.0,
                              tolerance("pin_friction_solve_rtol"), np.zeros(1), np.zeros(1), np.zeros(1),
                              np.zeros((1, 1)), np.zeros(1, dtype=np.int64))
    return outcome, tau[0]


def test_pin_newton_iterate():
    """With a reaction independent of the torque (d lambda / d tau = 0) the first iterate gives tau = -2.5 N m, the
    second finds it converged; a step whose Jacobian 1 + (mu r s / |R|) R . dR/dtau = 1 + 0.125 * 4 * (-2) is 0
    fails."""
    assert pin_step(0.0, [0.0, 0.0]) == (STEPPED, -2.5)
    assert pin_step(-2.5, [0.0, 0.0]) == (CONVERGED, -2.5)
    assert pin_step(0.0, [0.0, -2.0]) == (STEP_FAILED, 0.0)
