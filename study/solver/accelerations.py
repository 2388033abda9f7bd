"""Acceleration solvers: given M, Q, Phi_q and the acceleration right-hand side c, find qdd and lambda.

    M qdd + Phi_q^T lambda = Q,        Phi_q qdd = c        (c = gamma + stabilization term)

Three ways, chosen by name (``ACCELERATION_SOLVERS``):

- ``multiplier``: the saddle-point (augmented) system, solved directly.
- ``partitioned``: coordinate partitioning, papers 000/001's null-space matrix R = [E; -Phi_v^-1 Phi_u]
  (000 calls D = R^T): [R^T M; Phi_q] qdd = [R^T Q; c]. The dependent coordinates v are chosen by
  column-pivoted QR of Phi_q and chosen again when Phi_v becomes ill-conditioned; switches are recorded.
- ``orthonormal``: an orthonormal null-space basis N of Phi_q (from QR of Phi_q^T):
  qdd = Phi_q^+ c + N z with (N^T M N) z = N^T (Q - M Phi_q^+ c).
- ``augmented_lagrangian``: the acceleration-level augmented Lagrangian of Bayo, Garcia de Jalon and
  Serna (1988): (M + alpha Phi_q^T Phi_q) qdd_{i+1} = Q - Phi_q^T lambda_i + alpha Phi_q^T c,
  lambda_{i+1} = lambda_i + alpha (Phi_q qdd_{i+1} - c). Its matrix is positive-definite whatever the
  rank of Phi_q, so it needs no rank decision: it passes singular poses and redundant constraints
  (``passes_singular``). The first three need a full-rank Phi_q; a run with them stops at a singular
  pose (``study.solver.checks.SingularityMonitor``).

Each returns lambda too, from the projection of M qdd - Q onto the range of Phi_q^T.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
from scipy.linalg.lapack import dpotrf, dpotrs

Array = np.ndarray


class AccelerationSolver:
    """Contract: ``solve(M, Q, J, c) -> (qdd, lam)`` with shapes (m,m), (m,), (r,m), (r,) -> (m,), (r,).

    Subclasses implement ``_solve``. A solver may keep state between calls (the partition), so a
    simulation creates its own instance.
    """

    name = ""
    #: whether the solver is defined for a rank-deficient Phi_q (then a run does not stop at singular poses)
    passes_singular = False

    def solve(self, M: Array, Q: Array, J: Array, c: Array) -> tuple[Array, Array]:
        if J.shape[0] == 0:
            return np.linalg.solve(M, Q), np.zeros(0)
        return self._solve(M, Q, J, c)

    def _solve(self, M, Q, J, c):  # pragma: no cover - abstract
        raise NotImplementedError

    def statistics(self) -> dict:
        return {}


class Multiplier(AccelerationSolver):
    """Augmented saddle-point form [[M, J^T], [J, 0]] [qdd; lambda] = [Q; c]."""

    name = "multiplier"

    def _solve(self, M, Q, J, c):
        m, r = M.shape[0], J.shape[0]
        K = np.zeros((m + r, m + r))
        K[:m, :m] = M
        K[:m, m:] = J.T
        K[m:, :m] = J
        x = np.linalg.solve(K, np.concatenate([Q, c]))
        return x[:m], x[m:]


@dataclass
class Partitioned(AccelerationSolver):
    """Coordinate partitioning with the null-space matrix R = [E; -Phi_v^-1 Phi_u] (001 eq. 8, 000 eq. 24).

    Parameters
    ----------
    switch_cond : float
        Re-choose the dependent coordinates when sigma_max(Phi_q) / sigma_min(Phi_v) exceeds this
        (Phi_v is nearly singular compared with the full Jacobian). 1e3: beyond it the elimination
        loses ~3 digits more than a well-chosen partition (near a dead centre of the current
        partition), well before it becomes singular.
    """

    switch_cond: float = 1e3
    name: str = "partitioned"
    dependent: tuple[int, ...] | None = None
    switches: list = field(default_factory=list)

    def choose(self, J: Array) -> tuple[int, ...]:
        _, _, piv = sla.qr(J, mode="economic", pivoting=True)
        return tuple(sorted(int(i) for i in piv[: J.shape[0]]))

    def _ill_conditioned(self, J: Array) -> bool:
        smallest = np.linalg.svd(J[:, list(self.dependent)], compute_uv=False).min()
        return not smallest * self.switch_cond > np.linalg.norm(J, 2)

    def null_space_matrix(self, J: Array) -> Array:
        """R (m, n) with J R = 0 and R[u] = E for the independent coordinates u."""
        m, r = J.shape[1], J.shape[0]
        if self.dependent is None or self._ill_conditioned(J):
            new = self.choose(J)
            if self.dependent is not None and new != self.dependent:
                self.switches.append((self.dependent, new))
            self.dependent = new
        dep = list(self.dependent)
        ind = [i for i in range(m) if i not in self.dependent]
        R = np.zeros((m, m - r))
        R[ind, :] = np.eye(m - r)
        R[dep, :] = -np.linalg.solve(J[:, dep], J[:, ind])
        return R

    def _solve(self, M, Q, J, c):
        R = self.null_space_matrix(J)
        A = np.vstack([R.T @ M, J])
        qdd = np.linalg.solve(A, np.concatenate([R.T @ Q, c]))
        dep = list(self.dependent)
        lam = np.linalg.solve(J[:, dep].T, (Q - M @ qdd)[dep])  # rows v of M qdd + J^T lam = Q
        return qdd, lam

    def statistics(self) -> dict:
        return {"partition_switches": len(self.switches), "dependent_coordinates": list(self.dependent or ())}


class Orthonormal(AccelerationSolver):
    """Orthonormal null-space basis from a full QR of Phi_q^T."""

    name = "orthonormal"

    def _solve(self, M, Q, J, c):
        r = J.shape[0]
        Qf, Rf = np.linalg.qr(J.T, mode="complete")
        Y, N = Qf[:, :r], Qf[:, r:]
        qp = Y @ np.linalg.solve(Rf[:r].T, c)       # particular solution, J qp = c
        z = np.linalg.solve(N.T @ M @ N, N.T @ (Q - M @ qp))
        qdd = qp + N @ z
        lam = np.linalg.solve(Rf[:r], Y.T @ (Q - M @ qdd))
        return qdd, lam


@dataclass
class AugmentedLagrangian(AccelerationSolver):
    """Acceleration-level augmented Lagrangian (Bayo, Garcia de Jalon, Serna 1988, Comput. Methods Appl.
    Mech. Eng. 71; the formulation family of the IFToMM benchmark reference solutions).

    Iterates, from lambda_0 = 0,

        (M + alpha J^T J) qdd_{i+1} = Q - J^T lambda_i + alpha J^T c
        lambda_{i+1} = lambda_i + alpha (J qdd_{i+1} - c)

    with one Cholesky factorization per call. A fixed point satisfies M qdd + J^T lambda = Q and, where
    c lies in the range of J, J qdd = c. A component of c outside that range (a drifted state at a
    singular pose) only moves lambda along the null space of J^T, which J^T removes: qdd is unaffected.
    In a direction where J has the singular value sigma the error contracts by m / (m + alpha sigma^2)
    per iteration (m the mass scale), so away from singular poses a few iterations reach round-off and
    only within sigma ~ sqrt(m / alpha) of a singular pose the iteration stops at ``max_iter`` with the
    penalty-regularized acceleration (counted in ``statistics()['unconverged']``).

    Parameters
    ----------
    penalty : float
        alpha relative to the scale max(diag M) / max_i |J_i|^2 (dimensionless). 1e7, Bayo and Avello's
        value for the unit-size benchmark problems: stiff enough that the regularized directions are
        only those with sigma below ~3e-4 of the Jacobian's scale, soft enough that the matrix's
        condition number (~alpha) leaves 9 digits for the solve, which the iteration then refines.
    tol : float
        Stop when max|qdd_{i+1} - qdd_i| <= tol (1 + max|qdd|): 1e-12, round-off of the solve.
    max_iter : int
        20: away from singular poses the iteration converges in 2-4 steps.
    """

    penalty: float = 1e7
    tol: float = 1e-12
    max_iter: int = 20
    name: str = "augmented_lagrangian"
    passes_singular = True
    calls: int = 0
    unconverged: int = 0
    most_iterations: int = 0

    def _solve(self, M, Q, J, c):
        rows = np.einsum("ij,ij->i", J, J)
        alpha = self.penalty * float(np.max(np.diag(M))) / max(float(rows.max()), np.finfo(float).tiny)
        # LAPACK's Cholesky directly: what sla.cho_factor / cho_solve call, without their checks and copies,
        # which cost more than the solve itself at this size and up to 21 solves per call
        factor, info = dpotrf(M + alpha * (J.T @ J), lower=False, clean=False)
        if info:
            raise np.linalg.LinAlgError(f"M + alpha Phi_q^T Phi_q is not positive-definite (LAPACK dpotrf info {info})")
        lam = np.zeros(J.shape[0])
        Jc = alpha * (J.T @ c)
        qdd = dpotrs(factor, Q + Jc, lower=False)[0]
        self.calls += 1
        for i in range(1, self.max_iter + 1):
            lam = lam + alpha * (J @ qdd - c)
            new = dpotrs(factor, Q - J.T @ lam + Jc, lower=False)[0]
            done = np.abs(new - qdd).max() <= self.tol * (1.0 + np.abs(new).max())
            qdd = new
            if done:
                break
        else:
            self.unconverged += 1
        self.most_iterations = max(self.most_iterations, i)
        return qdd, lam

    def statistics(self) -> dict:
        return {"al_calls": self.calls, "al_unconverged": self.unconverged, "al_most_iterations": self.most_iterations}


ACCELERATION_SOLVERS: dict[str, type[AccelerationSolver]] = {
    "multiplier": Multiplier,
    "partitioned": Partitioned,
    "orthonormal": Orthonormal,
    "augmented_lagrangian": AugmentedLagrangian,
}


def make_acceleration_solver(name: str) -> AccelerationSolver:
    if name not in ACCELERATION_SOLVERS:
        raise ValueError(f"unknown acceleration solver {name!r}; valid choices: {', '.join(ACCELERATION_SOLVERS)}")
    return ACCELERATION_SOLVERS[name]()
