"""Mechanism A: slider-crank with Coulomb friction in the slider guide (paper 000, sec. 3).

Coordinates q = [q1, q2]: crank angle, rod angle relative to the crank (rod absolute angle q1+q2).
A = l1 (cos q1, sin q1); C2 = A - c2 e(q1+q2); B = A - l2 e(q1+q2), e(a) = (cos a, sin a).
The slider guide is the line y = 0: its normal gap y_B is the constraint (000 eq. 22), so its
multiplier is the normal force. The resistance F and the Coulomb friction act through that contact.
"""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from study.model import EquationsOfMotion, MechanismBuilder
from study.model.builder import constant_torque
from study.params import ParameterSet

COORDINATES = ("q1", "q2")


def _damper(alpha: float):
    def law(t, angle, rate):
        return -alpha * rate
    return law


def describe(ps: ParameterSet) -> MechanismBuilder:
    """The body-level description of the slider-crank for one parameter set."""
    v = ps.values
    numeric = {k: getattr(v, k) for k in ("J1", "m1", "J2", "m2", "m3", "J3", "l1", "l2", "c2", "g", "mu", "F",
                                           "alpha")}
    b = MechanismBuilder("slider_crank", COORDINATES, numeric)
    p = b.p
    q1, q2 = b.q
    ax, ay = p.l1 * sp.cos(q1), p.l1 * sp.sin(q1)
    rod = q1 + q2
    crank = b.body("crank", 0, 0, q1, p.m1, p.J1)
    b.body("rod", ax - p.c2 * sp.cos(rod), ay - p.c2 * sp.sin(rod), rod, p.m2, p.J2)
    b.body("slider", ax - p.l2 * sp.cos(rod), ay - p.l2 * sp.sin(rod), 0, p.m3, p.J3)
    b.point("A", ax, ay)
    slider_point = b.point("B", ax - p.l2 * sp.cos(rod), ay - p.l2 * sp.sin(rod))
    b.gravity(p.g)
    b.sliding_contact("guide", slider_point, normal=(0, 1), offset=0, tangent=(1, 0),
                      mu_static=p.mu, mu_kinetic=p.mu, resistance=p.F)
    b.torque("drive", crank, constant_torque(v.M))
    if v.alpha_law == "spring":
        b.potential("alpha_spring", p.alpha * q1 ** 2 / 2)
    else:
        b.torque("alpha_damper", crank, _damper(v.alpha))
    return b


def equations(ps: ParameterSet) -> EquationsOfMotion:
    return describe(ps).compile(ps.sha256)


def on_branch(ps: ParameterSet, q: np.ndarray) -> bool:
    """The assembly branch implied by 000 eqs. (13), (32): cos(q1+q2) > 0 (B beyond A from O)."""
    return math.cos(q[0] + q[1]) > 0
