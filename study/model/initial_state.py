"""Consistent initial conditions (paper 001 eqs. 6-7): Newton-Raphson on Phi(q) = 0, then Phi_q qd = 0.

The independent coordinates and rates are held at the given values; the dependent ones are solved. A model-level
computation on the constraint equations alone (no integrator): :class:`study.model.Mechanism` finds its initial state
with it, and both engines start from that state.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from study.model.eom import EquationsOfMotion
from study.reference_data import tolerance

# Newton stops when max|Phi| <= NEWTON_TOL. 1e-13 is a few ulps of the mechanisms' lengths
# (<= 10 m), the smallest residual double precision can promise for these trigonometric constraints.
NEWTON_TOL = 1e-13
NEWTON_MAX_ITER = 50


class InitialConditionError(RuntimeError):
    """Newton-Raphson failed or the dependent Jacobian is singular."""


@dataclass(frozen=True)
class ConsistentState:
    q: np.ndarray
    qd: np.ndarray
    iterations: int
    phi_residual: float       # max |Phi(q)|
    velocity_residual: float  # max |Phi_q(q) qd|
    newton_history: tuple[float, ...]  # max |Phi| before each iteration


def _split(m: int, independent: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    ind = np.asarray(independent, dtype=int)
    if len(set(ind.tolist())) != len(ind) or np.any(ind < 0) or np.any(ind >= m):
        raise ValueError(f"independent = {list(independent)} must be distinct indices in 0..{m - 1}")
    dep = np.setdiff1d(np.arange(m), ind)
    return ind, dep


def consistent_initial_conditions(
    eom: EquationsOfMotion,
    q_guess: Sequence[float],
    independent: Sequence[int],
    qd_independent: Sequence[float],
    *,
    tol: float = NEWTON_TOL,
    max_iter: int = NEWTON_MAX_ITER,
) -> ConsistentState:
    """Solve Phi(q) = 0 for the dependent coordinates, then the velocity constraint.

    Parameters
    ----------
    eom : EquationsOfMotion
    q_guess : (m,) array_like
        Start of the Newton iteration; its independent entries are kept fixed.
    independent : sequence of int
        Indices of the n = m - r independent coordinates.
    qd_independent : (n,) array_like
        Rates of the independent coordinates.

    Raises
    ------
    InitialConditionError
        If Phi_v is singular (dead centre) or Newton does not reach ``tol`` in ``max_iter`` steps.
    """
    m, r = eom.n_coordinates, eom.n_constraints
    ind, dep = _split(m, independent)
    if len(dep) != r:
        raise ValueError(f"{len(ind)} independent coordinates given; the mechanism has {m - r} degrees of freedom")
    q = np.array(q_guess, dtype=float)
    qd_ind = np.asarray(qd_independent, dtype=float)
    if q.shape != (m,) or qd_ind.shape != (len(ind),):
        raise ValueError(f"q_guess must have shape ({m},) and qd_independent ({len(ind)},); "
                         f"got {q.shape} and {qd_ind.shape}")
    if r == 0:   # no constraints (free bodies held by loads only): the given state is consistent
        qd = np.zeros(m)
        qd[ind] = qd_ind
        return ConsistentState(q=q, qd=qd, iterations=0, phi_residual=0.0, velocity_residual=0.0,
                               newton_history=(0.0,))
    history = []
    singular_ratio = tolerance("singular_ratio")
    for it in range(max_iter + 1):
        phi = eom.phi(q)
        history.append(float(np.max(np.abs(phi))))
        jac = eom.phi_q(q)
        jac_v = jac[:, dep]
        # Scale-aware: sigma_min(Phi_v) relative to sigma_max(Phi_q), the whole Jacobian (the condition
        # number of Phi_v alone is 1 for any 1 x 1 Phi_v, however close to zero it is).
        sigma = np.linalg.svd(jac, compute_uv=False)     # r > 0 rows here, so neither matrix is empty
        ratio = float(np.linalg.svd(jac_v, compute_uv=False).min() / sigma.max()) if sigma.max() > 0 else 0.0
        if not ratio >= singular_ratio:
            raise InitialConditionError(
                f"{eom.name}: the dependent Jacobian Phi_q[:, {dep.tolist()}] is singular at q = {q}: "
                f"sigma_min(Phi_v) / sigma_max(Phi_q) = {ratio:.3g} < {singular_ratio:g} (singular_ratio); a "
                f"dead-centre configuration or a wrong choice of independent coordinates {ind.tolist()}")
        if history[-1] <= tol:
            break
        if it == max_iter:
            raise InitialConditionError(
                f"{eom.name}: Newton-Raphson did not converge in {max_iter} iterations from q = {list(q_guess)}; "
                f"max|Phi| history {history[-5:]} (tolerance {tol:g})")
        q[dep] -= np.linalg.solve(jac_v, phi)
    jac = eom.phi_q(q)
    qd = np.zeros(m)
    qd[ind] = qd_ind
    qd[dep] = np.linalg.solve(jac[:, dep], -jac[:, ind] @ qd_ind)
    return ConsistentState(
        q=q,
        qd=qd,
        iterations=len(history) - 1,
        phi_residual=history[-1],
        velocity_residual=float(np.max(np.abs(jac @ qd))),
        newton_history=tuple(history),
    )


def constraint_residuals(eom: EquationsOfMotion, q: Sequence[float], qd: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Phi(q) and Phi_q(q) qd, to show how far a given state is from the constraint manifold."""
    q = np.asarray(q, dtype=float)
    qd = np.asarray(qd, dtype=float)
    return eom.phi(q), eom.phi_q(q) @ qd
