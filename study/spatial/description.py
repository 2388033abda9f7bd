"""Joint-level description of a spatial mechanism: rigid bodies in 3D, their joints and loads.

Every body has the redundant coordinates of the seeds (Nikravesh; Haug): its centre of mass r = (x, y, z) in the
global frame and its orientation by four Euler parameters p = (e0, e1, e2, e3), held on p^T p = 1 by one more
constraint row per body (:mod:`study.spatial.derive`). Points and axes of a body are given in its body frame (origin
at the centre of mass); a ground point or axis is a global 3-tuple in place of a name.

Every value is checked where it enters: a body's mass must be finite and > 0, its inertia tensor (three principal
moments or a full 3 x 3 matrix) symmetric positive definite and physical (each principal moment at most the sum of
the other two), a point or axis a real 3-vector, an axis not zero. A wrong value raises one
:class:`~study.spatial.elements.SpatialDescriptionError` naming it, its owner and what is wrong. A planar description
(:class:`study.model.joints.Description`) is a different type: nothing here takes one (:func:`spatial_only`).
"""

from __future__ import annotations

import dataclasses
import hashlib
from typing import Any, Mapping, Sequence

import numpy as np
import sympy as sp

from study.reference_data import tolerance
from study.spatial.elements import (GROUND, Cylindrical, Distance, FixedJoint, JointFriction, PointLoad, Prismatic,
                                    Revolute, RigidBody, SpatialDescriptionError, Spherical, TorqueLoad, Universal)

FRAMES = ("global", "body")


def real_vector(value: Any, length: int, what: str) -> np.ndarray:
    """``value`` as a finite real vector of ``length`` entries, or a SpatialDescriptionError naming ``what``."""
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise SpatialDescriptionError(f"{what} = {value!r} is not a vector of {length} real numbers") from None
    if array.shape != (length,):
        shape = "a number" if array.ndim == 0 else f"{array.size} entries"
        raise SpatialDescriptionError(f"{what} = {value!r} has {shape}; a spatial {what.split()[0]} needs {length}"
                                      + (" (a planar value?)" if array.shape == (length - 1,) else ""))
    if not np.isfinite(array).all():
        raise SpatialDescriptionError(f"{what} = {value!r} is not finite")
    return array


def unit_axis(value: Any, what: str) -> np.ndarray:
    """A nonzero 3-vector, normalized; a zero axis is refused (it has no direction)."""
    axis = real_vector(value, 3, what)
    norm = float(np.linalg.norm(axis))
    if norm <= tolerance("spatial_zero_axis"):
        raise SpatialDescriptionError(f"{what} = {value!r} is a zero vector (|axis| = {norm:.3g}): an axis needs a "
                                      f"direction")
    return axis / norm


def inertia_tensor(value: Any, what: str) -> np.ndarray:
    """Three principal moments or a full 3 x 3 tensor -> a symmetric positive-definite, physical 3 x 3 matrix."""
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise SpatialDescriptionError(f"{what} = {value!r} is not real numbers") from None
    if array.shape == (3,):
        array = np.diag(array)
    if array.shape != (3, 3) or not np.isfinite(array).all():
        raise SpatialDescriptionError(f"{what} = {value!r} must be 3 principal moments or a finite 3 x 3 tensor"
                                      + (" (a planar body's scalar inertia?)" if array.ndim == 0 else ""))
    scale = float(np.max(np.abs(array)))
    if np.max(np.abs(array - array.T)) > tolerance("round_off") * scale:
        raise SpatialDescriptionError(f"{what} = {array.tolist()} is not symmetric")
    moments = np.linalg.eigvalsh(array)
    if not moments.min() > 0:
        raise SpatialDescriptionError(f"{what} = {array.tolist()} is not positive definite: principal moments "
                                      f"{moments.tolist()} (each must be > 0)")
    if moments[2] > (moments[0] + moments[1]) * (1 + tolerance("round_off")):
        raise SpatialDescriptionError(f"{what} = {array.tolist()} is not a rigid body's: its largest principal "
                                      f"moment {moments[2]:.6g} exceeds the sum of the other two {moments[:2].tolist()}")
    return array


def load_components(value: Any, t: sp.Symbol, what: str) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """Three sympy expressions of time ``t`` only (numbers included)."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 3:
        raise SpatialDescriptionError(f"{what} = {value!r} must be 3 components (numbers or expressions of t)")
    exprs = tuple(sp.sympify(v) for v in value)
    stray = sorted(str(s) for e in exprs for s in e.free_symbols if s != t)
    if stray:
        raise SpatialDescriptionError(f"{what} = {value!r} uses {stray}: a load here depends on time t only")
    return exprs


def spatial_only(d: Any) -> "SpatialDescription":
    """``d`` if it is a SpatialDescription; a planar description (or anything else) is refused, never converted."""
    if not isinstance(d, SpatialDescription):
        kind = type(d).__name__
        raise SpatialDescriptionError(f"{getattr(d, 'name', d)!r} is a {kind}, not a SpatialDescription: a planar "
                                      f"description runs through study.model, never silently as a spatial one")
    return d


class SpatialDescription:
    """Collect a spatial mechanism: bodies, joints and loads, each checked as it is added.

    Parameters
    ----------
    name : str
    label : str, optional
        A human-readable name for reports.
    """

    def __init__(self, name: str, label: str = ""):
        if not isinstance(name, str) or not name.isidentifier():
            raise SpatialDescriptionError(f"mechanism name {name!r} must be an identifier")
        self.name = name
        self.label = label or name
        self.t = sp.Symbol("t", real=True)
        self.bodies: dict[str, RigidBody] = {}
        self.joints: list[Spherical | Revolute | FixedJoint | Prismatic | Cylindrical | Universal | Distance] = []
        self.loads: list[PointLoad | TorqueLoad] = []
        self.frictions: dict[str, JointFriction] = {}
        self.gravity_vector = np.zeros(3)
        self.redundant = 0
        self.redundancy_reason = ""
        self._names: set[str] = set()

    def _claim(self, kind: str, name: str) -> None:
        if not isinstance(name, str) or not name.isidentifier() or name == GROUND:
            raise SpatialDescriptionError(f"{self.name}: {kind} name {name!r} must be an identifier other than "
                                          f"{GROUND!r}")
        if name in self._names:
            raise SpatialDescriptionError(f"{self.name}: the name {name!r} ({kind}) is used twice")
        self._names.add(name)

    def body(self, name: str, mass: float, inertia: Any, points: Mapping[str, Sequence[float]] | None = None,
             axes: Mapping[str, Sequence[float]] | None = None) -> RigidBody:
        """A rigid body; ``inertia`` at the centre of mass in the body frame (3 principal moments or 3 x 3)."""
        self._claim("body", name)
        m = real_vector([mass], 1, f"mass of body {name!r}")[0]
        if not m > 0:
            raise SpatialDescriptionError(f"mass of body {name!r} = {mass!r} must be > 0")
        body = RigidBody(name=name, mass=float(m), inertia=inertia_tensor(inertia, f"inertia of body {name!r}"),
                         points={k: tuple(real_vector(v, 3, f"point {k!r} of body {name!r}"))
                                 for k, v in (points or {}).items()},
                         axes={k: tuple(unit_axis(v, f"axis {k!r} of body {name!r}")) for k, v in (axes or {}).items()})
        self.bodies[name] = body
        return body

    def _point(self, joint: str, body: str, point: Any) -> str | tuple:
        if body == GROUND:
            return tuple(real_vector(point, 3, f"ground point of joint {joint!r}"))
        if body not in self.bodies:
            raise SpatialDescriptionError(f"joint {joint!r}: no body {body!r} (bodies: {sorted(self.bodies)})")
        if point not in self.bodies[body].points:
            raise SpatialDescriptionError(f"joint {joint!r}: body {body!r} has no point {point!r} (points: "
                                          f"{sorted(self.bodies[body].points)})")
        return point

    def _axis(self, joint: str, body: str, axis: Any) -> str | tuple:
        if body == GROUND:
            return tuple(unit_axis(axis, f"ground axis of joint {joint!r}"))
        if axis not in self.bodies[body].axes:
            raise SpatialDescriptionError(f"joint {joint!r}: body {body!r} has no axis {axis!r} (axes: "
                                          f"{sorted(self.bodies[body].axes)})")
        return axis

    def _pair(self, name: str, a: tuple[str, Any], b: tuple[str, Any]) -> tuple:
        self._claim("joint", name)
        if a[0] == b[0]:
            raise SpatialDescriptionError(f"joint {name!r} joins {a[0]!r} to itself")
        return a[0], self._point(name, *a), b[0], self._point(name, *b)

    def spherical(self, name: str, a: tuple[str, Any], b: tuple[str, Any]) -> None:
        """Point a[1] of body a[0] coincides with point b[1] of body b[0] (either body may be GROUND)."""
        self.joints.append(Spherical(name, *self._pair(name, a, b)))

    def _axial(self, name: str, a: tuple, b: tuple) -> tuple:
        """(body_a, point a, axis a, body_b, point b, axis b) of two (body, point, axis) triples."""
        body_a, pa, body_b, pb = self._pair(name, a[:2], b[:2])
        return body_a, pa, self._axis(name, body_a, a[2]), body_b, pb, self._axis(name, body_b, b[2])

    def revolute(self, name: str, a: tuple[str, Any, Any], b: tuple[str, Any, Any]) -> None:
        """A spherical joint at (body, point) a and b whose axes a[2] and b[2] stay parallel."""
        self.joints.append(Revolute(name, *self._axial(name, a, b)))

    def cylindrical(self, name: str, a: tuple[str, Any, Any], b: tuple[str, Any, Any]) -> None:
        """Point a[1] stays on the line through b[1] along b[2], and axis a[2] parallel to b[2]."""
        self.joints.append(Cylindrical(name, *self._axial(name, a, b)))

    def universal(self, name: str, a: tuple[str, Any, Any], b: tuple[str, Any, Any]) -> None:
        """A spherical joint at (body, point) a and b whose axes a[2] and b[2] stay perpendicular (they must be
        perpendicular in the initial state, :func:`study.spatial.initial.initial_state`)."""
        self.joints.append(Universal(name, *self._axial(name, a, b)))

    def _rotation(self, name: str, orientation: Any) -> np.ndarray:
        c = np.eye(3) if orientation is None else np.array(orientation, dtype=float)
        if c.shape != (3, 3) or not np.isfinite(c).all() or \
                np.max(np.abs(c.T @ c - np.eye(3))) > tolerance("spatial_rotation_orthogonality") or \
                np.linalg.det(c) <= 0:
            raise SpatialDescriptionError(f"orientation of joint {name!r} = {orientation!r} is not a rotation matrix")
        return c

    def fixed(self, name: str, a: tuple[str, Any], b: tuple[str, Any], orientation: Any = None) -> None:
        """Weld a's body to b's (or to ground): the points coincide, the relative rotation stays ``orientation``."""
        pair = self._pair(name, a, b)
        self.joints.append(FixedJoint(name, *pair, orientation=self._rotation(name, orientation)))

    def prismatic(self, name: str, a: tuple[str, Any], b: tuple[str, Any, Any], orientation: Any = None) -> None:
        """Point a[1] of body a[0] slides along axis b[2] of body b[0] through b[1]; the relative rotation stays
        ``orientation`` (C: A_a = A_b C; the identity by default)."""
        body_a, pa, body_b, pb = self._pair(name, a, b[:2])
        self.joints.append(Prismatic(name, body_a, pa, body_b, pb, self._axis(name, body_b, b[2]),
                                     self._rotation(name, orientation)))

    def distance(self, name: str, a: tuple[str, Any], b: tuple[str, Any], length: float) -> None:
        """Point a[1] of body a[0] stays at ``length`` (> 0) from point b[1] of body b[0]."""
        pair = self._pair(name, a, b)
        value = real_vector([length], 1, f"length of joint {name!r}")[0]
        if not value > 0:
            raise SpatialDescriptionError(f"length of joint {name!r} = {length!r} must be > 0 (a zero distance is a "
                                          f"spherical joint, whose row |d| - 0 has no gradient)")
        self.joints.append(Distance(name, *pair, length=float(value)))

    def friction(self, joint: str, mu_static: float, mu_kinetic: float, resistance: float = 0.0,
                 radius: float | None = None) -> None:
        """Coulomb friction in the revolute or prismatic joint ``joint`` (declared before): the law is
        :class:`~study.spatial.elements.JointFriction`'s. A revolute needs its pin ``radius`` [m] (> 0), a prismatic
        joint has none; 0 <= mu_kinetic <= mu_static, resistance >= 0."""
        kinds = {j.name: j for j in self.joints}
        if joint not in kinds:
            raise SpatialDescriptionError(f"{self.name}: friction in joint {joint!r}: no such joint (joints: "
                                          f"{sorted(kinds)})")
        if type(kinds[joint]) not in (Revolute, Prismatic):
            raise SpatialDescriptionError(f"{self.name}: friction in joint {joint!r}: a {type(kinds[joint]).__name__} "
                                          f"joint has no friction law here (only revolute and prismatic joints)")
        if joint in self.frictions:
            raise SpatialDescriptionError(f"{self.name}: friction in joint {joint!r} is given twice")
        values = {key: real_vector([value], 1, f"{key} of the friction in joint {joint!r}")[0]
                  for key, value in (("mu_static", mu_static), ("mu_kinetic", mu_kinetic),
                                     ("resistance", resistance))}
        if not 0 <= values["mu_kinetic"] <= values["mu_static"] or values["resistance"] < 0:
            raise SpatialDescriptionError(f"{self.name}: friction in joint {joint!r}: needs 0 <= mu_kinetic "
                                          f"({mu_kinetic!r}) <= mu_static ({mu_static!r}) and resistance "
                                          f"({resistance!r}) >= 0")
        revolute = isinstance(kinds[joint], Revolute)
        if revolute != (radius is not None):
            raise SpatialDescriptionError(f"{self.name}: friction in joint {joint!r}: radius = {radius!r}: "
                                          + ("a revolute joint needs its pin radius [m]" if revolute else
                                             "a prismatic joint's friction has no radius (its normal force is N)"))
        if revolute:
            radius = real_vector([radius], 1, f"radius of the friction in joint {joint!r}")[0]
            if not radius > 0:
                raise SpatialDescriptionError(f"{self.name}: friction in joint {joint!r}: radius = {radius!r} must "
                                              f"be > 0")
            radius = float(radius)
        self.frictions[joint] = JointFriction(joint, *(float(v) for v in values.values()), radius=radius)

    def redundant_rows(self, count: int, reason: str) -> None:
        """Declare ``count`` joint rows dependent at every configuration (Bricard's linkage: 1; ``reason`` says why):
        rank(Phi_q) = r - count, checked at the initial state (:func:`study.spatial.initial.initial_state`)."""
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise SpatialDescriptionError(f"{self.name}: redundant_rows count = {count!r} must be an integer >= 1")
        if not isinstance(reason, str) or not reason.strip():
            raise SpatialDescriptionError(f"{self.name}: redundant_rows needs its reason (why the rows are dependent "
                                          f"everywhere), got {reason!r}")
        self.redundant, self.redundancy_reason = count, reason

    def gravity(self, g: Sequence[float]) -> None:
        """Uniform gravity, the global acceleration vector g (a potential m g . r per body)."""
        self.gravity_vector = real_vector(g, 3, "gravity vector")

    def force(self, name: str, body: str, point: str, components: Sequence) -> None:
        """A force (global components, numbers or expressions of ``self.t``) at a point of a body."""
        self._claim("load", name)
        self._point(name, body, point)
        self.loads.append(PointLoad(name, body, point, load_components(components, self.t, f"force {name!r}")))

    def torque(self, name: str, body: str, components: Sequence, frame: str = "global") -> None:
        """A torque on a body, its components in the 'global' or the 'body' frame."""
        self._claim("load", name)
        if body not in self.bodies:
            raise SpatialDescriptionError(f"torque {name!r}: no body {body!r} (bodies: {sorted(self.bodies)})")
        if frame not in FRAMES:
            raise SpatialDescriptionError(f"torque {name!r}: frame = {frame!r} must be one of {FRAMES}")
        self.loads.append(TorqueLoad(name, body, load_components(components, self.t, f"torque {name!r}"), frame))

    def fingerprint(self, redundancy: bool = True) -> str:
        """SHA-256 (16 hex) of the description's content: its bodies, joints, loads, gravity and (unless
        ``redundancy`` is False: what the equations are derived from) declared redundant rows, every number at full
        precision (``repr``) and every law as sympy prints it."""
        def plain(value):
            if isinstance(value, np.ndarray):
                return [plain(v) for v in value.tolist()]
            if isinstance(value, (list, tuple)):
                return [plain(v) for v in value]
            if isinstance(value, Mapping):
                return {k: plain(v) for k, v in sorted(value.items())}
            return repr(value) if isinstance(value, float) else str(value)

        parts = [("body", plain(dataclasses.asdict(b))) for b in self.bodies.values()]
        parts += [(type(e).__name__, plain(dataclasses.asdict(e))) for e in (*self.joints, *self.loads)]
        parts += [("gravity", plain(self.gravity_vector))]
        parts += [("redundant", self.redundant, self.redundancy_reason)] if redundancy else []
        parts += [("friction", plain(dataclasses.asdict(f))) for f in self.frictions.values()]
        return hashlib.sha256(repr((self.name, parts)).encode()).hexdigest()[:16]
