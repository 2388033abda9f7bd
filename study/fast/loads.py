"""Load laws of the fast path as numba functions, and their extraction from a mechanism description.

The reference laws are Python callables (``study.mechanisms.quick_return.CuttingLaw``, the torque
closures of ``study.model.builder``). The fast path needs them compiled, so the formulas of the
cutting law are written a second time here (:func:`cutting_smooth`, :func:`cutting_on_off`); the
agreement tests in ``tests/test_fast.py`` compare both at many states. Torque laws are not copied:
:func:`torque_coefficients` reads a law's constant and rate coefficient by calling it, and checks
at probe points that the law really is affine in the rate (constant drive torque, viscous damper).
Anything else is refused with a ValueError, never approximated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from study.mechanisms.quick_return import CuttingLaw
from study.model.builder import MechanismBuilder


@njit(cache=True)
def _ramp(u):
    return 0.5 * (1.0 + math.tanh(u))


@njit(cache=True)
def cutting_smooth(x, vx, F_cut, x_min, x_max, v_ramp, x_ramp):
    """Smooth cutting force along x: F_cut s(-v/v_ramp) s((x-x_min)/x_ramp) s((x_max-x)/x_ramp)."""
    s = _ramp(-vx / v_ramp)
    s *= _ramp((x - x_min) / x_ramp)
    s *= _ramp((x_max - x) / x_ramp)
    return F_cut * s


@njit(cache=True)
def cutting_on_off(mode_v, mode_lo, mode_hi, F_cut):
    """On/off cutting force along x in a frozen mode: on while v_D < 0 inside the window."""
    if mode_v < 0 and mode_lo > 0 and mode_hi > 0:
        return F_cut
    return 0.0


# Probe states (t, angle, rate) for the affine check: arbitrary, away from special values.
_PROBES = ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.37, 1.3, -2.9), (12.5, -4.1, 7.3), (3.1, 0.2, 1e-3))
# A torque law is accepted as affine if it matches c0 + c1 rate to round-off of its own size.
_AFFINE_RTOL = 1e-12


@dataclass(frozen=True)
class TorqueSpec:
    """tau = c0 + c1 * rate on body ``body`` (load ``name``)."""

    name: str
    body: str
    c0: float
    c1: float


@dataclass(frozen=True)
class PointSpec:
    """A compiled point load: ``kind`` in ('cutting_smooth', 'cutting_on_off'), its numbers."""

    name: str
    point: str
    kind: str
    values: tuple[float, ...]
    n_indicators: int


def torque_coefficients(name: str, law) -> tuple[float, float]:
    """(c0, c1) with law(t, angle, rate) = c0 + c1 rate, or ValueError if the law is not of that form."""
    c0 = float(law(*_PROBES[0]))
    c1 = float(law(*_PROBES[1])) - c0
    for t, angle, rate in _PROBES[2:]:
        got, want = float(law(t, angle, rate)), c0 + c1 * rate
        if not abs(got - want) <= _AFFINE_RTOL * max(abs(got), abs(c0), abs(c1 * rate), 1e-300):
            raise ValueError(f"backend='compiled': torque load {name!r} is not affine in the rate "
                             f"(at t={t}, angle={angle}, rate={rate} it gives {got!r}, c0 + c1 rate = {want!r}); "
                             f"the compiled path supports constant torques and viscous dampers only; "
                             f"use backend='reference'")
    return c0, c1


def point_spec(load) -> PointSpec:
    """The compiled form of a point load, or ValueError naming it."""
    law = load.law
    if isinstance(law, CuttingLaw):
        if law.law == "smooth":
            return PointSpec(load.name, load.point.name, "cutting_smooth",
                             (law.F_cut, law.x_min, law.x_max, law.v_ramp, law.x_ramp), 0)
        if law.law == "on_off":
            return PointSpec(load.name, load.point.name, "cutting_on_off", (law.F_cut, law.x_min, law.x_max), 3)
    raise ValueError(f"backend='compiled': point load {load.name!r} ({type(law).__name__}) has no compiled law; "
                     f"supported: the quick-return cutting law ('smooth', 'on_off'); use backend='reference'")


def load_specs(b: MechanismBuilder) -> tuple[tuple[TorqueSpec, ...], tuple[PointSpec, ...]]:
    """Compiled forms of every torque and point load of a description."""
    torques = tuple(TorqueSpec(t.name, t.body.name, *torque_coefficients(t.name, t.law)) for t in b.torque_loads)
    points = tuple(point_spec(pl) for pl in b.point_loads)
    return torques, points


def load_vector(torques, points) -> np.ndarray:
    """The numeric load parameters ``lp`` in the order the generated code reads them."""
    values: list[float] = []
    for t in torques:
        values += [t.c0, t.c1]
    for pt in points:
        values += list(pt.values)
    return np.asarray(values, dtype=float)
