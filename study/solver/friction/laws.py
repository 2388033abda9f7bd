"""Friction laws: the treatments of Coulomb's sgn(v_t) by name, and the readings of a contact's resistance.

Treatments, by name (``FRICTION_TREATMENTS``):

- ``exact``: set-valued Coulomb law with event-located stick/slip switching. The integrator's mode
  holds per contact a stick/slip entry and the frozen sliding direction
  (:class:`study.solver.friction.switching.StickSlipSwitching`).
- ``regularized``: sgn(v_t) replaced by a smooth approximation (``SIGN_FUNCTIONS``: tanh, sat,
  arctan, sqrt) of width eps; no stick, the contact creeps under sub-limit loads.
- ``sign``: 000's plain sgn(v_t) at every evaluation (meant for fixed-step RK4; it chatters at v_t = 0).

Each treatment is one class for both backends. Its phases law (the contacts' stick flags and slip factors s,
f = -s (R + mu_k |N|) in slip) is ``compiled_phases``, a compiled function of ``study.laws.friction`` (its one home)
that both paths call: it reads the numbers ``compiled_parameters()`` at its offset in the options
(``study.fast.frontend.pack_options``; ``FrictionDynamics.phases`` on the reference path). The slip factors of
'regularized' and 'sign' are ``study.kernels.signs`` functions.

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

from study.kernels.signs import SIGN_FUNCTIONS, SIGN_IDS
from study.laws.friction import mode_phases, slip_phases

Array = np.ndarray

# Readings of a contact's constant resistance R at rest -> the fraction of R in the static limit.
RESISTANCE_READINGS = {"holds": 1.0, "sliding_only": 0.0}

#: Default width eps [m/s] of a regularized friction sign (in-house 'regularized' and 'sign', whose
#: apparent-stick band it also sets, and the Exudyn models' tanh(v/eps)). 1 mm/s is below 1 % of the
#: sliding speeds of the study's cases (slider-crank ~0.2-0.3 m/s, ram up to ~6 m/s), so the
#: regularized force equals the Coulomb force (tanh >= 0.99) except within ~2.6 mm/s of a stop.
DEFAULT_EPS = 1e-3


class SlipFactor:
    """A treatment without a true stick: the slip factor is ``SIGN_FUNCTIONS[sgn](v_t, eps)`` at every
    evaluation, and ``stick_<contact>`` is reported as 1 inside the band |v_t| <= eps (apparent stick)."""

    sgn: str
    eps: float

    compiled_phases = staticmethod(slip_phases)

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

    compiled_phases = staticmethod(mode_phases)

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
