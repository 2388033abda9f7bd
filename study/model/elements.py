"""The parts of a planar mechanism's description, as data: bodies, pin and contact friction, joints, load inputs,
loads and potentials (:mod:`study.model.joints` states their conventions; its
:class:`~study.model.joints.Description` makes them)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import sympy as sp

Expr = sp.Expr
GROUND = "ground"


class DescriptionError(ValueError):
    """The mechanism description is inconsistent; the message lists every problem."""


@dataclass(frozen=True)
class Body:
    """A rigid body: mass, centroidal inertia, named local points (COM frame), angle in q."""

    name: str
    mass: Expr
    inertia: Expr
    points: Mapping[str, tuple[Expr, Expr]]
    angle: Expr
    position: tuple[Expr, Expr] | None = None   # a free body's centre of mass in q (relative coordinates)


@dataclass(frozen=True)
class Friction:
    """Coulomb contact data of a prismatic joint: mu_s, mu_k and a constant resistance F [N].

    On a revolute joint (``revolute(..., friction=Friction(mu_s, mu_k), radius=r)``) the same data is pin friction:
    mu_kinetic is the sliding pin's coefficient, mu_static bounds the torque that holds it at rest (the exact
    treatment), ``resistance`` a constant friction torque T0 [N m]."""

    mu_static: Expr
    mu_kinetic: Expr
    resistance: Expr = sp.Integer(0)


@dataclass(frozen=True)
class Revolute:
    """``friction`` with ``radius`` (the pin's radius r [m]): Coulomb pin friction, a torque
    tau = -(mu_k r |R|_delta + T0) s(omega_rel) on body a and -tau on body b, R the joint's reaction (the multipliers
    of its two rows), omega_rel = theta_a' - theta_b'. Such a joint is always a cut joint (its reaction is its rows'
    multipliers; ``cut=False`` with friction is refused)."""

    name: str
    a: tuple[str, str]
    b: tuple[str, str]
    cut: bool | None = None
    friction: Friction | None = None
    radius: Expr | None = None


@dataclass(frozen=True)
class Distance:
    """Point a[1] of body a[0] stays at ``length`` from point b[1] of body b[0] (a massless rod with a pin at each
    end). Always a constraint row, ``<name> = |r_a - r_b| - length``: its multiplier is the rod's force along the
    line, a tension where it pulls the points together."""

    name: str
    a: tuple[str, str]
    b: tuple[str, str]
    length: Expr


@dataclass(frozen=True)
class Prismatic:
    """``travel``: the slider point's position along ``axis`` from the guide point, as an expression of q. With
    it the joint can place a body in relative coordinates (a tree joint); without it, it is a loop closure."""

    name: str
    slider: tuple[str, str]
    guide: tuple[str, str]
    axis: tuple[Expr, Expr]
    normal: tuple[Expr, Expr]
    angle_offset: Expr = sp.Integer(0)
    friction: Friction | None = None
    travel: Expr | None = None


@dataclass(frozen=True)
class Input:
    """A named input of the load laws: ``kind`` in x, y, vx, vy (a point), angle, rate (a body)."""

    kind: str
    body: str
    point: str | None = None


@dataclass(frozen=True)
class Load:
    """A force (fx, fy, global frame) at a body point, or a torque (``point`` None, ``components`` (tau,))."""

    name: str
    body: str
    point: str | None
    components: tuple[Expr, ...]


@dataclass(frozen=True)
class Potential:
    """A conservative load given by its potential energy in the inputs (springs)."""

    name: str
    energy: Expr
