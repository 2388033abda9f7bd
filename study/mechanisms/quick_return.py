"""Mechanism B: the quick-return (shaper) mechanism of paper 001, sec. 4 (Haug's shaper).

Coordinates q = [q1, q2, q3]: crank, rocker and connecting-rod angles (absolute).
Rocker pivot at the origin; crank pivot O = (0, h1); A = O + l1 e(q1); E = l2 e(q2);
D = E + l3 e(q3); the ram slides along y = h2. Body 4 (block) sits at A and turns with the rocker.
Constraints: A lies on the rocker line (001 f1, the normal gap of A), D on the ram guide (001 f2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import sympy as sp

from study.model import EquationsOfMotion, MechanismBuilder
from study.model.builder import constant_torque
from study.params import ParameterSet

COORDINATES = ("q1", "q2", "q3")


@dataclass(frozen=True)
class CuttingLaw:
    """Cutting force on the ram along x (001 sec. 4, after Haug [11]).

    ``on_off``: F_x = F_cut while v_D < 0 and x_min <= x_D <= x_max, else 0. It switches, so it
    exposes the indicators (v_D, x_D - x_min, x_max - x_D); with a frozen ``mode`` (their signs)
    the force is constant between switches.
    ``smooth``: F_cut * s(-v_D/v_ramp) * s((x_D - x_min)/x_ramp) * s((x_max - x_D)/x_ramp),
    s(u) = (1 + tanh u)/2.
    """

    F_cut: float
    x_min: float
    x_max: float
    law: str
    v_ramp: float
    x_ramp: float

    def __call__(self, t: float, r: np.ndarray, v: np.ndarray, mode=None) -> tuple[float, float]:
        x, vx = r[0], v[0]
        if self.law == "smooth":
            s = 0.5 * (1 + math.tanh(-vx / self.v_ramp))
            s *= 0.5 * (1 + math.tanh((x - self.x_min) / self.x_ramp))
            s *= 0.5 * (1 + math.tanh((self.x_max - x) / self.x_ramp))
            return (self.F_cut * s, 0.0)
        if mode is None:
            on = vx < 0 and self.x_min <= x <= self.x_max
        else:
            on = mode[0] < 0 and mode[1] > 0 and mode[2] > 0
        return (self.F_cut if on else 0.0, 0.0)

    def indicators(self, t: float, r: np.ndarray, v: np.ndarray) -> tuple[float, float, float]:
        return (v[0], r[0] - self.x_min, self.x_max - r[0])


def cutting_law(ps: ParameterSet) -> CuttingLaw:
    v = ps.values
    return CuttingLaw(v.F_cut, v.x_cut_min, v.x_cut_max, v.cutting_law, v.v_ramp, v.x_ramp)


def describe(ps: ParameterSet) -> MechanismBuilder:
    """The body-level description of the quick-return mechanism for one parameter set."""
    v = ps.values
    names = ("l1", "l2", "l3", "m1", "m2", "m3", "m4", "m5", "a1", "a2", "a3", "J1", "J2", "J3", "J4", "J5",
             "h1", "h2", "g", "mu_guide")
    b = MechanismBuilder("quick_return", COORDINATES, {k: getattr(v, k) for k in names})
    p = b.p
    q1, q2, q3 = b.q
    a = (p.l1 * sp.cos(q1), p.h1 + p.l1 * sp.sin(q1))
    e = (p.l2 * sp.cos(q2), p.l2 * sp.sin(q2))
    d = (e[0] + p.l3 * sp.cos(q3), e[1] + p.l3 * sp.sin(q3))
    crank = b.body("crank", p.a1 * sp.cos(q1), p.h1 + p.a1 * sp.sin(q1), q1, p.m1, p.J1)
    b.body("rocker", p.a2 * sp.cos(q2), p.a2 * sp.sin(q2), q2, p.m2, p.J2)
    b.body("rod", e[0] + p.a3 * sp.cos(q3), e[1] + p.a3 * sp.sin(q3), q3, p.m3, p.J3)
    b.body("block", a[0], a[1], q2, p.m4, p.J4)
    b.body("ram", d[0], d[1], 0, p.m5, p.J5)
    b.point("A", *a)
    b.point("E", *e)
    ram_point = b.point("D", *d)
    b.gravity(p.g)
    # A on the rocker line: normal gap of A, n = (-sin q2, cos q2); equals 001's f1.
    b.constraint("block_on_rocker", -sp.sin(q2) * a[0] + sp.cos(q2) * a[1])
    # D on the ram guide y = h2, written as 001's f2 = h2 - y_D (normal (0, -1)).
    b.sliding_contact("ram_guide", ram_point, normal=(0, -1), offset=-p.h2, tangent=(1, 0),
                      mu_static=p.mu_guide, mu_kinetic=p.mu_guide)
    b.torque("drive", crank, constant_torque(v.M))
    law = cutting_law(ps)
    if v.cutting_law == "on_off":
        b.force("cutting", ram_point, law, law.indicators, ("v_D", "x_D-x_min", "x_max-x_D"))
    else:
        b.force("cutting", ram_point, law)
    return b


def equations(ps: ParameterSet) -> EquationsOfMotion:
    return describe(ps).compile(ps.sha256)


def on_branch(ps: ParameterSet, q: np.ndarray) -> bool:
    """The paper's configuration: crank pivot above the rocker pivot, rocker pointing up (sin q2 > 0)."""
    return math.sin(q[1]) > 0
