"""The post-step projection law (study.laws.projection), compiled and through its source, on a point mass on the
unit circle typed here by hand: Phi = x^2 + y^2 - 1 (and the same row twice, a Jacobian of rank 1 everywhere)."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
from numba import njit, types

from study.kernels.signatures import KINEMATICS, KINEMATICS_T, V1, f8, i8
from study.laws.projection import NOT_CONVERGED, OK, project
from study.reference_data import tolerance
from study.solver.stabilization import Projection

MASSES = (2.0, 0.5)


def circle(q, p, phi, J, M):
    """Phi_k = (k + 1) (x^2 + y^2 - 1) for each of the r rows (r = phi.size), M = diag(MASSES)."""
    for k in range(phi.size):
        phi[k] = (k + 1) * (q[0] * q[0] + q[1] * q[1] - 1.0)
        J[k, 0], J[k, 1] = (k + 1) * 2.0 * q[0], (k + 1) * 2.0 * q[1]
    M[0, 0], M[0, 1], M[1, 0], M[1, 1] = MASSES[0], 0.0, 0.0, MASSES[1]


def _project(kinematics, q, qd, p, r, tol, mass, max_iter, rcond):
    """The law as the compiled loop calls it (the kinematics a first-class function)."""
    return project(kinematics, q, qd, p, r, tol, mass, max_iter, rcond)


@lru_cache(maxsize=None)
def compiled_pair():
    """(circle, the law) compiled for their signatures on first use, not when the module is collected (every
    xdist worker collects every file)."""
    law = njit(types.Tuple((types.boolean, i8))(KINEMATICS_T, V1, V1, V1, i8, f8, types.boolean, i8, f8))(_project)
    return njit(KINEMATICS)(circle), law


def run(backend: str, q, qd, r: int = 1, mass: bool = False, max_iter: int = 10):
    q, qd = np.array(q, dtype=float), np.array(qd, dtype=float)
    args = (q, qd, np.zeros(0), r, Projection().tol, mass, max_iter, tolerance("singular_ratio"))
    if backend == "compiled":
        kinematics, law = compiled_pair()
        changed, status = law(kinematics, *args)
    else:
        changed, status = project.py_func(circle, *args)
    return q, qd, changed, status


@pytest.mark.parametrize("backend", ["compiled", "source"])
@pytest.mark.parametrize("r", [1, 2])
def test_minimum_norm_projection_is_radial(backend, r):
    """W = I: each correction is along grad Phi (radial), so q goes to q / |q| and qd loses its radial part; the
    same with the row given twice (J J^T singular: the truncated least squares leaves the lost direction alone)."""
    q0, qd0 = np.array([1.1, 0.3]), np.array([0.4, -0.7])
    q, qd, changed, status = run(backend, q0, qd0, r)
    assert (changed, status) == (True, OK)
    n = q0 / np.linalg.norm(q0)
    tol = tolerance("round_off")
    assert np.abs(q - n).max() <= tol
    assert np.abs(qd - (qd0 - (qd0 @ n) * n)).max() <= tol * np.abs(qd0).max()


@pytest.mark.parametrize("backend", ["compiled", "source"])
def test_mass_weighted_velocity_projection(backend):
    """W = M: q ends on the circle, qd = qd0 - M^-1 J^T (J M^-1 J^T)^-1 J qd0 at the projected q."""
    qd0 = np.array([0.4, -0.7])
    q, qd, changed, status = run(backend, [1.1, 0.3], qd0, mass=True)
    assert (changed, status) == (True, OK)
    assert abs(q @ q - 1.0) <= Projection().tol
    J, Minv = 2.0 * q[None, :], np.diag([1.0 / m for m in MASSES])
    expected = qd0 - Minv @ J.T @ np.linalg.solve(J @ Minv @ J.T, J @ qd0)
    assert np.abs(qd - expected).max() <= tolerance("round_off") * np.abs(qd0).max()


@pytest.mark.parametrize("backend", ["compiled", "source"])
def test_on_the_manifold_nothing_changes(backend):
    q0, qd0 = np.array([0.6, 0.8]), np.array([-0.8, 0.6])
    q, qd, changed, status = run(backend, q0, qd0)
    assert (changed, status) == (False, OK)
    assert np.array_equal(q, q0) and np.array_equal(qd, qd0)


@pytest.mark.parametrize("backend", ["compiled", "source"])
def test_iteration_bound(backend):
    """From |q| = 3 one Gauss-Newton step reaches |q| = 5/3 only: not converged within max_iter = 1."""
    q, qd, changed, status = run(backend, [3.0, 0.0], [0.0, 1.0], max_iter=1)
    assert (changed, status) == (False, NOT_CONVERGED)
    assert abs(q[0] - 5.0 / 3.0) <= tolerance("round_off")


def test_reference_names_the_iteration_bound():
    """Projection.project raises the readable error around the law's status."""
    class Circle:
        n_constraints = 1

        @staticmethod
        def phi(q):
            return np.array([q @ q - 1.0])

        @staticmethod
        def phi_q(q):
            return 2.0 * q[None, :]

    with pytest.raises(RuntimeError, match=r"did not reach max\|Phi\| <= 1e-12 in 1 iterations \(max\|Phi\| = 1.78\)"):
        Projection(max_iter=1).project(Circle(), np.array([3.0, 0.0]), np.array([0.0, 1.0]))
    q, qd, changed = Projection().project(Circle(), np.array([1.1, 0.3]), np.array([0.4, -0.7]))
    assert changed and abs(q @ q - 1.0) <= Projection().tol and abs(q @ qd) <= Projection().tol
