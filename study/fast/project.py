"""Compiled post-step projection (``study.solver.stabilization.Projection.project``).

q is moved onto Phi = 0 by Gauss-Newton corrections dq = -W^-1 Phi_q^T (Phi_q W^-1 Phi_q^T)^-1 Phi
(W = I or M), then qd onto Phi_q qd = 0 with the same metric.
"""

from __future__ import annotations

import numpy as np

from study.kernels.cache import internal
from study.fast.dynamics import CF_PROJ_TOL, CI_PROJ_MASS, CI_PROJ_MAXITER
from study.kernels.linalg import lu_factor, lu_solve

OK, SINGULAR, NOT_CONVERGED = 0, 1, 4


@internal()
def _correct(J, M, mass, residual, out):
    """out = -W^-1 J^T (J W^-1 J^T)^-1 residual; returns False if a system is singular."""
    r, m = J.shape
    WJt = np.empty((m, r))
    if mass:
        Mf = M.copy()
        piv = np.empty(m, np.int64)
        if not lu_factor(Mf, piv):
            return False
        col = np.empty(m)
        for k in range(r):
            for i in range(m):
                col[i] = J[k, i]
            lu_solve(Mf, piv, col)
            for i in range(m):
                WJt[i, k] = col[i]
    else:
        for i in range(m):
            for k in range(r):
                WJt[i, k] = J[k, i]
    S = np.empty((r, r))
    for a in range(r):
        for b in range(r):
            acc = 0.0
            for i in range(m):
                acc += J[a, i] * WJt[i, b]
            S[a, b] = acc
    pr = np.empty(r, np.int64)
    if not lu_factor(S, pr):
        return False
    z = residual.copy()
    lu_solve(S, pr, z)
    for i in range(m):
        acc = 0.0
        for k in range(r):
            acc += WJt[i, k] * z[k]
        out[i] = -acc
    return True


@internal()
def project(kinematics, y, p, ci, cf, m, r):
    """Project y = [q, qd, ...] in place; returns (changed, status)."""
    tol, mass, max_iter = cf[CF_PROJ_TOL], ci[CI_PROJ_MASS] == 1, ci[CI_PROJ_MAXITER]
    q, qd = y[:m].copy(), y[m:2 * m].copy()
    phi, J, M = np.empty(r), np.empty((r, m)), np.empty((m, m))
    dq, v = np.empty(m), np.empty(r)
    kinematics(q, p, phi, J, M)
    big_phi, big_v = 0.0, 0.0
    for k in range(r):
        acc = 0.0
        for i in range(m):
            acc += J[k, i] * qd[i]
        v[k] = acc
        big_phi, big_v = max(big_phi, abs(phi[k])), max(big_v, abs(acc))
    if big_phi <= tol and big_v <= tol:
        return False, OK
    converged = False
    for _ in range(max_iter):
        if np.max(np.abs(phi)) <= tol:
            converged = True
            break
        if not _correct(J, M, mass, phi, dq):
            return False, SINGULAR
        for i in range(m):
            q[i] += dq[i]
        kinematics(q, p, phi, J, M)
    if not converged:
        return False, NOT_CONVERGED
    for k in range(r):
        acc = 0.0
        for i in range(m):
            acc += J[k, i] * qd[i]
        v[k] = acc
    if not _correct(J, M, mass, v, dq):
        return False, SINGULAR
    for i in range(m):
        y[i] = q[i]
        y[m + i] = qd[i] + dq[i]
    return True, OK
