"""The post-step projection: q onto Phi = 0, then qd onto Phi_q qd = 0, in the metric W = I or W = M(q).

Each correction is the minimum-W-norm dq with Phi_q dq = -residual, by least squares truncated at ``rcond``
(``singular_ratio``; rank-revealing: at a singular pose the lost rows' directions are left alone, elsewhere it is
dq = -W^-1 Phi_q^T (Phi_q W^-1 Phi_q^T)^-1 residual). q is corrected by Gauss-Newton steps (residual Phi) until
max|Phi| <= tol, at most ``max_iter`` of them; then qd once (residual Phi_q qd).

:func:`project` is compiled for the compiled loop (``study.fast.project``, the kinematics a generated kernel) and
run through its own source, ``project.py_func``, by the reference path (``study.solver.stabilization.Projection``,
the kinematics the equations' Python callables); both call the compiled :func:`correction`.
"""

from __future__ import annotations

import numpy as np

from study.kernels.cache import internal, kernel

OK, NOT_CONVERGED = 0, 1


@kernel()
def correction(J, M, mass, residual, rcond):
    """The minimum-W-norm dq with J dq = -residual (W = M if ``mass``, else I; M is read only then)."""
    if mass:
        L = np.linalg.cholesky(M)                               # M = L L^T, dq = L^-T dz
        JL = np.linalg.solve(L, J.T).T                          # J L^-T
        dz = np.linalg.lstsq(JL, residual, rcond)[0]
        return -np.linalg.solve(L.T, dz)
    return -np.linalg.lstsq(J, residual, rcond)[0]


@internal()
def project(kinematics, q, qd, p, r, tol, mass, max_iter, rcond):
    """Project q (m,) and qd (m,) in place; returns (changed, status): status NOT_CONVERGED when max|Phi| > tol
    after ``max_iter`` corrections (q is then the last iterate). ``kinematics(q, p, phi, J, M)`` writes Phi, Phi_q
    and (if ``mass``) M at q (signature ``study.kernels.signatures.KINEMATICS``)."""
    m = q.size
    phi, J, M = np.empty(r), np.empty((r, m)), np.empty((m, m))
    kinematics(q, p, phi, J, M)
    if r == 0 or (np.max(np.abs(phi)) <= tol and np.max(np.abs(J @ qd)) <= tol):
        return False, OK
    converged = False
    for _ in range(max_iter):
        if np.max(np.abs(phi)) <= tol:
            converged = True
            break
        q += correction(J, M, mass, phi, rcond)
        kinematics(q, p, phi, J, M)
    if not converged:
        return False, NOT_CONVERGED
    qd += correction(J, M, mass, J @ qd, rcond)
    return True, OK
