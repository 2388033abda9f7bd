"""Coulomb friction in sliding joints with the normal force taken from the constraint multipliers.

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
silently.

Treatments, by name (``FRICTION_TREATMENTS``):

- ``exact``: set-valued Coulomb law with event-located stick/slip switching. The integrator's mode
  holds per contact a stick/slip entry and the frozen sliding direction (:class:`StickSlipSwitching`).
- ``regularized``: sgn(v_t) replaced by a smooth approximation (``SIGN_FUNCTIONS``: tanh, sat,
  arctan, sqrt) of width eps; no stick, the contact creeps under sub-limit loads.
- ``sign``: 000's plain sgn(v_t) at every evaluation (meant for fixed-step RK4; it chatters at v_t = 0).

Paper 000 says only that R (its F) "opposes the slider's motion"; whether it also resists the onset of
motion, i.e. counts as static holding capacity, is an open assumption. ``RESISTANCE_READINGS`` names
both readings; the exact treatment takes one (``resistance_reading``), and the parameter file of a
mechanism states which one it uses (``reference/slider_crank.toml``, ``resistance_reading``):

- ``holds``: a stuck contact is held while |f_req| <= R + mu_s |N| (R is a dry resistance, like friction);
- ``sliding_only``: held while |f_req| <= mu_s |N| (R acts only while the contact slides).

Both readings give the same sliding motion; they differ only in when a contact sticks and breaks away.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from study.errors import SimulationError
from study.solver.dynamics import Dynamics
from study.solver.stabilization import SIGN_FUNCTIONS

Array = np.ndarray

# A sign hypothesis sigma_j for N_j is consistent if sigma_j N_j >= -CONSISTENCY_RTOL * (scale of the
# terms summed into N_j). N_j comes from solves whose condition numbers stay below ~1e5 for the
# study's mechanisms, so its round-off is below 1e5 * 2.2e-16 ~ 2e-11 relative; 1e-10 rejects a
# hypothesis only when N_j has the wrong sign by more than round-off.
CONSISTENCY_RTOL = 1e-10

# Readings of a contact's constant resistance R at rest -> the fraction of R in the static limit.
RESISTANCE_READINGS = {"holds": 1.0, "sliding_only": 0.0}

#: Default width eps [m/s] of a regularized friction sign (in-house 'regularized' and 'sign', whose
#: apparent-stick band it also sets, and the Exudyn models' tanh(v/eps)). 1 mm/s is below 1 % of the
#: sliding speeds of the study's cases (slider-crank ~0.2-0.3 m/s, ram up to ~6 m/s), so the
#: regularized force equals the Coulomb force (tanh >= 0.99) except within ~2.6 mm/s of a stop.
DEFAULT_EPS = 1e-3


class PainleveError(RuntimeError):
    """No consistent, or more than one consistent, sign of the normal force (Painleve's paradox).

    Attributes
    ----------
    contacts : tuple of str
    t : float
    mu : tuple of float
        The kinetic coefficients of the contacts whose normal-force sign was hypothesized.
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


class FrictionLawError(SimulationError):
    """A contact at rest can neither stick nor slide consistently (static limit below the kinetic force)."""


# --- treatments -------------------------------------------------------------------------------
@dataclass(frozen=True)
class ExactCoulomb:
    """Set-valued Coulomb law: stick while |f_required| <= c R + mu_s |N|, else slip with R + mu_k |N|.

    c = 1 for ``resistance_reading`` 'holds', 0 for 'sliding_only' (``RESISTANCE_READINGS``, see the
    module docstring). The sliding direction is frozen in the integrator's mode between located events.
    """

    resistance_reading: str = "holds"
    name: str = "exact"
    switched: bool = True

    def __post_init__(self) -> None:
        if self.resistance_reading not in RESISTANCE_READINGS:
            raise ValueError(f"resistance_reading = {self.resistance_reading!r}; valid choices: "
                             f"{', '.join(RESISTANCE_READINGS)}")

    @property
    def static_resistance_fraction(self) -> float:
        return RESISTANCE_READINGS[self.resistance_reading]

    def factor(self, v: Array) -> Array:  # pragma: no cover - the direction comes from the mode
        raise TypeError("the exact treatment takes its sliding directions from the mode")

    def apparent_stick(self, v: Array) -> Array:  # pragma: no cover
        raise TypeError("the exact treatment has a true stick state")

    def settings(self) -> dict:
        return {"friction": self.name, "resistance_reading": self.resistance_reading}


@dataclass(frozen=True)
class RegularizedCoulomb:
    """sgn(v_t) replaced by ``SIGN_FUNCTIONS[sgn](v_t, eps)`` (tanh(v/eps), sat, arctan, sqrt).

    ``eps`` [m/s] is the width of the transition (1/c for tanh and arctan). ``stick_<contact>`` is
    reported as 1 inside the band |v_t| <= eps (apparent stick: the law has no true stick).
    """

    eps: float = DEFAULT_EPS
    sgn: str = "tanh"
    name: str = "regularized"
    switched: bool = False

    def __post_init__(self) -> None:
        if not (np.isfinite(self.eps) and self.eps > 0):
            raise ValueError(f"friction_eps = {self.eps!r} must be finite and > 0")
        smooth = [k for k in SIGN_FUNCTIONS if k != "sign"]
        if self.sgn not in smooth:
            hint = " (the plain sgn is friction='sign')" if self.sgn == "sign" else ""
            raise ValueError(f"friction_sgn = {self.sgn!r}{hint}; valid choices: {', '.join(smooth)}")

    def factor(self, v: Array) -> Array:
        return SIGN_FUNCTIONS[self.sgn](np.asarray(v, dtype=float), self.eps)

    def apparent_stick(self, v: Array) -> Array:
        return np.abs(v) <= self.eps

    def settings(self) -> dict:
        return {"friction": self.name, "friction_eps": self.eps, "friction_sgn": self.sgn}


@dataclass(frozen=True)
class PlainSign:
    """000's law as printed: f = -(R + mu |N|) sgn(v_t), sgn(0) = 0, evaluated at every stage.

    ``eps`` only defines the reported apparent stick, |v_t| <= eps.
    """

    eps: float = DEFAULT_EPS
    name: str = "sign"
    switched: bool = False

    def __post_init__(self) -> None:
        if not (np.isfinite(self.eps) and self.eps > 0):
            raise ValueError(f"friction_eps = {self.eps!r} must be finite and > 0")

    def factor(self, v: Array) -> Array:
        return np.sign(np.asarray(v, dtype=float))

    def apparent_stick(self, v: Array) -> Array:
        return np.abs(v) <= self.eps

    def settings(self) -> dict:
        return {"friction": self.name, "friction_eps": self.eps}


FRICTION_TREATMENTS = {"exact": ExactCoulomb, "regularized": RegularizedCoulomb, "sign": PlainSign}


def make_friction(name: str, eps: float = DEFAULT_EPS, sgn: str = "tanh", resistance_reading: str = "holds"):
    """A friction treatment by name: 'exact' (resistance_reading), 'regularized' (eps, sgn) or 'sign'
    (eps: apparent stick). ``resistance_reading`` matters only for 'exact', the one with a static limit."""
    if name not in FRICTION_TREATMENTS:
        raise ValueError(f"unknown friction treatment {name!r}; valid choices: None, {', '.join(FRICTION_TREATMENTS)}")
    if resistance_reading not in RESISTANCE_READINGS:
        raise ValueError(f"resistance_reading = {resistance_reading!r}; valid choices: {', '.join(RESISTANCE_READINGS)}")
    if name == "exact":
        return ExactCoulomb(resistance_reading=resistance_reading)
    if name == "regularized":
        return RegularizedCoulomb(eps=eps, sgn=sgn)
    return PlainSign(eps=eps)


# --- the coupled contact problem ----------------------------------------------------------------
@dataclass(frozen=True)
class ContactSolution:
    """Accelerations and contact forces at one state (shapes: (m,), (r,), then one entry per contact).

    ``friction`` is the tangential force f_j on the body along the tangent (resistance included;
    in stick, the force the guide must supply). ``margin`` = c R + mu_s |N| - |f| in stick (c: the
    static fraction of R, ``RESISTANCE_READINGS``), NaN in slip.
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
    tangential force, dW_j/dt = f_j v_t,j. The mode passed to :meth:`rhs` is the loads' mode
    (``n_load_modes`` entries) followed, for the exact treatment, by two entries per contact:
    (+1 stick / -1 slip, sliding direction +-1).
    """

    law: ExactCoulomb | RegularizedCoulomb | PlainSign | None = None
    n_load_modes: int = 0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.law is None:
            raise ValueError("FrictionDynamics needs a friction treatment (law=make_friction(...))")
        if not self.eom.contacts:
            raise ValueError(f"EquationsOfMotion {self.eom.name!r} has no sliding contacts: friction needs at least one")
        self._index = np.array([c.constraint_index for c in self.eom.contacts])
        self._mu_k = np.array([c.mu_kinetic for c in self.eom.contacts])
        self._mu_s = np.array([c.mu_static for c in self.eom.contacts])
        self._resistance = np.array([c.resistance for c in self.eom.contacts])
        # the part of R that holds a stuck contact (the exact law's reading; no static limit otherwise)
        self._static_resistance = self._resistance * getattr(self.law, "static_resistance_fraction", 1.0)

    def static_limit(self, normal: Array) -> Array:
        """Largest tangential force each contact can supply at rest: c R + mu_s |N| [N] (see ``RESISTANCE_READINGS``)."""
        return self._static_resistance + self._mu_s * np.abs(np.asarray(normal, dtype=float))

    @property
    def contact_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.eom.contacts)

    @property
    def n_contacts(self) -> int:
        return len(self.eom.contacts)

    def load_mode(self, mode):
        if not self._modal or mode is None:
            return None
        return tuple(mode[:self.n_load_modes])

    def phases(self, mode, v_t: Array) -> tuple[Array, Array]:
        """(stick flags, slip factors s) of the contacts in ``mode`` at tangential velocities ``v_t``."""
        nc = self.n_contacts
        if self.law.switched:
            if mode is None or len(mode) != self.n_load_modes + 2 * nc:
                raise ValueError(f"the exact friction treatment needs a mode with {self.n_load_modes} load entries and "
                                 f"2 per contact ({nc} contacts); got {mode!r}")
            entries = np.asarray(mode[self.n_load_modes:], dtype=float).reshape(nc, 2)
            stick = entries[:, 0] > 0
            return stick, np.where(stick, 0.0, entries[:, 1])
        return np.zeros(nc, dtype=bool), np.asarray(self.law.factor(v_t), dtype=float).reshape(nc)

    def _setup(self, t, q, qd, mode, stick, s):
        eom = self.eom
        J = eom.phi_q(q)
        c = eom.gamma(q, qd) + self.stabilization.bias(eom.phi(q), J @ qd)
        Jt = np.array([np.asarray(ct.tangent_jacobian(q), dtype=float) for ct in eom.contacts])
        bt = np.array([float(ct.tangent_bias(q, qd)) for ct in eom.contacts])
        v_t = Jt @ qd
        if stick is None or s is None:
            stick_m, s_m = self.phases(mode, v_t)
            stick = stick_m if stick is None else stick
            s = s_m if s is None else s
        stick = np.asarray(stick, dtype=bool)
        s = np.where(stick, 0.0, np.asarray(s, dtype=float))
        M, Q = eom.mass(q), self._forces(t, q, qd, self.load_mode(mode))
        return M, Q, J, c, Jt, bt, v_t, stick, s

    def contact_solution(self, t: float, q: Array, qd: Array, mode=None, stick=None, s=None) -> ContactSolution:
        """Solve the coupled friction problem at one state.

        ``stick`` and ``s`` (one entry per contact) override the phases implied by ``mode``.
        Raises :class:`PainleveError` unless exactly one normal-force sign hypothesis is consistent.
        """
        M, Q, J, c, Jt, bt, v_t, stick, s = self._setup(t, q, qd, mode, stick, s)
        return self._solve(t, M, Q, J, c, Jt, bt, v_t, stick, s)

    def hypotheses(self, t: float, q: Array, qd: Array, mode=None, stick=None, s=None) -> list[dict]:
        """Every normal-force sign hypothesis at one state: dicts with sigma ({contact index: +-1}),
        f, qdd, lam, normal, tol and consistent (for checks and error messages)."""
        M, Q, J, c, Jt, bt, v_t, stick, s = self._setup(t, q, qd, mode, stick, s)
        return list(self._hypotheses(M, Q, J, c, Jt, bt, stick, s))

    def _hypotheses(self, M, Q, J, c, Jt, bt, stick, s):
        """Yield dicts (sigma, f, qdd, lam, normal, tol, consistent) for each sign hypothesis."""
        nc, r, m = self.n_contacts, J.shape[0], M.shape[0]
        k = self._index
        qdd_a, lam_a = self.accelerations.solve(M, Q, J, c)
        active = [j for j in range(nc) if stick[j] or s[j] != 0.0]
        if not active:
            yield {"sigma": {}, "f": np.zeros(nc), "qdd": qdd_a, "lam": lam_a, "normal": -lam_a[k],
                   "tol": np.zeros(nc), "consistent": True}
            return
        na = len(active)
        U, L = np.empty((m, na)), np.empty((r, na))
        zero = np.zeros(r)
        for col, j in enumerate(active):
            U[:, col], L[:, col] = self.accelerations.solve(M, Jt[j], J, zero)
        assumed = [j for j in active if not stick[j] and self._mu_k[j] > 0]
        for signs in itertools.product((1.0, -1.0), repeat=len(assumed)):
            sigma = dict(zip(assumed, signs))
            A, b = np.zeros((na, na)), np.zeros(na)
            for row, j in enumerate(active):
                if stick[j]:
                    A[row] = Jt[j] @ U
                    b[row] = -(Jt[j] @ qdd_a + bt[j])
                else:
                    w = s[j] * self._mu_k[j] * sigma.get(j, 0.0)
                    A[row] = -w * L[k[j]]
                    A[row, row] += 1.0
                    b[row] = -s[j] * self._resistance[j] + w * lam_a[k[j]]
            try:
                fa = np.linalg.solve(A, b)
            except np.linalg.LinAlgError:
                yield {"sigma": sigma, "f": None, "qdd": None, "lam": None, "normal": None, "tol": None,
                       "consistent": False, "singular": True}
                continue
            lam = lam_a + L @ fa
            normal = -lam[k]
            tol = CONSISTENCY_RTOL * (np.abs(lam_a[k]) + np.abs(L[k]) @ np.abs(fa))
            consistent = all(sigma[j] * normal[j] >= -tol[j] for j in assumed)
            f = np.zeros(nc)
            f[active] = fa
            yield {"sigma": sigma, "f": f, "qdd": qdd_a + U @ fa, "lam": lam, "normal": normal, "tol": tol,
                   "consistent": consistent}

    def _solve(self, t, M, Q, J, c, Jt, bt, v_t, stick, s) -> ContactSolution:
        hyps = list(self._hypotheses(M, Q, J, c, Jt, bt, stick, s))
        good = [h for h in hyps if h["consistent"]]
        chosen = good[0] if good else None
        for other in good[1:]:
            differ = [j for j in chosen["sigma"] if chosen["sigma"][j] != other["sigma"][j]]
            # Both hypotheses agree when every contact whose assumed sign differs has N = 0 (grazing).
            if not all(abs(h["normal"][j]) <= h["tol"][j] for j in differ for h in (chosen, other)):
                chosen = None
                break
        if chosen is None:
            self._painleve(t, hyps, len(good))
        N = chosen["normal"]
        f = chosen["f"]
        margin = np.where(stick, self.static_limit(N) - np.abs(f), np.nan)
        return ContactSolution(chosen["qdd"], chosen["lam"], N, f, v_t, stick.copy(), margin)

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


# --- event-located stick/slip switching (the exact treatment) -----------------------------------
@dataclass
class StickSlipSwitching:
    """Switching rule for :func:`study.solver.integrate.integrate` (its ``switching=``).

    Mode = (load entries..., then per contact: e_stick, e_dir). e_stick = +1 in stick, -1 in slip;
    e_dir = the frozen sliding direction (+-1; kept, unused, in stick). Indicators, whose signs equal
    the mode entries while the mode holds:

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

    def initial_mode(self, t0: float, y0: Array) -> tuple:
        dyn, eom = self.dyn, self.dyn.eom
        q, qd = self._state(y0)
        nc = dyn.n_contacts
        v_t = np.array([ct.tangent_jacobian(q) @ qd for ct in eom.contacts])
        friction = []
        for j in range(nc):
            friction += [-1, int(np.sign(v_t[j])) or 1]
        load = []
        if dyn.n_load_modes:
            g = np.asarray(eom.indicators(t0, q, qd), dtype=float)
            load = [1 if gi >= 0 else -1 for gi in g]
        mode = tuple(load + friction)
        # contacts at rest: stick if the static limit allows it, else slide where the loads push
        for j in range(nc):
            if v_t[j] == 0.0:
                mode = self._rest_decision(t0, q, qd, mode, j, record=False)
        if dyn.n_load_modes and np.any(np.asarray(eom.indicators(t0, q, qd)) == 0):
            dt = 1e-9  # as integrate.initial_mode: a zero takes the sign it has just after t0
            y_ahead = y0 + dt * dyn.rhs(t0, y0, mode)
            g_ahead = np.asarray(eom.indicators(t0 + dt, *self._state(y_ahead)), dtype=float)
            g0 = np.asarray(eom.indicators(t0, q, qd), dtype=float)
            load = [(1 if ga >= 0 else -1) if gz == 0 else mi for gz, ga, mi in zip(g0, g_ahead, mode)]
            mode = tuple(load) + mode[dyn.n_load_modes:]
        self.transitions.append({"t": float(t0), "contact": None, "initial": self.describe(mode)})
        return mode

    def describe(self, mode) -> dict:
        """{contact: 'stick' | 'slip+' | 'slip-'} for a mode."""
        out = {}
        for j, ct in enumerate(self.dyn.eom.contacts):
            e = self._entry(j)
            out[ct.name] = "stick" if mode[e] > 0 else ("slip+" if mode[e + 1] > 0 else "slip-")
        return out

    def indicators(self, t: float, y: Array, mode) -> Array:
        dyn, eom = self.dyn, self.dyn.eom
        q, qd = self._state(y)
        values = list(np.asarray(eom.indicators(t, q, qd), dtype=float)) if dyn.n_load_modes else []
        stick, _ = dyn.phases(mode, None)
        sol = dyn.contact_solution(t, q, qd, mode) if stick.any() else None
        for j, ct in enumerate(eom.contacts):
            direction = float(mode[self._entry(j) + 1])
            if stick[j]:
                values += [sol.margin[j], direction]
            else:
                values += [-direction * float(ct.tangent_jacobian(q) @ qd), direction]
        return np.asarray(values)

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
        ct = dyn.eom.contacts[j]
        a_t = float(ct.tangent_jacobian(q) @ free.qdd + ct.tangent_bias(q, qd))
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
        dyn = self.dyn
        new = list(mode)
        e = self._entry(j)
        held = self._held(t, q, qd, mode, j)
        if held is not None and held.margin[j] >= 0:
            new[e] = 1
        else:
            new[e], new[e + 1] = -1, self._free_direction(t, q, qd, mode, j)
            if held is not None:
                self._check_slip_starts(t, q, qd, tuple(new), j, held)
        new = tuple(new)
        if record and new != tuple(mode):  # a contact found again at rest in its own direction is no transition
            self._log(t, j, was, new, held)
        return new

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
        dyn, ct = self.dyn, self.dyn.eom.contacts[j]
        slide = dyn.contact_solution(t, q, qd, new)
        d = new[self._entry(j) + 1]
        a_t = float(ct.tangent_jacobian(q) @ slide.qdd + ct.tangent_bias(q, qd))
        scale = float(np.abs(ct.tangent_jacobian(q) @ held.qdd).max() + abs(ct.tangent_bias(q, qd)))
        if d * a_t >= -CONSISTENCY_RTOL * max(scale, abs(a_t)):
            return
        kinetic = float(abs(slide.friction[j]))
        raise FrictionLawError(
            f"contact {ct.name!r} at rest at t = {t:.9g} s has no consistent mode: holding it needs "
            f"|f_req| = {abs(float(held.friction[j])):.6g} N, above its static limit {float(dyn.static_limit(held.normal)[j]):.6g} N "
            f"(resistance_reading {dyn.law.resistance_reading!r}), but sliding {'+' if d > 0 else '-'} meets the kinetic "
            f"force {kinetic:.6g} N (R + mu_k |N|), which decelerates it (a_t = {a_t:.3g} m/s^2 against the sliding "
            f"direction). A static limit below the kinetic resistance makes the law inconsistent here; use "
            f"resistance_reading 'holds' (the contact stays at rest, held by R + mu_s |N|) or a regularized law",
            t=float(t), quantity="friction", contact=ct.name)

    def _log(self, t, j, was, new, held):
        dyn, name = self.dyn, self.dyn.eom.contacts[j].name
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
            new = list(mode)
            new[i] = -new[i]
            return tuple(new)
        j, which = divmod(i - dyn.n_load_modes, 2)
        if which == 1:
            raise RuntimeError(f"direction entry of contact {dyn.eom.contacts[j].name!r} crossed zero; its indicator is constant")
        q, qd = self._state(y)
        e = self._entry(j)
        was = self.describe(mode)[dyn.eom.contacts[j].name]
        if mode[e] < 0:  # sliding contact came to rest: stick or slide on
            return self._rest_decision(t, q, qd, mode, j, was=was)
        # stuck contact reached its static limit: slip where the loads push (against f_req)
        held = dyn.contact_solution(t, q, qd, mode)
        new = list(mode)
        new[e], new[e + 1] = -1, self._free_direction(t, q, qd, mode, j)
        new = tuple(new)
        self._log(t, j, was, new, held)
        return new
