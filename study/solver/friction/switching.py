"""The stick/slip switching rule of the exact treatment: indicators, and the mode after a located event."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from study.errors import SimulationError
from study.laws.contact import CONSISTENCY_RTOL
from study.laws.friction import switching_pair
from study.laws.modes import LOOKAHEAD, as_mode, flip, settle_zeros, signs
from study.solver.friction.contact import FrictionDynamics, PainleveError

Array = np.ndarray


class FrictionLawError(SimulationError):
    """A contact at rest can neither stick nor slide consistently (static limit below the kinetic force), or holding
    it would lock another sliding contact or pin (a statically indeterminate hold)."""


@dataclass
class StickSlipSwitching:
    """Switching rule for :func:`study.solver.integrate.integrate` (its ``switching=``).

    Mode = (load entries..., then per contact, then per pin with friction: e_stick, e_dir). e_stick = +1
    in stick, -1 in slip; e_dir = the frozen sliding direction (+-1; kept, unused, in stick). Indicators,
    whose signs equal the mode entries while the mode holds (a pin's v_t is its relative rotation rate
    omega, its f the torque tau, its static limit T0 + mu_s r |R|_delta; the law
    ``study.laws.friction.switching_pair``):

    - e_stick in slip:  -e_dir v_t       (crosses zero when the contact comes to rest)
    - e_stick in stick: c R + mu_s |N| - |f_req|   (crosses zero when the static limit is reached)
    - e_dir:            the constant e_dir (never crosses)

    At a crossing (``on_event``): a sliding contact at rest sticks if the force needed to hold it
    satisfies |f_req| <= c R + mu_s |N| (f_req: the force the guide would have to supply). Otherwise it
    slides on in the direction the other forces push it: the sign of its tangential acceleration
    without tangential force, which is -sgn(f_req) (:meth:`_free_direction`) and stays defined at a
    kinematic dead centre, where every v_t = 0 of a one-degree-of-freedom mechanism with a moving
    crank lies (the contact cannot be held there: f_req is unbounded). A stuck contact whose limit is
    reached slips in that same direction. Each transition is logged in ``transitions``.
    """

    dyn: FrictionDynamics
    transitions: list = field(default_factory=list)

    def _state(self, y):
        m = self.dyn.m
        return y[:m], y[m:2 * m]

    def _entry(self, j: int) -> int:
        return self.dyn.n_load_modes + 2 * j

    def _rates(self, q, qd, qdd=None) -> Array:
        """Each entry's velocity (v_t, omega), or with ``qdd`` its rate of change."""
        A, b = self.dyn.rate_rows(q, qd)
        return A @ qd if qdd is None else A @ qdd + b

    def initial_mode(self, t0: float, y0: Array) -> tuple:
        dyn, eom = self.dyn, self.dyn.eom
        q, qd = self._state(y0)
        nc = dyn.n_contacts
        v_t = self._rates(q, qd)
        friction = []
        for j in range(nc):
            friction += [-1, int(np.sign(v_t[j])) or 1]
        g0 = np.asarray(eom.indicators(t0, q, qd), dtype=float) if dyn.n_load_modes else np.zeros(0)
        mode = as_mode(signs(g0)) + tuple(friction)
        # contacts at rest: stick if the static limit allows it, else slide where the loads push. A subnormal
        # velocity (below the smallest normal double, ~2.2e-308) is rest too: it carries no reliable sign
        for j in range(nc):
            if abs(v_t[j]) < np.finfo(float).tiny:
                mode = self._rest_decision(t0, q, qd, mode, j, record=False)
        if np.any(g0 == 0):  # a load's zero takes the sign it has just after t0 (the rule of study.laws.modes)
            y_ahead = y0 + LOOKAHEAD * dyn.rhs(t0, y0, mode)
            g_ahead = np.asarray(eom.indicators(t0 + LOOKAHEAD, *self._state(y_ahead)), dtype=float)
            mode = as_mode(settle_zeros(np.asarray(mode, dtype=np.int64), g0, g_ahead))
        self.transitions.append({"t": float(t0), "contact": None, "initial": self.describe(mode)})
        return mode

    def describe(self, mode) -> dict:
        """{contact or pin: 'stick' | 'slip+' | 'slip-'} for a mode."""
        out = {}
        for j, name in enumerate(self.dyn.contact_names):
            e = self._entry(j)
            out[name] = "stick" if mode[e] > 0 else ("slip+" if mode[e + 1] > 0 else "slip-")
        return out

    def indicators(self, t: float, y: Array, mode) -> Array:
        dyn, eom = self.dyn, self.dyn.eom
        q, qd = self._state(y)
        nlm, n = dyn.n_load_modes, dyn.n_contacts
        values = np.empty(nlm + 2 * n)
        if nlm:
            values[:nlm] = np.asarray(eom.indicators(t, q, qd), dtype=float)
        stick, _ = dyn.phases(mode, None)
        sol = dyn.contact_solution(t, q, qd, mode) if stick.any() else None
        level, force = (dyn.static_limit(sol.normal), sol.friction) if sol is not None else (np.zeros(n), np.zeros(n))
        v = self._rates(q, qd)
        for j in range(n):   # each entry's pair: the law study.laws.friction.switching_pair
            e = self._entry(j)
            switching_pair(bool(stick[j]), float(level[j]), float(force[j]), float(mode[e + 1]), float(v[j]), values, e)
        return values

    def _free_direction(self, t, q, qd, mode, j) -> int:
        """Sign of contact j's tangential acceleration with no tangential force there (others as in mode).

        This is where the other forces push the contact: -sgn(f_req) whenever it can be held
        (f_req = -a_t / (J_t M^-1 J_t^T) restricted to the constraints, whose denominator is > 0),
        and still defined where it cannot (a kinematic dead centre, where a_t does not depend on f_j
        and f_req's sign is round-off).
        """
        dyn = self.dyn
        stick, s = dyn.phases(mode, None)
        stick, s = stick.copy(), s.copy()
        stick[j], s[j] = False, 0.0
        free = dyn.contact_solution(t, q, qd, mode, stick=stick, s=s)
        a_t = float(self._rates(q, qd, free.qdd)[j])
        return 1 if a_t >= 0 else -1

    def _held(self, t, q, qd, mode, j):
        """The solution with contact j stuck (others as in mode), or None if that problem is singular."""
        dyn = self.dyn
        stick, s = dyn.phases(mode, None)
        stick, s = stick.copy(), s.copy()
        stick[j], s[j] = True, 0.0
        try:
            return dyn.contact_solution(t, q, qd, mode, stick=stick, s=s)
        except PainleveError as exc:
            if exc.singular:
                return None
            raise

    def _rest_decision(self, t, q, qd, mode, j, record=True, was="slip") -> tuple:
        """The mode for contact j at rest: stick if the static limit allows, else slide where pushed."""
        new = list(mode)
        e = self._entry(j)
        held = self._held(t, q, qd, mode, j)
        if held is not None and held.margin[j] >= 0:
            new[e] = 1
            self._check_not_locking(t, q, qd, tuple(new), j)
        else:
            new[e], new[e + 1] = -1, self._free_direction(t, q, qd, mode, j)
            if held is not None:
                self._check_slip_starts(t, q, qd, tuple(new), j, held)
        new = tuple(new)
        if record and new != tuple(mode):  # a contact found again at rest in its own direction is no transition
            self._log(t, j, was, new, held)
        return new

    def _check_not_locking(self, t, q, qd, new, j) -> None:
        """Raise :class:`FrictionLawError` if holding entry j (stuck in ``new``) locks an entry that still slides.

        Entry i is locked when the stuck entries and the constraints leave it no motion: its mobility A_i qdd under a
        unit force A_i^T (A_i its velocity row; qdd from the constraints plus every stuck entry's row) drops to
        round-off (``CONSISTENCY_RTOL`` of its mobility without entry j held: the mobility comes from the same
        saddle-point solves whose round-off that constant bounds, condition numbers below ~1e5). All the friction
        entries of a one-degree-of-freedom mechanism come to rest together like that: which of them holds, and how
        much, is statically indeterminate, and the exact treatment refuses it rather than pick one. Entries whose
        friction is identically zero carry no share and are not checked.
        """
        dyn = self.dyn
        stick, _ = dyn.phases(new, None)
        sliding = [i for i in range(dyn.n_contacts) if not stick[i] and dyn.carries_friction[i]]
        if not sliding:
            return
        A, _ = dyn.rate_rows(q, qd)
        M, J = dyn._mass(t, q), dyn._phi_q(t, q)
        others = [k for k in range(dyn.n_contacts) if stick[k] and k != j]

        def mobility(i, held):
            Jx = np.vstack([J, A[held]])
            try:
                qdd = dyn.accelerations.solve(M, A[i], Jx, np.zeros(Jx.shape[0]))[0]
            except np.linalg.LinAlgError:   # the stuck rows are dependent: i cannot move either
                return 0.0
            return float(A[i] @ qdd)

        locked = [dyn.contact_names[i] for i in sliding
                  if mobility(i, others + [j]) <= CONSISTENCY_RTOL * mobility(i, others)]
        if locked:
            name = dyn.contact_names[j]
            raise FrictionLawError(
                f"{name!r} comes to rest at t = {t:.9g} s and can be held, but holding it also stops "
                f"{', '.join(map(repr, locked))} (the mechanism has no motion left for them): how the holding force "
                f"splits among joints held together is statically indeterminate, and the exact treatment does not "
                f"choose a split; use friction='regularized', or friction on fewer of these joints",
                t=float(t), quantity="friction", contact=name)

    def _check_slip_starts(self, t, q, qd, new, j, held) -> None:
        """Raise :class:`FrictionLawError` if contact j, too weakly held to stick, cannot slide either.

        Sliding in direction d (the way the other forces push) is consistent only if the contact then
        accelerates that way, d a_t >= 0. With a static limit below the kinetic resistance (reading
        'sliding_only' with R > 0, or mu_s < mu_k) a required force between the two leaves no
        consistent mode: held, the limit is exceeded; sliding, the kinetic force R + mu_k |N| exceeds the
        push and stops the contact at once. Without this check the integrator would locate a new stop
        after every restart at the same instant, forever (the Zeno limit of those restarts is a contact
        held by the kinetic force, i.e. the reading 'holds').
        """
        dyn, name = self.dyn, self.dyn.contact_names[j]
        slide = dyn.contact_solution(t, q, qd, new)
        d = new[self._entry(j) + 1]
        A, b = dyn.rate_rows(q, qd)
        a_t = float(A[j] @ slide.qdd + b[j])
        scale = float(abs(A[j] @ held.qdd) + abs(b[j]))
        if d * a_t >= -CONSISTENCY_RTOL * max(scale, abs(a_t)):
            return
        kinetic = float(abs(slide.friction[j]))
        limit = float(dyn.static_limit(held.normal)[j])
        if j >= len(dyn.eom.contacts):   # a pin: its T0 always holds, so only mu_s < mu_k gets here
            what, unit, rate, law, fix = "pin", "N m", "rad/s^2", "T0 + mu_k r |R|_delta", "mu_s >= mu_k for the pin"
        else:
            what, unit, rate, law = "contact", "N", "m/s^2", "R + mu_k |N|"
            fix = "resistance_reading 'holds' (the contact stays at rest, held by R + mu_s |N|)"
        raise FrictionLawError(
            f"{what} {name!r} at rest at t = {t:.9g} s has no consistent mode: holding it needs "
            f"|f_req| = {abs(float(held.friction[j])):.6g} {unit}, above its static limit {limit:.6g} {unit} "
            f"(resistance_reading {dyn.law.resistance_reading!r}), but sliding {'+' if d > 0 else '-'} meets the "
            f"kinetic "
            f"{'torque' if what == 'pin' else 'force'} {kinetic:.6g} {unit} ({law}), which decelerates it "
            f"(rate {a_t:.3g} {rate} against the sliding direction). A static limit below the kinetic one makes the "
            f"law inconsistent here; use {fix} or a regularized law",
            t=float(t), quantity="friction", contact=name)

    def _log(self, t, j, was, new, held):
        dyn, name = self.dyn, self.dyn.contact_names[j]
        entry = {"t": float(t), "contact": name, "from": was, "to": self.describe(new)[name]}
        if held is None:  # holding the contact is a singular problem: it is kinematically locked
            entry.update({"f_required": float("inf"), "normal": float("nan"), "limit": float("nan")})
        else:
            entry.update({"f_required": float(held.friction[j]), "normal": float(held.normal[j]),
                          "limit": float(dyn.static_limit(held.normal)[j])})
        self.transitions.append(entry)

    def on_event(self, t: float, y: Array, mode, i: int) -> tuple:
        """The mode after indicator i crossed zero at (t, y).

        Crossings at the same instant (a load's switch on the same velocity, e.g. the quick-return's
        cutting law on v_D) are settled here too: every other indicator already past zero at t is
        processed, each once, so the integrator restarts from a mode consistent with every indicator.
        """
        mode = self._switch(t, y, mode, i)
        done = {i}
        for _ in range(len(mode)):
            g = self.indicators(t, y, mode)
            late = [k for k in range(len(mode)) if k not in done and g[k] * mode[k] < 0]
            if not late:
                break
            mode = self._switch(t, y, mode, late[0])
            done.add(late[0])
        return mode

    def _switch(self, t: float, y: Array, mode, i: int) -> tuple:
        dyn = self.dyn
        if i < dyn.n_load_modes:
            return as_mode(flip(np.asarray(mode, dtype=np.int64), i))
        j, which = divmod(i - dyn.n_load_modes, 2)
        if which == 1:
            raise RuntimeError(f"direction entry of contact {dyn.contact_names[j]!r} crossed zero; its indicator is constant")
        q, qd = self._state(y)
        e = self._entry(j)
        was = self.describe(mode)[dyn.contact_names[j]]
        if mode[e] < 0:  # sliding contact came to rest: stick or slide on
            return self._rest_decision(t, q, qd, mode, j, was=was)
        # stuck contact reached its static limit: slip where the loads push (against f_req)
        held = dyn.contact_solution(t, q, qd, mode)
        new = list(mode)
        new[e], new[e + 1] = -1, self._free_direction(t, q, qd, mode, j)
        new = tuple(new)
        self._log(t, j, was, new, held)
        return new
