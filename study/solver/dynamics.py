"""The first-order ODE of a constrained mechanism: state y = [q, qd, W], W the work of each load.

``Dynamics`` joins an EquationsOfMotion, an acceleration solver and a stabilization method:

    qdd, lambda = solve(M, Q, Phi_q, gamma + b(Phi, Phidot)),    dW_i/dt = Q_i . qd

and counts right-hand-side evaluations. Discontinuous loads are evaluated in a frozen ``mode``.

Two checks of a user's equations cost little enough to make at every evaluation, and catch what the
acceleration solvers would accept without a word: M(q) must be real and positive-definite (one LAPACK
Cholesky factorization, ``dpotrf``, under a microsecond for a small M: a generic solve of the saddle-point
system goes through with an indefinite or singular M), and Phi_q(q) real (the solvers copy it into real
arrays, dropping an imaginary part). Everything else a user's callable can do wrong shows in the output
(complex, non-finite) or as an exception; ``study.solver.checks.RunGuard`` names the callable then.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg.lapack import dpotrf

from study.errors import NonFiniteError, SimulationError, UserFunctionError
from study.model.eom import EquationsOfMotion, output_problem
from study.solver.accelerations import AccelerationSolver
from study.solver.stabilization import Stabilization

Array = np.ndarray


def fmt_vector(x) -> str:
    """A vector in one line, 6 significant digits (for messages)."""
    return "[" + ", ".join(f"{v:.6g}" for v in np.asarray(x, dtype=float).ravel()) + "]"


def _at(t: float, q: Array, qd: Array | None) -> str:
    return f"(at t = {t:.9g} s, q = {fmt_vector(q)}" + ("" if qd is None else f", qd = {fmt_vector(qd)}") + ")"


def output_error(eom: EquationsOfMotion, label: str, value, shape: tuple[int, ...], t: float, q: Array,
                 qd: Array | None = None) -> SimulationError | None:
    """The run failure of a user's callable ``label`` (e.g. 'forces(t, q, qd)') that returned ``value`` at time t, if
    it is not a real array of ``shape``: NonFiniteError for complex values, UserFunctionError otherwise."""
    problem = output_problem(value, shape)
    if problem is None:
        return None
    kind = NonFiniteError if problem.startswith("returned complex") else UserFunctionError
    return kind(f"{eom.name}: {label} {problem} {_at(t, q, qd)}", t=float(t), quantity=label.split("(")[0])


def raised_error(eom: EquationsOfMotion, label: str, exc: BaseException, t: float, q: Array,
                 qd: Array | None = None) -> UserFunctionError:
    """The run failure of a user's callable ``label`` that raised ``exc`` at time t (chain it: raise ... from exc)."""
    text = " ".join(str(exc).split())  # one line (the command line prints one)
    return UserFunctionError(f"{eom.name}: {label} raised {type(exc).__name__}: {text} {_at(t, q, qd)}", t=float(t),
                             quantity=label.split("(")[0], exception=type(exc).__name__)


def mass_failure(eom: EquationsOfMotion, t: float, q: Array, M) -> SimulationError | None:
    """Why M = mass(q) cannot be used at time t, or None if it can: not a real (m, m) array, or finite but not
    positive-definite (singular, or indefinite). A non-finite M is left to the run's non-finite check."""
    m = eom.n_coordinates
    error = output_error(eom, "mass(q)", M, (m, m), t, q)
    if error is not None:
        return error
    A = np.asarray(M, dtype=float)
    if not np.isfinite(A).all() or not dpotrf(A)[1]:
        return None
    eig = np.linalg.eigvalsh(0.5 * (A + A.T))
    big = float(np.max(np.abs(eig)))
    singular = abs(eig.min()) <= 100 * m * np.finfo(float).eps * big
    what = "singular" if singular else "not positive-definite (indefinite)"
    asym = float(np.max(np.abs(A - A.T))) / big if big > 0 else 0.0
    note = f" (nor symmetric: max|M - M^T| / max|eigenvalue| = {asym:.3g})" if asym > 1e-12 else ""
    return NonFiniteError(
        f"{eom.name}: mass(q) is {what}{note} at t = {t:.9g} s, q = {fmt_vector(q)}: smallest eigenvalue {eig.min():.6g}, "
        f"largest {eig.max():.6g} (of its symmetric part; every eigenvalue must be > 0); the accelerations are not "
        f"determined by such a mass matrix (a coordinate without inertia, or a sign error in mass(q))", t=float(t),
        quantity="mass", eigenvalues=list(map(float, eig)))


@dataclass
class Dynamics:
    eom: EquationsOfMotion
    accelerations: AccelerationSolver
    stabilization: Stabilization
    work_names: tuple[str, ...] = ()
    nfev: int = 0
    _modal: bool = field(init=False, default=False)

    def __post_init__(self) -> None:
        self._modal = self.eom.indicators is not None

    @property
    def m(self) -> int:
        return self.eom.n_coordinates

    def split(self, y: Array) -> tuple[Array, Array, Array]:
        m = self.m
        return y[:m], y[m:2 * m], y[2 * m:]

    def _forces(self, t, q, qd, mode):
        return self.eom.forces(t, q, qd, mode=mode) if self._modal else self.eom.forces(t, q, qd)

    def _applied(self, t, q, qd, mode):
        return self.eom.applied_forces(t, q, qd, mode=mode) if self._modal else self.eom.applied_forces(t, q, qd)

    def _mass(self, t: float, q: Array):
        """M(q), checked real and positive-definite (see the module docstring)."""
        M = self.eom.mass(q)
        try:
            ok = M.dtype.kind == "f" and not dpotrf(M)[1]
        except Exception:  # noqa: BLE001 - not an array, or not square: mass_failure says which
            ok = False
        if not ok:
            error = mass_failure(self.eom, t, q, M)
            if error is not None:
                raise error
            return np.asarray(M, dtype=float)  # e.g. a list, or integers: usable
        return M

    def _phi_q(self, t: float, q: Array) -> Array:
        """Phi_q(q), checked real."""
        J = self.eom.phi_q(q)
        if type(J) is not np.ndarray or J.dtype.kind == "c":
            error = output_error(self.eom, "phi_q(q)", J, np.shape(J), t, q)
            if error is not None:
                raise error
            return np.asarray(J, dtype=float)
        return J

    def evaluate(self, t: float, q: Array, qd: Array, mode=None) -> tuple[Array, Array]:
        """Accelerations and multipliers at one state."""
        eom = self.eom
        J = self._phi_q(t, q)
        c = eom.gamma(q, qd) + self.stabilization.bias(eom.phi(q), J @ qd)
        return self.accelerations.solve(self._mass(t, q), self._forces(t, q, qd, mode), J, c)

    def powers(self, t: float, q: Array, qd: Array, mode=None) -> Array:
        if not self.work_names:
            return np.zeros(0)
        applied = self._applied(t, q, qd, mode)
        return np.array([applied[name] @ qd for name in self.work_names])

    def rhs(self, t: float, y: Array, mode=None) -> Array:
        self.nfev += 1
        q, qd, _ = self.split(y)
        qdd, _ = self.evaluate(t, q, qd, mode)
        return np.concatenate([qd, qdd, self.powers(t, q, qd, mode)])
