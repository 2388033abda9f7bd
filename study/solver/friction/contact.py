"""The contact solve: accelerations, normal and friction forces of every contact at one state.

SPEC sec. 1 and paper 000 (eqs. 3, 10, 25-34). Each :class:`study.model.SlidingContact` j of an
EquationsOfMotion has its normal gap as constraint row k_j, so its normal force is N_j = -lambda[k_j]
(000: the normal reaction is ideal and drops out of D Q^(N) = 0, eq. 6). Its tangential reaction
f_j acts along the tangent, as the generalized force J_t,j^T f_j (000 eqs. 5, 19-20)::

    M qdd + Phi_q^T lambda = Q + sum_j J_t,j^T f_j,        Phi_q qdd = c = gamma + b(Phi, Phidot)

    slip (direction s_j):  f_j = -s_j (R_j + mu_k,j |N_j|)                      (000 eq. 3, 32)
    stick:                 J_t,j qdd + tangent_bias_j = 0 (v_t,j stays 0),  f_j its multiplier

R_j is the contact's constant ``resistance`` (000's F). N depends on qdd, and qdd on f: the coupled
problem is solved exactly at every evaluation. Everything is linear in f once the sign of each
N_j is assumed (|N_j| = sigma_j N_j), so by superposition

    qdd = qdd_a + U f,   lambda = lambda_a + L f

(qdd_a, lambda_a: no tangential force; columns of U, L: a unit tangential force at one contact,
from the same acceleration solver, so the multiplier form and the null-space (000's D matrix)
forms both work), and f solves a small linear system per sign hypothesis sigma. This is the
saddle-point system [[M, J^T], [J, 0]] with the friction column moved to the left-hand side,
reduced to the contacts. A hypothesis is consistent if sigma_j N_j >= 0 for every assumed sign.
Exactly one consistent solution is used. None, or two that differ, is Painleve's paradox
(friction makes the normal force ill-posed) and raises :class:`PainleveError`; nothing is chosen
silently. The treatments of sgn are in :mod:`study.solver.friction.laws`. The solve itself (the hypotheses, the
consistency rule, the choice; the pins' Newton iterate below) is ``study.laws.contact``, for both backends: this
module computes qdd_a, lambda_a, U, L with its acceleration solver, calls it, and names what fails.

Revolute joints with friction (:class:`study.model.FrictionalPin`, cut joints whose reaction R_p is the multipliers
of their two rows) add a torque on the relative rotation omega_p = P_p qd (P_p = d omega_p / d qd), generalized
force P_p^T tau_p:

    slip (slip factor s_p):  tau_p = -(mu_k,p r_p |R_p|_delta + T0_p) s_p,   |R|_delta = sqrt(|R|^2 + delta^2)
    stick:                   P_p qdd + rate_bias_p = 0 (omega_p stays 0), tau_p its multiplier

A stuck pin is one more constraint row, appended after the others, whose multiplier is -tau_p. R depends on the
sliding pins' tau affinely (R = R_0 + L tau, L their unit-torque responses) and tau on |R|: the small nonlinear
system tau = g(tau) is solved by Newton (``pin_friction_solve_rtol``), around the contacts' solve above, which is
repeated at every iterate. s_p is the treatment's slip factor of omega_p [rad/s] ('regularized', 'sign'; the width
friction_eps read in rad/s) or the mode's frozen direction ('exact'). A stuck pin holds while |tau_p| <=
mu_s,p r_p |R_p|_delta + T0_p (its constant torque always holds; the readings of ``RESISTANCE_READINGS`` are paper
000's reading of a slider's resistance). The pins follow the contacts in every per-contact output and in the exact
treatment's mode (``normal_<pin>`` = |R| [N], ``friction_<pin>`` = tau [N m], ``v_t`` = omega [rad/s],
``work_friction_<pin>`` = its work).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from study.laws.contact import (CONSISTENT, CONVERGED, FORCE, NORMAL, OK, PIN_MAX_ITERATIONS, SCRATCH_ROWS,
                                SIGMA, SINGULAR_HYPOTHESIS, STEP_FAILED, TOL, active_entries, assumed_signs,
                                contact_forces, hypothesis, pin_newton_step)
from study.laws.friction import friction_level, pin_norm, stuck_margin
from study.reference_data import tolerance
from study.solver.dynamics import Dynamics
from study.solver.friction.laws import ExactCoulomb, PlainSign, RegularizedCoulomb

Array = np.ndarray


class PinFrictionError(RuntimeError):
    """The friction torques of revolute joints did not converge (``joints``, ``t``, ``q``, ``qd`` as attributes)."""

    def __init__(self, message: str, joints: tuple[str, ...], t: float, q, qd):
        super().__init__(message)
        self.joints, self.t, self.q, self.qd = joints, t, np.array(q), np.array(qd)


class PainleveError(RuntimeError):
    """No consistent, or more than one consistent, sign of the normal force (Painleve's paradox).

    Attributes
    ----------
    contacts : tuple of str
    t : float
    mu : tuple of float
        The kinetic coefficients of the contacts whose normal-force sign was hypothesized (for a singular hold of
        stuck pins: their static coefficients).
    consistent : int
        Number of consistent hypotheses found (0 or >= 2 distinct ones).
    singular : bool
        True if every hypothesis gave a singular system (e.g. a stuck contact that the other
        constraints lock, so its tangential force is indeterminate).
    """

    def __init__(self, message: str, contacts: tuple[str, ...], t: float, mu: tuple[float, ...], consistent: int,
                 singular: bool = False):
        super().__init__(message)
        self.contacts, self.t, self.mu, self.consistent = contacts, t, mu, consistent
        self.singular = singular


@dataclass(frozen=True)
class ContactSolution:
    """Accelerations and contact forces at one state (shapes: (m,), (r,), then one entry per contact, then per pin).

    ``friction`` is the tangential force f_j on the body along the tangent (resistance included;
    in stick, the force the guide must supply), a pin's torque tau_p. ``margin`` = c R + mu_s |N| - |f| in stick
    (c: the static fraction of R, ``RESISTANCE_READINGS``), T0 + mu_s r |R|_delta - |tau| for a stuck pin, NaN in
    slip.
    """

    qdd: Array
    lam: Array
    normal: Array
    friction: Array
    v_t: Array
    stick: Array
    margin: Array


@dataclass
class FrictionDynamics(Dynamics):
    """:class:`Dynamics` with Coulomb friction at every contact of the equations of motion.

    State y = [q, qd, W_applied, W_friction]: the last block is the work of each contact's
    tangential force, dW_j/dt = f_j v_t,j (a pin's: tau_p omega_p). The mode passed to :meth:`rhs` is the
    loads' mode (``n_load_modes`` entries) followed, for the exact treatment, by two entries per contact and
    then per pin: (+1 stick / -1 slip, sliding direction +-1).
    """

    law: ExactCoulomb | RegularizedCoulomb | PlainSign | None = None
    n_load_modes: int = 0
    pin_norm_width: float | None = None   # delta [N] of |R|_delta; None: tolerance("pin_friction_norm_width")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.law is None:
            raise ValueError("FrictionDynamics needs a friction treatment (law=make_friction(...))")
        pins = tuple(getattr(self.eom, "pin_frictions", ()))
        if not self.eom.contacts and not pins:
            raise ValueError(f"EquationsOfMotion {self.eom.name!r} has no sliding contacts and no revolute joints with "
                             f"friction: friction needs at least one")
        self._pins = pins
        self._nc = len(self.eom.contacts)
        if pins:
            self._pin_rows = np.array([p.rows for p in pins], dtype=int)
            self._pin_coef = np.array([p.mu_kinetic * p.radius for p in pins])
            self._pin_torque = np.array([p.torque for p in pins])
            delta = tolerance("pin_friction_norm_width") if self.pin_norm_width is None else self.pin_norm_width
            if not (np.isfinite(delta) and delta > 0):
                raise ValueError(f"pin_norm_width = {delta!r} must be finite and > 0")
            self._pin_delta = float(delta)
            self._pin_rtol = tolerance("pin_friction_solve_rtol")
        self._index = np.array([c.constraint_index for c in self.eom.contacts], dtype=int)
        self._mu_k = np.array([c.mu_kinetic for c in self.eom.contacts])
        self._mu_s = np.array([c.mu_static for c in self.eom.contacts])
        self._resistance = np.array([c.resistance for c in self.eom.contacts])
        # static limit per entry (contacts, then pins): the part of R that holds (the exact law's reading), or a pin's
        # whole T0, plus mu_s |N| (mu_s r |R|_delta)
        fraction = getattr(self.law, "static_resistance_fraction", 1.0)
        self._static_resistance = np.concatenate([fraction * self._resistance, [p.torque for p in pins]])
        self._static_coef = np.concatenate([self._mu_s, [p.mu_static * p.radius for p in pins]])
        self._phase_parameters = np.array(self.law.compiled_parameters(), dtype=float)
        #: entries with friction data that is not identically zero (a coefficient or a constant resistance > 0)
        self.carries_friction = np.concatenate([
            (self._mu_s > 0) | (self._mu_k > 0) | (self._resistance > 0),
            [p.mu_static > 0 or p.mu_kinetic > 0 or p.torque > 0 for p in pins]]).astype(bool)

    @property
    def pin_numbers(self) -> tuple[float, float]:
        """(delta [N] of |R|_delta, relative tolerance of the pins' torque solve); zeros without pins."""
        return (self._pin_delta, self._pin_rtol) if self._pins else (0.0, 0.0)

    def static_limit(self, normal: Array) -> Array:
        """Largest force (torque) each contact (pin) can supply at rest: c R + mu_s |N| [N] for a contact,
        T0 + mu_s r |R|_delta [N m] for a pin (``normal``: the per-entry outputs; see ``RESISTANCE_READINGS``)."""
        n = np.abs(np.asarray(normal, dtype=float))
        if self._pins:
            n[self._nc:] = pin_norm.py_func(n[self._nc:], 0.0, self._pin_delta)
        return friction_level.py_func(self._static_coef, n, self._static_resistance)

    def rate_rows(self, q: Array, qd: Array) -> tuple[Array, Array]:
        """(A (n, m), b (n,)): each entry's velocity A_j qd and rate A_j qdd + b_j, contacts (J_t, tangent bias)
        then pins (P, rate_bias)."""
        rows = [np.asarray(c.tangent_jacobian(q), dtype=float) for c in self.eom.contacts]
        rows += [np.asarray(p.rate_jacobian(q), dtype=float) for p in self._pins]
        bias = [float(c.tangent_bias(q, qd)) for c in self.eom.contacts]
        bias += [float(p.rate_bias(q, qd)) for p in self._pins]
        return np.array(rows).reshape(len(rows), q.size), np.array(bias)

    @property
    def contact_names(self) -> tuple[str, ...]:
        """The sliding contacts, then the revolute joints with friction."""
        return tuple(c.name for c in self.eom.contacts) + tuple(p.name for p in self._pins)

    @property
    def n_contacts(self) -> int:
        """Entries of the per-contact outputs: sliding contacts and revolute joints with friction."""
        return self._nc + len(self._pins)

    def load_mode(self, mode):
        if not self._modal or mode is None:
            return None
        return tuple(mode[:self.n_load_modes])

    def phases(self, mode, v_t: Array | None) -> tuple[Array, Array]:
        """(stick flags, slip factors s) of the contacts, then the pins, in ``mode`` at their velocities ``v_t``
        (tangential velocities, then relative rotation rates; None for the exact treatment, which reads only the
        mode): the treatment's ``compiled_phases`` (``study.laws.friction``), as on the compiled path."""
        n = self.n_contacts
        entries = np.zeros(0, dtype=np.int64)
        if self.law.switched:
            if mode is None or len(mode) != self.n_load_modes + 2 * n:
                raise ValueError(f"the exact friction treatment needs a mode with {self.n_load_modes} load entries and "
                                 f"2 per contact and pin ({n}); got {mode!r}")
            entries = np.asarray(mode, dtype=np.int64)
        v = np.zeros(n) if v_t is None else np.ascontiguousarray(v_t, dtype=float).reshape(n)
        stick, s = np.empty(n, dtype=bool), np.empty(n)
        self.law.compiled_phases(entries, self.n_load_modes, v, self._phase_parameters, 0, stick, s)
        return stick, s

    def _setup(self, t, q, qd, mode, stick, s):
        eom = self.eom
        J = self._phi_q(t, q)
        c = eom.gamma(q, qd) + self.stabilization.bias(eom.phi(q), J @ qd)
        A, b = self.rate_rows(q, qd)
        v = A @ qd
        if stick is None or s is None:
            stick_m, s_m = self.phases(mode, v)
            stick = stick_m if stick is None else stick
            s = s_m if s is None else s
        stick = np.asarray(stick, dtype=bool)
        s = np.where(stick, 0.0, np.asarray(s, dtype=float))
        M, Q = self._mass(t, q), self._forces(t, q, qd, self.load_mode(mode))
        return M, Q, J, c, A, b, v, stick, s

    def contact_solution(self, t: float, q: Array, qd: Array, mode=None, stick=None, s=None) -> ContactSolution:
        """Solve the coupled friction problem at one state.

        ``stick`` and ``s`` (one entry per contact, then per pin) override the phases implied by ``mode``.
        Raises :class:`PainleveError` unless exactly one normal-force sign hypothesis is consistent, or if
        holding the stuck entries is a singular problem (``singular``).
        """
        M, Q, J, c, A, b, v, stick, s = self._setup(t, q, qd, mode, stick, s)
        nc = self._nc
        if not self._pins:
            return self._solve(t, M, Q, J, c, A, b, v, stick, s)
        return self._solve_pins(t, q, qd, M, Q, J, c, A[:nc], b[:nc], v, stick, s, A[nc:], b[nc:])

    def _solve_pins(self, t, q, qd, M, Q, J, c, Jt, bt, v, stick, s, P, pb) -> ContactSolution:
        """Newton on F(tau) = tau + (mu r |R(tau)|_delta + T0) s = 0 of the sliding pins around the contacts' solve
        (each iterate: ``study.laws.contact.pin_newton_step``), the stuck pins' locks appended to the constraints."""
        nc, pins, r = self._nc, self._pins, J.shape[0]
        held, slip = stick[nc:], s[nc:]
        free = ~held
        if held.any():
            J, c = np.vstack([J, P[held]]), np.concatenate([c, -pb[held]])
        Pf = P[free]
        try:   # the unit-torque responses of the free pins' multipliers: dlam[j] = d lambda / d tau_j
            dlam = np.array([self.accelerations.solve(M, row, J, np.zeros(J.shape[0]))[1] for row in Pf])
        except np.linalg.LinAlgError:
            self._singular_hold(t, held)
        n = len(Pf)
        dlam = np.ascontiguousarray(dlam, dtype=float).reshape(n, J.shape[0])
        rows = np.ascontiguousarray(self._pin_rows[free], dtype=np.int64).reshape(2 * n)
        slip_f, coef, torque = np.ascontiguousarray(slip[free]), self._pin_coef[free], self._pin_torque[free]
        tau_f, norm, res, step, jac, piv = np.zeros(n), np.empty(n), np.empty(n), np.empty(n), np.empty((n, n)), \
            np.empty(n, dtype=np.int64)
        history = []
        for _ in range(PIN_MAX_ITERATIONS):
            try:
                sol = self._solve(t, M, Q + Pf.T @ tau_f, J, c, Jt, bt, v[:nc], stick[:nc], s[:nc])
            except np.linalg.LinAlgError:
                self._singular_hold(t, held)
            outcome = pin_newton_step(sol.lam, rows, dlam, tau_f, slip_f, coef, torque, self._pin_delta,
                                      self._pin_rtol, norm, res, step, jac, piv)
            history.append(float(np.max(np.abs(res), initial=0.0)))
            if outcome == CONVERGED:
                R = sol.lam[self._pin_rows]                  # (np, 2)
                tau = np.zeros(len(pins))
                tau[free], tau[held] = tau_f, -sol.lam[r:]
                normal = np.concatenate([sol.normal, pin_norm.py_func(R[:, 0], R[:, 1], 0.0)])   # |R|
                friction = np.concatenate([sol.friction, tau])
                margin = np.where(stick, stuck_margin.py_func(self.static_limit(normal), friction), np.nan)
                return ContactSolution(sol.qdd, sol.lam[:r], normal, friction, v, stick.copy(), margin)
            if outcome == STEP_FAILED:
                break
        names = tuple(p.name for p in pins)
        raise PinFrictionError(
            f"t = {t:.9g} s: the friction torques of revolute joint(s) {', '.join(map(repr, names))} did not converge "
            f"in {len(history)} Newton iterations (max |tau - g(tau)| per iteration: "
            f"{', '.join(f'{h:.3g}' for h in history[-5:])} N m; relative tolerance {self._pin_rtol:g}) at "
            f"q = {np.array2string(np.asarray(q), precision=6)}, qd = {np.array2string(np.asarray(qd), precision=6)}: "
            f"a likely cause is mu * radius too large for the joint's unit-torque reaction (|mu r s dR/dtau| >= 1)",
            names, float(t),
            q, qd)

    def hypotheses(self, t: float, q: Array, qd: Array, mode=None, stick=None, s=None) -> list[dict]:
        """Every normal-force sign hypothesis at one state: dicts with sigma ({contact index: +-1}),
        f, qdd, lam, normal, tol and consistent (for checks and error messages)."""
        M, Q, J, c, A, b, _, stick, s = self._setup(t, q, qd, mode, stick, s)
        nc = self._nc
        return self._hypotheses(M, Q, J, c, np.ascontiguousarray(A[:nc]), b[:nc], stick[:nc], s[:nc])

    def _responses(self, M, Q, J, c, Jt, stick, s):
        """(qdd_a, lambda_a, active, n_act, U, L): the solution without tangential forces and the responses to a unit
        tangential force at each active contact (the columns of U, L), from this dynamics' acceleration solver."""
        qdd, lam = self.accelerations.solve(M, Q, J, c)
        qdd, lam = np.array(qdd, dtype=float), np.array(lam, dtype=float)
        active = np.zeros(self._nc, dtype=np.int64)
        n_act = active_entries(stick, s, active)
        U, L = np.empty((qdd.size, n_act)), np.empty((lam.size, n_act))
        zero = np.zeros(lam.size)
        for col, j in enumerate(active[:n_act]):
            U[:, col], L[:, col] = self.accelerations.solve(M, Jt[j], J, zero)
        return qdd, lam, active, n_act, U, L

    def _hypotheses(self, M, Q, J, c, Jt, bt, stick, s) -> list[dict]:
        """A dict (sigma, f, qdd, lam, normal, tol, consistent, singular) for each sign hypothesis, each from
        ``study.laws.contact.hypothesis`` (the one the solve uses)."""
        nc = self._nc
        qdd_a, lam_a, active, n_act, U, L = self._responses(M, Q, J, c, Jt, stick, s)
        assumed = np.zeros(nc, dtype=np.int64)
        n_ass = assumed_signs(active, n_act, stick, self._mu_k, assumed)
        scratch, A, piv = np.zeros((SCRATCH_ROWS, nc)), np.zeros((nc, nc)), np.zeros(nc, dtype=np.int64)
        hyps = []
        for combo in range(1 << n_ass):
            outcome = hypothesis(combo, assumed, n_ass, active, n_act, stick, s, Jt, bt, qdd_a, lam_a, U, L,
                                 self._index, self._mu_k, self._resistance, A, piv, scratch)
            rows = active[:n_act]
            sigma = {int(rows[a]): float(scratch[SIGMA, a]) for a in assumed[:n_ass]}
            if outcome == SINGULAR_HYPOTHESIS:
                hyps.append({"sigma": sigma, "f": None, "qdd": None, "lam": None, "normal": None, "tol": None,
                             "consistent": False, "singular": True})
                continue
            fa = scratch[FORCE, :n_act]
            f, normal, tol = np.zeros(nc), -(lam_a + L @ fa)[self._index], np.zeros(nc)
            f[rows], normal[rows], tol[rows] = fa, scratch[NORMAL, :n_act], scratch[TOL, :n_act]
            hyps.append({"sigma": sigma, "f": f, "qdd": qdd_a + U @ fa, "lam": lam_a + L @ fa, "normal": normal,
                         "tol": tol, "consistent": outcome == CONSISTENT})
        return hyps

    def _solve(self, t, M, Q, J, c, Jt, bt, v_t, stick, s) -> ContactSolution:
        """The contacts' solve (``study.laws.contact.contact_forces``); PainleveError unless exactly one sign
        hypothesis is consistent."""
        nc = self._nc
        qdd, lam, active, n_act, U, L = self._responses(M, Q, J, c, Jt, stick, s)
        f, N = np.zeros(nc), np.zeros(nc)
        status = contact_forces(active, n_act, stick, s, Jt, bt, qdd, lam, U, L, self._index, self._mu_k,
                                self._resistance, np.zeros((nc, nc)), np.zeros(nc, dtype=np.int64),
                                np.zeros((SCRATCH_ROWS, nc)), f, N)
        if status != OK:
            hyps = self._hypotheses(M, Q, J, c, Jt, bt, stick, s)
            self._painleve(t, hyps, sum(h["consistent"] for h in hyps))
        limit = friction_level.py_func(self._mu_s, N, self._static_resistance[:nc])
        margin = np.where(stick, stuck_margin.py_func(limit, f), np.nan)
        return ContactSolution(qdd, lam, N, f, v_t, stick.copy(), margin)

    def _singular_hold(self, t, held):
        names = tuple(p.name for p, h in zip(self._pins, held) if h)
        raise PainleveError(f"t = {t:.9g} s: the stick problem of pin(s) {', '.join(map(repr, names))} is singular "
                            f"(the other constraints lock their relative rotation)", names, float(t),
                            tuple(p.mu_static for p, h in zip(self._pins, held) if h), 0, singular=True)

    def _painleve(self, t, hyps, n_good):
        assumed = sorted(hyps[0]["sigma"])
        singular = all(h.get("singular") for h in hyps)
        if not assumed:  # no sign was assumed: only stuck contacts, and their system is singular
            names = tuple(c.name for c in self.eom.contacts)
            raise PainleveError(f"t = {t:.9g} s: the stick problem of contact(s) {', '.join(map(repr, names))} is "
                                f"singular (the other constraints lock their tangential motion)", names, float(t),
                                tuple(float(m) for m in self._mu_s), 0, singular=True)
        names = tuple(self.eom.contacts[j].name for j in assumed)
        mus = tuple(float(self._mu_k[j]) for j in assumed)
        lines = []
        for h in hyps:
            label = ", ".join(f"N_{self.eom.contacts[j].name} {'>' if v > 0 else '<'} 0" for j, v in h["sigma"].items())
            if h.get("singular"):
                lines.append(f"  assume {label}: singular system")
            else:
                got = ", ".join(f"N_{self.eom.contacts[j].name} = {h['normal'][j]:.6g}" for j in assumed)
                lines.append(f"  assume {label}: {got} -> {'consistent' if h['consistent'] else 'inconsistent'}")
        what = "no consistent" if n_good == 0 else f"{n_good} different consistent"
        raise PainleveError(
            f"Painleve paradox at t = {t:.9g} s, contact(s) {', '.join(repr(n) for n in names)} with mu = "
            f"{', '.join(f'{m:g}' for m in mus)}: {what} signs of the normal force (exactly one is needed):\n"
            + "\n".join(lines), names, float(t), mus, n_good, singular=singular)

    # --- Dynamics interface ----------------------------------------------------------------------
    def evaluate(self, t: float, q: Array, qd: Array, mode=None) -> tuple[Array, Array]:
        sol = self.contact_solution(t, q, qd, mode)
        return sol.qdd, sol.lam

    def powers(self, t: float, q: Array, qd: Array, mode=None) -> Array:
        return super().powers(t, q, qd, self.load_mode(mode))

    def rhs(self, t: float, y: Array, mode=None) -> Array:
        self.nfev += 1
        q, qd, _ = self.split(y)
        sol = self.contact_solution(t, q, qd, mode)
        return np.concatenate([qd, sol.qdd, self.powers(t, q, qd, mode), sol.friction * sol.v_t])

    def stick_flags(self, sol: ContactSolution) -> Array:
        """1.0 in stick (exact) or apparent stick |v_t| <= eps (regularized, sign), else 0.0."""
        if self.law.switched:
            return sol.stick.astype(float)
        return np.asarray(self.law.apparent_stick(sol.v_t), dtype=float)
