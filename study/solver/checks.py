"""Checks made before and during a run: a user's equations, singular configurations, non-finite values.

Before a run (:func:`validate_equations`, once, skipped with ``simulate(..., check=False)``):

1. every callable returns finite real values of its shape at (q0, qd0) (potential_energy, if given, a scalar);
2. M(q0) is symmetric and positive-definite (Cholesky);
3. phi_q(q0) equals the central-difference Jacobian of phi;
4. gamma(q0, qd) equals its definition -(Phi_q qd)_q qd, by a central difference of phi_q along qd
   (at qd0 and at a unit test velocity, so a zero qd0 does not make the check empty);
5. q0 and qd0 lie on the constraints (``study.model.initial_state`` makes them consistent).

Every failed check is listed in one :class:`study.errors.EquationsError`. The tolerances are in
``reference/tolerances.toml`` with their reasons.

During a run (:class:`SingularityMonitor`): the rank of Phi_q is measured by

    rho(q) = sigma_min(Phi_q(q)) / max(sigma_max(Phi_q(q)), s_ref)

with ``s_ref`` the Jacobian's scale at the start (:func:`jacobian_scale`: its largest singular value,
or the first-order change of Phi_q over a move of the size of q0 where Phi_q itself vanishes). A
1 x m Jacobian's sigma_min / sigma_max is always 1, so s_ref is what makes a one-constraint mechanism's
singular pose (Phi_q -> 0) visible. A run whose rho falls below ``singular_ratio`` stops with the time,
the pose and rho.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from study.errors import (EquationsError, NonFiniteError, RunBoundError, SimulationError, SingularConfigurationError,
                          UserFunctionError)
from study.model.eom import EquationsOfMotion, output_problem
from study.reference_data import tolerance
from study.solver.budget import Budget
from study.solver.dynamics import fmt_vector as _fmt, output_error, raised_error
from study.solver.friction import FrictionDynamics, PainleveError

Array = np.ndarray


def _finite_difference(f: Callable[[Array], Array], x: Array, direction: Array, h: float) -> Array:
    return (np.asarray(f(x + h * direction), dtype=float) - np.asarray(f(x - h * direction), dtype=float)) / (2 * h)


def _step(q: Array) -> float:
    return tolerance("finite_difference_step") * max(1.0, float(np.max(np.abs(q))) if q.size else 1.0)


def numeric_jacobian(f: Callable[[Array], Array], q: Array) -> Array:
    """Central-difference Jacobian of f at q, (len(f(q)), len(q))."""
    h = _step(q)
    cols = [_finite_difference(f, q, e, h) for e in np.eye(len(q))]
    return np.stack(cols, axis=-1) if cols else np.zeros((0, 0))


def numeric_gamma(eom: EquationsOfMotion, q: Array, qd: Array) -> Array:
    """-(Phi_q qd)_q qd by a central difference of phi_q along qd (qd held fixed)."""
    h = _step(q)
    return -_finite_difference(lambda x: eom.phi_q(x) @ qd, q, qd, h)


def singular_values(J: Array) -> Array:
    return np.linalg.svd(J, compute_uv=False) if J.size else np.zeros(0)


def jacobian_scale(eom: EquationsOfMotion, q0: Array) -> float:
    """The scale s_ref of Phi_q: max(sigma_max(Phi_q(q0)), |d Phi_q| over a move of |q0| along each axis)."""
    if eom.n_constraints == 0:
        return 1.0
    J = np.asarray(eom.phi_q(q0), dtype=float)
    sigma = singular_values(J)
    size = float(np.linalg.norm(q0)) or 1.0
    h = _step(q0)
    change = max(np.linalg.norm(_finite_difference(eom.phi_q, q0, e, h), 2) for e in np.eye(len(q0))) * size
    scale = max(float(sigma.max()) if sigma.size else 0.0, float(change))
    return scale if np.isfinite(scale) and scale > 0 else 1.0


def singularity_measure(J: Array, scale: float) -> float:
    """rho = sigma_min(J) / max(sigma_max(J), scale); 1 for no constraints, 0 for a rank-deficient J."""
    if J.shape[0] == 0:
        return 1.0
    s = singular_values(J)
    if not np.all(np.isfinite(s)):
        return 0.0
    return float(s.min() / max(s.max(), scale))


class SingularityMonitor:
    """Stops a run whose pose approaches a rank-deficient Phi_q (rho < ``singular_ratio``)."""

    def __init__(self, eom: EquationsOfMotion, q0: Array, ratio: float | None = None):
        self.eom = eom
        self.scale = jacobian_scale(eom, np.asarray(q0, dtype=float))
        self.ratio = tolerance("singular_ratio") if ratio is None else ratio
        self.smallest = np.inf
        self._last: tuple[float, Array] | None = None

    def measure(self, q: Array) -> float:
        return singularity_measure(np.asarray(self.eom.phi_q(q), dtype=float), self.scale)

    def _jacobian(self, t: float, q: Array) -> Array:
        """Phi_q(q) at an accepted step, where an implicit integrator may not have evaluated the equations yet:
        a phi_q that raises, or returns complex values or a wrong shape, fails the run with its name and t."""
        try:
            J = self.eom.phi_q(q)
        except Exception as exc:  # noqa: BLE001 - the user's callable raised
            raise raised_error(self.eom, "phi_q(q)", exc, t, q) from exc
        error = output_error(self.eom, "phi_q(q)", J, (self.eom.n_constraints, len(q)), t, q)
        if error is not None:
            raise error
        return np.asarray(J, dtype=float)

    def rank(self, J: Array) -> int:
        """Numerical rank of Phi_q: singular values at or above ``singular_ratio`` times the scale."""
        s = singular_values(J)
        return int(np.sum(s >= self.ratio * max(float(s.max(initial=0.0)), self.scale)))

    def check(self, t: float, q: Array) -> None:
        """Raise SingularConfigurationError if rho(q) < ratio, or if the step since the last call crossed a
        singular pose: a direction of the constraints' row space reversed, i.e. J J_last^T has an
        eigenvalue with real part <= 0 (a small step reverses a row direction only by passing through a
        rank drop; a step can jump over the pose itself). For J = D J_last (rows rescaled by D) the
        eigenvalues of D (J_last J_last^T) have the signs of D's entries (Sylvester's law of inertia),
        so rows that shrink without reversing are not reported. The eigenvalues, not the determinant:
        an even number of rows vanishing together (parallel windows of a linkage that all flatten at
        once) turns the determinant over twice and leaves it positive."""
        if self.eom.n_constraints == 0:
            return
        J = self._jacobian(t, q)
        rho = singularity_measure(J, self.scale)
        self.smallest = min(self.smallest, rho)
        reversed_ = 0
        if self._last is not None:
            C = J @ self._last[1].T
            reversed_ = int(np.sum(np.linalg.eigvals(C).real <= 0))
        if not rho >= self.ratio or reversed_:
            r, rank = self.eom.n_constraints, self.rank(J)
            where = (f"between t = {self._last[0]:.9g} s and t = {t:.9g} s: the Jacobian's rows turned over in "
                     f"{reversed_} direction(s), so Phi_q lost rank (by at least {reversed_}) within "
                     f"the step; now at" if reversed_ and rho >= self.ratio else
                     f"at t = {t:.9g} s: Phi_q is (nearly) rank-deficient (numerical rank {rank} of {r} rows) at")
            raise SingularConfigurationError(
                f"{self.eom.name}: singular configuration {where} q = {_fmt(q)}, where "
                f"sigma_min(Phi_q) / scale = {rho:.3g} (singular below {self.ratio:g}, "
                f"reference/tolerances.toml: singular_ratio); accelerations and multipliers are not determined "
                f"there (a dead centre, or links aligned); a method that needs a full-rank Phi_q cannot pass it, "
                f"acceleration_solver='augmented_lagrangian' can", t=float(t), quantity="Phi_q",
                pose=list(map(float, q)), measure=rho)
        self._last = (float(t), J)


def _evaluate(name: str, call: Callable[[], Array], problems: list[str],
              shape: tuple[int, ...] | None = None) -> Array | None:
    try:
        raw = call()
    except Exception as exc:  # noqa: BLE001 - reported as a problem of the user's callable
        problems.append(f"{name} raised {type(exc).__name__}: {exc}")
        return None
    problem = output_problem(raw, np.shape(raw) if shape is None else shape)  # complex, None, text, shape
    if problem:
        problems.append(f"{name} {problem}")
        return None
    value = np.asarray(raw, dtype=float)
    if not np.all(np.isfinite(value)):
        problems.append(f"{name} is not finite at the initial state: {_fmt(value)}")
        return None
    return value


def _relative(a: Array, b: Array, floor: float = 0.0) -> float:
    """max|a - b| relative to the largest entry of a, b (or ``floor``, the quantity's scale, if larger)."""
    scale = max(float(np.max(np.abs(a), initial=0.0)), float(np.max(np.abs(b), initial=0.0)), floor)
    diff = float(np.max(np.abs(a - b), initial=0.0))
    return diff / scale if scale > 0 else 0.0


def validate_equations(eom: EquationsOfMotion, q0: Array, qd0: Array, t0: float = 0.0) -> None:
    """Check a run's equations and initial state once (see the module docstring); raises EquationsError."""
    q0, qd0 = np.asarray(q0, dtype=float), np.asarray(qd0, dtype=float)
    problems: list[str] = []
    if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(qd0))):
        problems.append(f"the initial state is not finite: q0 = {_fmt(q0)}, qd0 = {_fmt(qd0)}")
        raise EquationsError(_message(eom, problems), tuple(problems))
    m, r = eom.n_coordinates, eom.n_constraints
    M = _evaluate("mass(q0)", lambda: eom.mass(q0), problems, (m, m))
    _evaluate("forces(0, q0, qd0)", lambda: eom.forces(t0, q0, qd0), problems, (m,))
    phi = _evaluate("phi(q0)", lambda: eom.phi(q0), problems, (r,))
    J = _evaluate("phi_q(q0)", lambda: eom.phi_q(q0), problems, (r, m))
    gamma = _evaluate("gamma(q0, qd0)", lambda: eom.gamma(q0, qd0), problems, (r,))
    if eom.potential_energy is not None:
        _evaluate("potential_energy(q0)", lambda: eom.potential_energy(q0), problems, ())

    if M is not None:
        sym = tolerance("mass_symmetry")
        asym = _relative(M, M.T)
        if asym > sym:
            problems.append(f"mass(q0) is not symmetric: max|M - M^T| / max|M| = {asym:.3g} > {sym:g} "
                            f"(mass_symmetry)")
        else:
            try:
                np.linalg.cholesky(0.5 * (M + M.T))
            except np.linalg.LinAlgError:
                eig = np.linalg.eigvalsh(0.5 * (M + M.T))
                problems.append(f"mass(q0) is not positive-definite: smallest eigenvalue {eig.min():.6g} "
                                f"(every eigenvalue must be > 0)")
    tol = tolerance("equations_check")
    scale = jacobian_scale(eom, q0) if J is not None and eom.n_constraints else 1.0
    if phi is not None and J is not None and eom.n_constraints:
        fd = _evaluate("phi near q0", lambda: numeric_jacobian(eom.phi, q0), problems)
        if fd is not None:
            err = _relative(J, fd, scale)
            if err > tol:
                i, j = np.unravel_index(np.argmax(np.abs(J - fd)), J.shape)
                problems.append(f"phi_q(q0) is not the Jacobian of phi: entry ({i}, {j}) is {J[i, j]:.9g}, the "
                                f"central difference of phi gives {fd[i, j]:.9g} (relative difference {err:.3g} "
                                f"> {tol:g}, equations_check)")
    if gamma is not None and J is not None and eom.n_constraints:
        for label, qd in (("qd0", qd0), ("a unit test velocity", np.ones_like(qd0))):
            g = gamma if label == "qd0" else _evaluate("gamma(q0, 1)", lambda: eom.gamma(q0, qd), problems)
            fd = _evaluate("phi_q near q0", lambda qd=qd: numeric_gamma(eom, q0, qd), problems)
            if g is None or fd is None:
                continue
            # gamma ~ (second derivative of Phi) |qd|^2, and the second derivative ~ scale / |q0|
            err = _relative(g, fd, scale / max(float(np.linalg.norm(q0)), _step(q0)) * float(qd @ qd))
            if err > tol:
                problems.append(f"gamma(q0, qd) at {label} is {_fmt(g)}, its definition -(Phi_q qd)_q qd gives "
                                f"{_fmt(fd)} (relative difference {err:.3g} > {tol:g}, equations_check)")
    if phi is not None and J is not None and eom.n_constraints and not problems:
        res = tolerance("initial_state_residual")
        sigma = float(singular_values(J).max())
        pos_scale = sigma * float(np.linalg.norm(q0))
        pos = float(np.max(np.abs(phi)))
        if pos_scale > 0 and pos > res * pos_scale:
            problems.append(f"q0 = {_fmt(q0)} is off the constraints: max|Phi(q0)| = {pos:.6g} is "
                            f"{pos / pos_scale:.3g} of |Phi_q| |q0| (allowed {res:g}, initial_state_residual)")
        vel_scale = sigma * float(np.linalg.norm(qd0))
        vel = float(np.max(np.abs(J @ qd0)))
        if vel_scale > 0 and vel > res * vel_scale:
            problems.append(f"qd0 = {_fmt(qd0)} violates the velocity constraints: max|Phi_q qd0| = {vel:.6g} is "
                            f"{vel / vel_scale:.3g} of |Phi_q| |qd0| (allowed {res:g}, initial_state_residual)")
        if problems:
            hint = ("; make the state consistent with study.model.initial_state.consistent_initial_conditions "
                    "(or pass check=False to run from it anyway)")
            raise EquationsError(_message(eom, problems) + hint, tuple(problems))
    if problems:
        raise EquationsError(_message(eom, problems), tuple(problems))


def _message(eom: EquationsOfMotion, problems: list[str]) -> str:
    return f"EquationsOfMotion {eom.name!r} failed {len(problems)} check(s) before the run: " + "; ".join(problems)


# --- a user's callables failing during a run -------------------------------------------------------
def diagnose_equations(eom: EquationsOfMotion, t: float, q: Array, qd: Array, mode=None, *, applied: bool = False,
                       contacts: bool = False, potential: bool = False) -> SimulationError | None:
    """The run failure of the first of a user's callables that raises, or returns something other than real
    numbers of its shape (complex values included), at (t, q, qd); None if every one is fine.

    Made only once an evaluation went wrong (an exception, a complex output): it evaluates the callables again,
    one by one, so that the failure names the callable rather than the solver's symptom of it. ``mode`` is the
    loads' mode; ``applied``, ``contacts`` and ``potential`` add applied_forces, the contacts' tangent
    functions and potential_energy. The caller chains the original exception (``raise error from exc``).
    """
    m, r = eom.n_coordinates, eom.n_constraints
    modal = eom.indicators is not None and mode is not None
    calls: list[tuple[str, Callable[[], object], tuple[int, ...] | None]] = [
        ("forces(t, q, qd)", lambda: eom.forces(t, q, qd, mode=mode) if modal else eom.forces(t, q, qd), (m,)),
        ("mass(q)", lambda: eom.mass(q), (m, m)), ("phi(q)", lambda: eom.phi(q), (r,)),
        ("phi_q(q)", lambda: eom.phi_q(q), (r, m)), ("gamma(q, qd)", lambda: eom.gamma(q, qd), (r,))]
    if applied:
        calls.append(("applied_forces(t, q, qd)", lambda: eom.applied_forces(t, q, qd, mode=mode) if modal else
                      eom.applied_forces(t, q, qd), None))
    if contacts:
        for ct in eom.contacts:  # their shapes are the friction code's business: only raising and complex here
            calls += [(f"contact {ct.name!r} tangent_jacobian(q)", lambda ct=ct: ct.tangent_jacobian(q), None),
                      (f"contact {ct.name!r} tangent_bias(q, qd)", lambda ct=ct: ct.tangent_bias(q, qd), None)]
    if potential and eom.potential_energy is not None:
        calls.append(("potential_energy(q)", lambda: eom.potential_energy(q), ()))
    for label, call, shape in calls:
        with_qd = "qd" in label
        try:
            value = call()
        except Exception as exc:  # noqa: BLE001 - the user's callable raised: that is the diagnosis
            return raised_error(eom, label, exc, t, q, qd if with_qd else None)
        if label.startswith("applied_forces"):
            if not hasattr(value, "items"):
                return UserFunctionError(f"{eom.name}: {label} returned {value!r:.80}, expected a mapping of load "
                                         f"names to arrays of shape ({m},) (at t = {t:.9g} s, q = {_fmt(q)}, "
                                         f"qd = {_fmt(qd)})", t=float(t), quantity="applied_forces")
            for key, v in value.items():
                error = output_error(eom, f"{label}[{key!r}]", v, (m,), t, q, qd)
                if error is not None:
                    return error
            continue
        error = output_error(eom, label, value, np.shape(value) if shape is None else shape, t, q,
                             qd if with_qd else None)
        if error is not None:
            return error
    return None


# --- non-finite values during a run ----------------------------------------------------------------
def diagnose_non_finite(eom: EquationsOfMotion, t: float, q: Array, qd: Array, result: Array, mode=None,
                        monitor: SingularityMonitor | None = None, fixed_step: float | None = None) -> SimulationError:
    """Name the first non-finite (or complex) quantity of an evaluation at (t, q, qd) and its likely cause."""
    where = f"{eom.name}: non-finite value at t = {t:.9g} s"
    step_hint = (f"the step h = {fixed_step:g} s is likely too large (the integration diverged): use a smaller step "
                 f"or an adaptive integrator" if fixed_step else
                 "the integration diverged (a step too large for the problem, or equations that blow up)")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        return NonFiniteError(f"{where} in the state (q = {_fmt(q)}, qd = {_fmt(qd)}): {step_hint}", t=t,
                              quantity="state")
    error = diagnose_equations(eom, t, q, qd, mode)  # a callable that raises, or returns complex values
    if error is not None:
        return error
    modal = eom.indicators is not None and mode is not None
    calls = (("forces(t, q, qd)", lambda: eom.forces(t, q, qd, mode=mode) if modal else eom.forces(t, q, qd)),
             ("mass(q)", lambda: eom.mass(q)), ("phi(q)", lambda: eom.phi(q)), ("phi_q(q)", lambda: eom.phi_q(q)),
             ("gamma(q, qd)", lambda: eom.gamma(q, qd)))
    big = max(float(np.max(np.abs(q), initial=0.0)), float(np.max(np.abs(qd), initial=0.0)))
    for name, call in calls:
        value = np.asarray(call(), dtype=float)
        if not np.all(np.isfinite(value)):
            cause = (f"{name.split('(')[0]} returns non-finite values at the start of the run (check that callable)"
                     if t == 0 else f"max|q|, |qd| = {big:.3g}: if that is far from the motion's size, {step_hint}; otherwise "
                     f"{name.split('(')[0]} itself returns non-finite values there (check that callable)")
            return NonFiniteError(f"{where}: {name} = {_fmt(value)} at q = {_fmt(q)}, qd = {_fmt(qd)}; {cause}",
                                  t=t, quantity=name.split("(")[0])
    if np.iscomplexobj(result):
        return NonFiniteError(f"{eom.name}: complex values at t = {t:.9g} s in the right-hand side, from equations "
                              f"whose callables return real values at q = {_fmt(q)}, qd = {_fmt(qd)}: "
                              f"{np.asarray(result)!r}"[:2000], t=t, quantity="rhs")
    rho = monitor.measure(q) if monitor is not None else float("nan")
    return NonFiniteError(f"{where} in the accelerations (qdd, lambda) from finite equations at q = {_fmt(q)}: "
                          f"the acceleration system is singular there (sigma_min(Phi_q) / scale = {rho:.3g}) or "
                          f"overflowed: {_fmt(result)}", t=t, quantity="qdd")


def diagnose_dynamics(dyn, t: float, q: Array, qd: Array, mode=None, potential: bool = False) -> SimulationError | None:
    """:func:`diagnose_equations` for the callables a Dynamics (or FrictionDynamics) evaluates in ``mode``."""
    friction = isinstance(dyn, FrictionDynamics)
    return diagnose_equations(dyn.eom, t, q, qd, dyn.load_mode(mode) if friction else mode,
                              applied=bool(dyn.work_names), contacts=friction, potential=potential)


class RunGuard:
    """The right-hand side of a run with its checks: finite output, an evaluation bound, singular systems.

    Wraps ``dyn.rhs`` (a :class:`study.solver.dynamics.Dynamics`), or ``rhs`` that evaluates the same (the
    compiled kernels). Every call costs one dtype test and one ``np.isfinite(...).all()`` on the output; the diagnosis (which quantity, why) is made only once something
    is non-finite or complex, or an exception came out of the evaluation: an exception raised by (or caused
    by the output of) a user's callable becomes a :class:`study.errors.UserFunctionError` naming the callable
    and the time, complex values a NonFiniteError (see :func:`diagnose_equations`); an exception no callable
    explains is raised as it is. (Dynamics itself checks M(q) positive-definite and Phi_q real.)
    """

    def __init__(self, dyn, monitor: SingularityMonitor | None, max_evaluations: float,
                 fixed_step: float | None = None, t_end: float | None = None, rhs=None):
        self.dyn, self.monitor = dyn, monitor
        self.rhs = dyn.rhs if rhs is None else rhs
        self.max_evaluations, self.fixed_step = max_evaluations, fixed_step
        # an adaptive run's pace (a fixed-step run's cost is known, and refused, before it starts)
        self.budget = (Budget(t_end, max_evaluations) if t_end is not None and fixed_step is None
                       and max_evaluations >= tolerance("budget_min_evaluations") else None)

    def __call__(self, t: float, y: Array, mode=None) -> Array:
        dyn = self.dyn
        if dyn.nfev >= self.max_evaluations:
            raise RunBoundError(
                f"{dyn.eom.name}: {dyn.nfev} evaluations reached max_evaluations = {self.max_evaluations:g} at "
                f"t = {t:.9g} s (a stalled or far too long run; max_evaluations= raises the bound)"
                + self._pose_note(y) + self._law_note(), t=float(t), quantity="evaluations", evaluations=dyn.nfev)
        if self.budget is not None:
            self.budget.update(dyn.nfev, t, dyn.eom.name, self._law_note())
        try:
            out = self.rhs(t, y, mode)
        except np.linalg.LinAlgError as exc:
            q = y[:dyn.m]
            error = self._diagnose(t, y, mode)  # a wrong shape can make a solve fail too
            if error is not None:
                raise error from exc
            raise SingularConfigurationError(
                f"{dyn.eom.name}: the acceleration system is singular at t = {t:.9g} s, q = {_fmt(q)} ({exc})"
                + self._pose_note(y), t=float(t), quantity="qdd", pose=list(map(float, q))) from exc
        except PainleveError:
            # Painleve's paradox is a property of a regular frictionless problem; at a singular pose the
            # frictionless problem itself has no unique solution, and that is what is reported.
            if self.monitor is not None and self.monitor.measure(y[:dyn.m]) < self.monitor.ratio:
                self.monitor.check(t, y[:dyn.m])
            raise
        except SimulationError:
            raise
        except Exception as exc:  # noqa: BLE001 - a user's callable raised, or returned what the solver cannot use
            error = self._diagnose(t, y, mode)
            if error is None:
                raise
            raise error from exc
        if out.dtype.kind != "f" or not np.isfinite(out).all():
            m = dyn.m
            error = self._diagnose(t, y, mode) if out.dtype.kind == "c" else None  # applied loads, contacts too
            if error is not None:
                raise error
            raise diagnose_non_finite(dyn.eom, t, y[:m], y[m:2 * m], out, self._load_mode(mode), self.monitor,
                                      self.fixed_step)
        return out

    def _load_mode(self, mode):
        return self.dyn.load_mode(mode) if isinstance(self.dyn, FrictionDynamics) else mode

    def _diagnose(self, t: float, y: Array, mode) -> SimulationError | None:
        return diagnose_dynamics(self.dyn, t, y[:self.dyn.m], y[self.dyn.m:2 * self.dyn.m], mode)

    def _pose_note(self, y: Array) -> str:
        if self.monitor is None or self.dyn.eom.n_constraints == 0:
            return ""
        return f"; at q = {_fmt(y[:self.dyn.m])} sigma_min(Phi_q) / scale = {self.monitor.measure(y[:self.dyn.m]):.3g}"

    def _law_note(self) -> str:
        """Why a plain-sgn friction run under an adaptive integrator stalls, when it is one."""
        law = getattr(self.dyn, "law", None)
        if law is None or law.name != "sign" or self.fixed_step is not None:
            return ""
        return ("; friction 'sign' (plain sgn) chatters at stick under an adaptive integrator, which shrinks its "
                "step at every sign change: use integrator RK4 with a fixed step (paper 000's way) or friction 'exact'")

    def describe(self, t: float, y: Array) -> str:
        note = self._pose_note(y) + self._law_note()
        return note[2:] if note else ""
