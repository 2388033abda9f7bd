"""Friction laws: the treatments of Coulomb's sgn(v_t) by name, and the readings of a contact's resistance.

Treatments, by name (``FRICTION_TREATMENTS``):

- ``exact``: set-valued Coulomb law with event-located stick/slip switching. The integrator's mode
  holds per contact a stick/slip entry and the frozen sliding direction
  (:class:`study.solver.friction.switching.StickSlipSwitching`).
- ``regularized``: sgn(v_t) replaced by a smooth approximation (``SIGN_FUNCTIONS``: tanh, sat,
  arctan, sqrt) of width eps; no stick, the contact creeps under sub-limit loads.
- ``sign``: 000's plain sgn(v_t) at every evaluation (meant for fixed-step RK4; it chatters at v_t = 0).

Each treatment is one class for both backends: ``phases`` gives the contacts' stick flags and slip
factors s (f = -s (R + mu_k |N|) in slip) on the reference path, and ``compiled_phases`` is the same law
for the compiled path, a numba function of signature ``study.kernels.signatures.PHASES`` that reads the
numbers ``compiled_parameters()`` at its offset in the compiled options (``study.fast.frontend.pack_options``).
The slip factors of 'regularized' and 'sign' are ``study.kernels.signs`` functions, the same on both paths.

Paper 000 says only that R (its F) "opposes the slider's motion"; whether it also resists the onset of
motion, i.e. counts as static holding capacity, is an open assumption. ``RESISTANCE_READINGS`` names
both readings; the exact treatment takes one (``resistance_reading``), and the parameter file of a
mechanism states which one it uses (``reference/slider_crank.toml``, ``resistance_reading``):

- ``holds``: a stuck contact is held while |f_req| <= R + mu_s |N| (R is a dry resistance, like friction);
- ``sliding_only``: held while |f_req| <= mu_s |N| (R acts only while the contact slides).

Both readings give the same sliding motion; they differ only in when a contact sticks and breaks away.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from study.kernels.cache import kernel
from study.kernels.signatures import PHASES
from study.kernels.signs import SIGN_FUNCTIONS, SIGN_IDS, apply, sign_function

Array = np.ndarray

# Readings of a contact's constant resistance R at rest -> the fraction of R in the static limit.
RESISTANCE_READINGS = {"holds": 1.0, "sliding_only": 0.0}

#: Default width eps [m/s] of a regularized friction sign (in-house 'regularized' and 'sign', whose
#: apparent-stick band it also sets, and the Exudyn models' tanh(v/eps)). 1 mm/s is below 1 % of the
#: sliding speeds of the study's cases (slider-crank ~0.2-0.3 m/s, ram up to ~6 m/s), so the
#: regularized force equals the Coulomb force (tanh >= 0.99) except within ~2.6 mm/s of a stop.
DEFAULT_EPS = 1e-3


@kernel()
def friction_level(coefficient, normal, constant):
    """The size of a Coulomb force or torque, constant + coefficient |normal|: a contact's R + mu |N| [N], a pin's
    T0 + mu r |R|_delta [N m]; with the static coefficient, the limit a stuck entry holds. Scalars (compiled) or
    arrays (``.py_func``, reference path)."""
    return constant + coefficient * np.abs(normal)


@kernel()
def pin_norm(rx, ry, delta):
    """|R|_delta = sqrt(Rx^2 + Ry^2 + delta^2) of a pin's reaction (delta: ``pin_friction_norm_width``), the smooth
    norm that replaces |R|'s kink at R = 0 in the pin's friction torque. Scalars or arrays (``.py_func``)."""
    return np.sqrt(rx * rx + ry * ry + delta * delta)


@kernel(PHASES)
def _mode_phases(mode, nlm, vt, cf, off, stick, s):
    """ExactCoulomb.phases: mode = the loads' nlm entries, then per contact (+1 stick / -1 slip, direction)."""
    for j in range(vt.size):
        stick[j] = mode[nlm + 2 * j] > 0
        s[j] = 0.0 if stick[j] else float(mode[nlm + 2 * j + 1])


@kernel(PHASES)
def _slip_phases(mode, nlm, vt, cf, off, stick, s):
    """SlipFactor.phases, with cf[off:] = SIGN_IDS[sgn], eps (SlipFactor.compiled_parameters)."""
    kind, eps = int(cf[off]), cf[off + 1]
    for j in range(vt.size):
        stick[j] = False
        s[j] = sign_function(kind, vt[j], eps)


class SlipFactor:
    """A treatment without a true stick: the slip factor is ``SIGN_FUNCTIONS[sgn](v_t, eps)`` at every
    evaluation, and ``stick_<contact>`` is reported as 1 inside the band |v_t| <= eps (apparent stick)."""

    sgn: str
    eps: float

    def factor(self, v: Array) -> Array:
        return apply(self.sgn, v, self.eps)

    def phases(self, entries: Array | None, v: Array) -> tuple[Array, Array]:
        """No contact sticks; the slip factors at the tangential velocities v (no mode entries: ``entries`` None)."""
        v = np.asarray(v, dtype=float)
        return np.zeros(v.size, dtype=bool), self.factor(v).reshape(v.size)

    compiled_phases = staticmethod(_slip_phases)

    def compiled_parameters(self) -> list[float]:
        return [float(SIGN_IDS[self.sgn]), self.eps]

    def apparent_stick(self, v: Array) -> Array:
        return np.abs(v) <= self.eps


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

    def phases(self, entries: Array, v: Array) -> tuple[Array, Array]:
        """Stick where the mode says so (``entries``: (nc, 2) mode entries, +1 stick / -1 slip and the frozen
        direction), else slip in the frozen direction."""
        stick = entries[:, 0] > 0
        return stick, np.where(stick, 0.0, entries[:, 1])

    compiled_phases = staticmethod(_mode_phases)

    def compiled_parameters(self) -> list[float]:
        return []

    def apparent_stick(self, v: Array) -> Array:  # pragma: no cover
        raise TypeError("the exact treatment has a true stick state")

    def settings(self) -> dict:
        return {"friction": self.name, "resistance_reading": self.resistance_reading}


@dataclass(frozen=True)
class RegularizedCoulomb(SlipFactor):
    """sgn(v_t) replaced by ``SIGN_FUNCTIONS[sgn](v_t, eps)`` (tanh(v/eps), sat, arctan, sqrt).

    ``eps`` [m/s] is the width of the transition (1/c for tanh and arctan).
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

    def settings(self) -> dict:
        return {"friction": self.name, "friction_eps": self.eps, "friction_sgn": self.sgn}


@dataclass(frozen=True)
class PlainSign(SlipFactor):
    """000's law as printed: f = -(R + mu |N|) sgn(v_t), sgn(0) = 0, evaluated at every stage.

    ``eps`` only defines the reported apparent stick, |v_t| <= eps.
    """

    eps: float = DEFAULT_EPS
    name: str = "sign"
    switched: bool = False
    sgn: ClassVar[str] = "sign"

    def __post_init__(self) -> None:
        if not (np.isfinite(self.eps) and self.eps > 0):
            raise ValueError(f"friction_eps = {self.eps!r} must be finite and > 0")

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
