"""ALI3-P: the index-3 augmented Lagrangian with mass-orthogonal projections, on the trapezoidal rule.

Bayo and Ledesma (1996), "Augmented Lagrangian and mass-orthogonal projection methods for constrained
multibody dynamics", Nonlinear Dynamics 9, 113-130; the form Cuadrado, Dopico et al. use for the IFToMM
benchmarks. With a fixed step h the trapezoidal rule makes the state at t + h a function of q_{n+1} alone:

    qd_{n+1} = qd_n + h/2 qdd_n + 2/h (q_{n+1} - q_hat),  qdd_{n+1} = 4/h^2 (q_{n+1} - q_hat),
    q_hat = q_n + h qd_n + h^2/4 qdd_n.

The equations of motion at t + h hold the constraints at position level through a penalty kappa and the
multipliers lam~ = h^2/4 lambda:

    f(q) = h^2/4 (M qdd - Q) + Phi_q^T (lam~ + kappa Phi) = 0,     lam~ <- lam~ + kappa Phi after each iteration,

solved by Newton iterations with the tangent M + kappa Phi_q^T Phi_q. That matrix is positive-definite whatever
the rank of Phi_q, so the method passes singular positions; the position constraints Phi = 0 (not their second
derivative) are what the iteration enforces, so the run stays on the branch it follows. After the iteration
the velocities and accelerations are projected onto Phi_q qd = 0 and Phi_q qdd = gamma in the metric of the
same matrix (the constraints of ``EquationsOfMotion`` do not depend on t):

    qd  <- qd  - (M + kappa Phi_q^T Phi_q)^-1 kappa Phi_q^T (Phi_q qd),
    qdd <- qdd - (M + kappa Phi_q^T Phi_q)^-1 kappa Phi_q^T (Phi_q qdd - gamma).

Written as corrections, the projections' round-off scales with the residual, not with kappa times the whole
vector (solving P qd = M qd* directly loses kappa * eps of qd in every step).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as sla

from study.errors import SimulationError
from study.solver.checks import diagnose_dynamics, diagnose_non_finite
from study.solver.dynamics import Dynamics
from study.solver.integrate import HermiteDense, Trajectory

Array = np.ndarray
NAME = "ALI3P"


@dataclass(frozen=True)
class ALI3P:
    """Settings of the index-3 augmented Lagrangian (see the module docstring).

    penalty : float
        kappa = penalty * max diag M(q0) / max_i |row i of Phi_q(q0)|^2, dimensionless; 1e8 (study's own). The
        method trades two errors: a small kappa makes the multiplier iteration slow where Phi_q loses rank (its
        rate is about 1 / (1 + kappa sigma_min^2 / M)); a large one makes the tangent ill-conditioned (round-off
        ~ eps * penalty per solve). On the N-four-bar (N = 2, h = 1e-3 s, 10 s), 1e4 and 1e5 left steps at the
        iteration limit at the crossings, while 1e7, 1e8 and 1e9 gave errors against the exact motion within
        1e-8 m of each other, with at most 15, 9 and 4 iterations in a step.
    tol : float
        A step has converged when max|dq| <= tol (1 + max|q|): 1e-12, a few thousand round-offs of the coordinates
        and far below the trapezoidal rule's local error (~h^3 |q'''| = 1e-8 at h = 1e-3 on the N-four-bar).
    max_iter : int
        50 Newton iterations: away from singular positions 2-3 are enough.
    accept_factor : float
        A step at ``max_iter`` is accepted (and counted in the result's stats) if its last correction is within
        ``accept_factor`` * tol (1 + max|q|), i.e. stagnating at round-off; 1e3 (1e-9 rad for O(1) angles,
        six orders below the benchmark's 1e-3 m). Beyond it the run stops with a SimulationError.
    """

    penalty: float = 1e8
    tol: float = 1e-12
    max_iter: int = 50
    accept_factor: float = 1e3


def integrate_index3(dyn: Dynamics, y0: Array, t_end: float, t_out: Array, step: float,
                     settings: ALI3P = ALI3P(), progress: Callable[[float], None] | None = None
                     ) -> tuple[Trajectory, dict]:
    """Integrate from t = 0 with the fixed step ``step`` (the last one shortened to reach t_end) and sample at
    ``t_out`` by cubic Hermite interpolation of [q, qd, W] between steps. Returns the samples and statistics.

    ``dyn`` provides the checked M(q) and Phi_q(q), the forces and the powers of the applied loads (whose work W
    is integrated by the trapezoidal rule too) and the initial accelerations (its acceleration solver's).
    """
    eom = dyn.eom
    q, qd, work = (np.array(part, dtype=float) for part in dyn.split(y0))
    t = 0.0
    qdd = dyn.evaluate(t, q, qd)[0]
    J0 = dyn._phi_q(t, q)
    rows = float(np.max(np.einsum("ij,ij->i", J0, J0), initial=0.0))
    # no constraint rows (or a Jacobian of zeros at q0): nothing to penalise, the step is the trapezoidal rule alone
    kappa = settings.penalty * float(np.max(np.diag(dyn._mass(t, q)))) / rows if rows > 0 else 0.0
    power = dyn.powers(t, q, qd)
    lam = np.zeros(eom.n_constraints)      # lam~ = h^2/4 lambda of the last step
    h_last = step
    stats = {"steps": 0, "newton_iterations": 0, "newton_most_iterations": 0, "newton_limit_steps": 0,
             "newton_largest_accepted_correction": 0.0, "kappa": kappa}
    t_out = np.asarray(t_out, dtype=float)
    samples_t, samples_y = [t_out[0]], [np.concatenate([q, qd, work])]
    k_out = 1
    n_steps = int(np.ceil(t_end / step - 1e-9))
    for k in range(1, n_steps + 1):
        t_new = min(k * step, t_end)
        h = t_new - t
        lam *= (h / h_last) ** 2
        try:
            q_new, qd_new, qdd_new, lam, iterations, correction = _step(dyn, settings, kappa, t_new, h, q, qd, qdd, lam)
        except SimulationError:
            raise
        except Exception as exc:  # noqa: BLE001 - a user's callable raised, or returned what cannot be used
            error = diagnose_dynamics(dyn, t_new, q, qd)
            if error is None:
                raise
            raise error from exc
        if not (np.isfinite(q_new).all() and np.isfinite(qd_new).all() and np.isfinite(qdd_new).all()):
            raise diagnose_non_finite(eom, t_new, q_new, qd_new, qdd_new, fixed_step=step)
        stats["newton_iterations"] += iterations
        stats["newton_most_iterations"] = max(stats["newton_most_iterations"], iterations)
        if iterations > settings.max_iter:
            stats["newton_limit_steps"] += 1
            stats["newton_largest_accepted_correction"] = max(stats["newton_largest_accepted_correction"], correction)
        power_new = dyn.powers(t_new, q_new, qd_new)
        work_new = work + 0.5 * h * (power + power_new)
        y_old = np.concatenate([q, qd, work])
        y_new = np.concatenate([q_new, qd_new, work_new])
        if k_out < len(t_out) and t_out[k_out] <= t_new * (1 + 1e-12):
            dense = HermiteDense(t, t_new, y_old, y_new, np.concatenate([qd, qdd, power]),
                                 np.concatenate([qd_new, qdd_new, power_new]))
            while k_out < len(t_out) and t_out[k_out] <= t_new * (1 + 1e-12):
                samples_t.append(t_out[k_out])
                samples_y.append(y_new if np.isclose(t_out[k_out], t_new, rtol=0, atol=1e-12) else dense(t_out[k_out]))
                k_out += 1
        t, q, qd, qdd, work, power, h_last = t_new, q_new, qd_new, qdd_new, work_new, power_new, h
        stats["steps"] += 1
        if progress is not None:
            progress(t)
    traj = Trajectory(np.asarray(samples_t), np.asarray(samples_y), [None] * len(samples_t), steps=stats["steps"])
    return traj, stats


def _step(dyn: Dynamics, settings: ALI3P, kappa: float, t: float, h: float, q: Array, qd: Array, qdd: Array,
          lam: Array) -> tuple[Array, Array, Array, Array, int, float]:
    """One trapezoidal step to time t: (q, qd, qdd, lam~, iterations (max_iter + 1 if at the limit), last |dq|)."""
    eom = dyn.eom
    q_hat = q + h * qd + 0.25 * h * h * qdd
    qd_hat = qd + 0.5 * h * qdd
    x = q + h * qd + 0.5 * h * h * qdd          # predictor: constant acceleration
    for iteration in range(1, settings.max_iter + 1):
        acc = 4.0 / (h * h) * (x - q_hat)
        vel = qd_hat + 0.5 * h * acc
        M, J = dyn._mass(t, x), dyn._phi_q(t, x)
        phi = np.asarray(eom.phi(x), dtype=float)
        if iteration > 1:
            lam = lam + kappa * phi
        f = 0.25 * h * h * (M @ acc - dyn._forces(t, x, vel, None)) + J.T @ (lam + kappa * phi)
        dyn.nfev += 1
        dx = -sla.cho_solve(sla.cho_factor(M + kappa * (J.T @ J)), f)
        x = x + dx
        correction = float(np.max(np.abs(dx)))
        scale = 1.0 + float(np.max(np.abs(x)))
        if correction <= settings.tol * scale:
            break
    else:
        if not correction <= settings.accept_factor * settings.tol * scale:
            raise SimulationError(
                f"{eom.name}: {NAME}'s Newton iteration did not converge in the step to t = {t:.9g} s: after "
                f"{settings.max_iter} iterations the correction is {correction:.3g} (converged: <= "
                f"{settings.tol * scale:.3g}); max|Phi| = {np.max(np.abs(phi), initial=0.0):.3g}: use a smaller step",
                t=float(t), quantity="newton", correction=correction)
        iteration = settings.max_iter + 1
    lam = lam + kappa * np.asarray(eom.phi(x), dtype=float)
    acc = 4.0 / (h * h) * (x - q_hat)
    vel = qd_hat + 0.5 * h * acc
    M, J = dyn._mass(t, x), dyn._phi_q(t, x)
    factor = sla.cho_factor(M + kappa * (J.T @ J))
    vel = vel - sla.cho_solve(factor, kappa * (J.T @ (J @ vel)))
    acc = acc - sla.cho_solve(factor, kappa * (J.T @ (J @ acc - eom.gamma(x, vel))))
    return x, vel, acc, lam, iteration, correction
