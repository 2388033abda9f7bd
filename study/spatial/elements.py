"""The parts of a spatial mechanism's description, as data: rigid bodies, joints, loads, and the error bad input
gets (:class:`~study.spatial.description.SpatialDescription` makes them and checks every number on the way in)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
import sympy as sp

from study.model.elements import GROUND, DescriptionError

__all__ = ["GROUND", "AxisPair", "Cylindrical", "Distance", "FixedJoint", "JointFriction", "PointLoad", "Prismatic",
           "Revolute", "RigidBody", "SpatialDescriptionError", "Spherical", "TorqueLoad", "Universal"]

Vector = tuple[float, float, float]


class SpatialDescriptionError(DescriptionError):
    """A spatial description (or its initial state) is wrong: the message names the value, its owner and why."""


@dataclass(frozen=True)
class RigidBody:
    """A rigid body: mass, the inertia tensor at its centre of mass in its body frame (3 x 3, symmetric positive
    definite), named local points and unit axes (body frame, origin at the centre of mass)."""

    name: str
    mass: float
    inertia: np.ndarray
    points: Mapping[str, Vector] = field(default_factory=dict)
    axes: Mapping[str, Vector] = field(default_factory=dict)


@dataclass(frozen=True)
class Spherical:
    """Point ``a`` of body ``body_a`` coincides with point ``b`` of ``body_b`` (3 rows). A ground point is its
    global coordinates (a 3-tuple) in place of a point name."""

    name: str
    body_a: str
    a: str | Vector
    body_b: str
    b: str | Vector


@dataclass(frozen=True)
class AxisPair:
    """A joint between point ``a`` of body_a and point ``b`` of body_b with an axis on each: ``axis_a`` of body_a,
    ``axis_b`` of body_b (each an axis name, or a global unit 3-tuple on ground)."""

    name: str
    body_a: str
    a: str | Vector
    axis_a: str | Vector
    body_b: str
    b: str | Vector
    axis_b: str | Vector


class Revolute(AxisPair):
    """A spherical joint (3 rows) whose two axes stay parallel (2 rows)."""


@dataclass(frozen=True)
class FixedJoint:
    """A spherical joint (3 rows) with the relative rotation locked (3 rows): body_a's frame stays at
    A_b C, C = ``orientation`` (3 x 3, body_b's frame -> body_a's frame at rest; the identity by default)."""

    name: str
    body_a: str
    a: str | Vector
    body_b: str
    b: str | Vector
    orientation: np.ndarray


@dataclass(frozen=True)
class Prismatic:
    """Point ``a`` of body_a slides along ``axis_b`` of body_b through point ``b`` (2 rows) with the relative rotation
    locked (3 rows) at A_a = A_b C, C = ``orientation`` (as for :class:`FixedJoint`)."""

    name: str
    body_a: str
    a: str | Vector
    body_b: str
    b: str | Vector
    axis_b: str | Vector
    orientation: np.ndarray


class Cylindrical(AxisPair):
    """Point ``a`` of body_a stays on the line through point ``b`` along ``axis_b`` of body_b (2 rows) and ``axis_a``
    stays parallel to ``axis_b`` (2 rows): sliding along and turning about the common axis are free."""


class Universal(AxisPair):
    """A spherical joint (3 rows) whose two axes (``axis_a`` of body_a, ``axis_b`` of body_b) stay perpendicular
    (1 row): the cross of a Cardan joint."""


@dataclass(frozen=True)
class Distance:
    """Point ``a`` of body_a stays at ``length`` (> 0) from point ``b`` of body_b (1 row): a massless rod with
    spherical ends."""

    name: str
    body_a: str
    a: str | Vector
    body_b: str
    b: str | Vector
    length: float


@dataclass(frozen=True)
class JointFriction:
    """Coulomb friction in the spatial joint ``joint`` (a revolute or a prismatic joint).

    * revolute: a torque about the axis, tau = -(mu_kinetic radius |R_t|_delta + resistance) s(omega_rel) on body a
      and -tau on body b; R_t is the joint's transverse reaction (the force component perpendicular to its axis),
      omega_rel the relative angular velocity about the axis, ``radius`` [m] the pin's radius;
    * prismatic: a force along the axis, f = -(mu_kinetic |N|_delta + resistance) s(v_rel) on point a and -f on
      body b; N is the normal reaction, the 2-vector of the joint's two transverse rows (``_tx``, ``_ty``), v_rel the
      velocity of point a relative to body b along the axis; ``radius`` is None (the rotation lock's reaction
      moments add no friction).

    At rest the joint holds up to the same level with ``mu_static`` (the exact treatment). |.|_delta is the smooth
    norm of the planar pins (``pin_friction_norm_width`` in reference/tolerances.toml); ``resistance`` a constant
    torque [N m] (revolute) or force [N] (prismatic)."""

    joint: str
    mu_static: float
    mu_kinetic: float
    resistance: float = 0.0
    radius: float | None = None


@dataclass(frozen=True)
class PointLoad:
    """A force (global components, sympy expressions of time t) at point ``point`` of ``body``."""

    name: str
    body: str
    point: str
    components: tuple[sp.Expr, sp.Expr, sp.Expr]


@dataclass(frozen=True)
class TorqueLoad:
    """A torque on ``body`` (components of time t) in the ``frame`` 'global' or 'body'."""

    name: str
    body: str
    components: tuple[sp.Expr, sp.Expr, sp.Expr]
    frame: str
