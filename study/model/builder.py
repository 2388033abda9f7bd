"""Body-level description of a planar mechanism.

A description lists coordinates, rigid bodies (centre-of-mass position and angle as sympy
expressions of q, with mass and centroidal inertia), named points, holonomic constraints,
gravity, springs (potentials), applied loads and sliding contacts. Parameters are sympy symbols,
so one derivation serves every variant; numbers are bound when the description is compiled.

Example
-------
>>> b = MechanismBuilder("pendulum", ["x", "y"], {"L": 1.0, "m": 2.0, "g": 9.81})
>>> x, y = b.q
>>> bob = b.body("bob", x, y, 0, mass=b.p.m, inertia=b.p.m * 0)   # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, Mapping, Sequence

import sympy as sp

from study.model.joints import DescriptionError

Expr = sp.Expr


@dataclass(frozen=True)
class Body:
    name: str
    x: Expr
    y: Expr
    angle: Expr
    mass: Expr
    inertia: Expr


@dataclass(frozen=True)
class Point:
    name: str
    x: Expr
    y: Expr


@dataclass(frozen=True)
class PointLoad:
    """A force (fx, fy; global frame) at a point, as expressions of t, q, qd, parameters and modes."""

    name: str
    point: Point
    components: tuple[Expr, Expr]


@dataclass(frozen=True)
class TorqueLoad:
    """A torque on a body (counter-clockwise positive), an expression of t, q, qd, parameters and modes."""

    name: str
    body: Body
    torque: Expr


@dataclass(frozen=True)
class Contact:
    """A sliding contact: the point's normal gap n.r - offset = 0 is a constraint row.

    ``guide`` None: the guide is fixed in ground (normal, tangent and offset constants) and the sliding velocity is
    v_t = t . v_point. Else the guide is that body: normal, tangent and offset are expressions of q (they turn and
    move with it) and v_t = t . (v_point - v_G*), v_G* the velocity of the guide's material point that coincides
    with the contact point, so the generalized friction force J_t^T f (J_t = dv_t/dqd) is the force f t on the
    point's body and -f t on the guide at the same place: equal and opposite, its power f v_t.
    """

    name: str
    point: Point
    normal: tuple[Expr, Expr]
    tangent: tuple[Expr, Expr]
    mu_static: Expr
    mu_kinetic: Expr
    resistance: Expr
    guide: Body | None = None


@dataclass(frozen=True)
class SymbolicPinFriction:
    """Coulomb friction of a revolute cut joint whose rows are ``rows`` (x, y: their multipliers are its reaction
    R): a torque tau = -(mu_kinetic r |R|_delta + torque) s(omega_rel) on ``body_a`` and -tau on ``body_b`` (None:
    ground), omega_rel = theta_a' - theta_b'; at rest it holds up to mu_static r |R|_delta + torque."""

    name: str
    rows: tuple[str, str]
    body_a: Body | None
    body_b: Body | None
    mu_static: Expr
    mu_kinetic: Expr
    radius: Expr
    torque: Expr


class MechanismBuilder:
    """Collect a planar mechanism's description (compiled by :func:`study.model.compile.compile_description`).

    Parameters
    ----------
    name : str
    coordinates : sequence of str
        Names of the m redundant coordinates; ``builder.q`` and ``builder.qd`` hold their symbols.
    parameters : mapping of str to float
        Numeric values; ``builder.p.<name>`` is the matching sympy symbol.
    """

    def __init__(self, name: str, coordinates: Sequence[str], parameters: Mapping[str, float]):
        if not coordinates:
            raise DescriptionError(f"mechanism {name!r}: at least one coordinate is needed")
        if len(set(coordinates)) != len(coordinates):
            raise DescriptionError(f"mechanism {name!r}: duplicate coordinate names in {list(coordinates)}")
        self.name = name
        self.coordinate_names = tuple(coordinates)
        self.q = sp.Matrix(sp.symbols([f"q_{c}" for c in coordinates], real=True))
        self.qd = sp.Matrix(sp.symbols([f"qd_{c}" for c in coordinates], real=True))
        self.values = dict(parameters)
        self.p = SimpleNamespace(**{k: sp.Symbol(f"p_{k}", real=True) for k in parameters})
        self.bodies: list[Body] = []
        self.points: list[Point] = []
        self.constraints: list[tuple[str, Expr]] = []
        self.potentials: list[tuple[str, Expr]] = []
        self.point_loads: list[PointLoad] = []
        self.torque_loads: list[TorqueLoad] = []
        self.contacts: list[Contact] = []
        self.pin_frictions: list[SymbolicPinFriction] = []
        self.gravity_g: Expr | None = None
        self.t = sp.Symbol("t", real=True)
        self.switches: list[tuple[str, Expr, sp.Symbol]] = []

    # --- description -------------------------------------------------------------------------
    def body(self, name: str, x: Any, y: Any, angle: Any, mass: Any, inertia: Any) -> Body:
        """A rigid body: centre of mass (x, y), angle, mass and centroidal inertia."""
        b = Body(name, *(sp.sympify(v) for v in (x, y, angle, mass, inertia)))
        self.bodies.append(b)
        return b

    def point(self, name: str, x: Any, y: Any) -> Point:
        """A named point (for loads, contacts and output)."""
        pt = Point(name, sp.sympify(x), sp.sympify(y))
        self.points.append(pt)
        return pt

    def constraint(self, name: str, expr: Any) -> None:
        """A holonomic constraint expr(q) = 0."""
        self.constraints.append((name, sp.sympify(expr)))

    def gravity(self, g: Any) -> None:
        """Uniform gravity of magnitude g along -y on every body."""
        self.gravity_g = sp.sympify(g)

    def potential(self, name: str, expr: Any) -> None:
        """A conservative load given by its potential energy (for example a spring)."""
        self.potentials.append((name, sp.sympify(expr)))

    def torque(self, name: str, body: Body, torque: Any) -> TorqueLoad:
        """A torque on a body: an expression of t, q, qd, parameters and mode symbols."""
        load = TorqueLoad(name, body, sp.sympify(torque))
        self.torque_loads.append(load)
        return load

    def force(self, name: str, point: Point, fx: Any, fy: Any) -> PointLoad:
        """A force (global frame) at a point: expressions of t, q, qd, parameters and mode symbols."""
        load = PointLoad(name, point, (sp.sympify(fx), sp.sympify(fy)))
        self.point_loads.append(load)
        return load

    def switch(self, name: str, expr: Any, mode: sp.Symbol | None = None) -> sp.Symbol:
        """A switching function of t, q, qd; returns its mode symbol (+1/-1, frozen between switches)."""
        mode = mode if mode is not None else sp.Symbol(f"mode_{len(self.switches)}", real=True)
        self.switches.append((name, sp.sympify(expr), mode))
        return mode

    def sliding_contact(self, name: str, point: Point, normal, offset, tangent,
                        mu_static: Any, mu_kinetic: Any, resistance: Any = 0, guide: Body | None = None) -> Contact:
        """A sliding joint: adds the constraint n.r_point - offset = 0 (n a unit vector).

        Its multiplier is then the normal force (N = -lambda along n), so Coulomb friction can use it. ``guide``: the
        body the point slides on (None: ground); then n, t and offset are expressions of q (the guide's rotated
        normal and axis, n . r of its guide point) and the sliding velocity is relative to the guide (see
        :class:`Contact`).
        """
        n = tuple(sp.sympify(v) for v in normal)
        t = tuple(sp.sympify(v) for v in tangent)
        row = n[0] * point.x + n[1] * point.y - sp.sympify(offset)
        self.constraint(name, row if guide is None else sp.expand(row))
        c = Contact(name, point, n, t, *(sp.sympify(v) for v in (mu_static, mu_kinetic, resistance)), guide=guide)
        self.contacts.append(c)
        return c

    def pin_friction(self, name: str, rows, body_a: Body | None, body_b: Body | None, mu_static: Any,
                     mu_kinetic: Any, radius: Any, torque: Any = 0) -> SymbolicPinFriction:
        """Coulomb friction of a revolute joint whose two constraint rows (already added) are ``rows``."""
        pin = SymbolicPinFriction(name, tuple(rows), body_a, body_b,
                          *(sp.sympify(v) for v in (mu_static, mu_kinetic, radius, torque)))
        self.pin_frictions.append(pin)
        return pin

    # --- checks -------------------------------------------------------------
    def validate(self) -> None:
        """Report every problem of the description in one DescriptionError."""
        problems = []
        m, r = len(self.q), len(self.constraints)
        if r >= m:
            problems.append(f"the number of constraints {r} must be smaller than the number of coordinates {m}")
        allowed = set(self.q) | set(vars(self.p).values())
        time_free = allowed
        names = [b.name for b in self.bodies] + [p.name for p in self.points] + [c[0] for c in self.constraints]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            problems.append(f"duplicate names: {dup}")
        for b in self.bodies:
            for key in ("x", "y", "angle", "mass", "inertia"):
                stray = getattr(b, key).free_symbols - time_free
                if stray:
                    problems.append(f"body {b.name!r}.{key} uses unknown symbols {sorted(map(str, stray))}")
            if b.mass.free_symbols & set(self.q) or b.inertia.free_symbols & set(self.q):
                problems.append(f"body {b.name!r}: mass and inertia must not depend on q")
        for name, e in self.constraints + self.potentials:
            stray = e.free_symbols - time_free
            if stray:
                problems.append(f"{name!r} uses unknown symbols {sorted(map(str, stray))}")
        dynamic = allowed | set(self.qd) | {self.t}
        modes = {m for _, _, m in self.switches}
        for name, e in [(ld.name, c) for ld in self.point_loads for c in ld.components] + \
                [(ld.name, ld.torque) for ld in self.torque_loads] + [(n, e) for n, e, _ in self.switches]:
            stray = e.free_symbols - dynamic - modes
            if stray:
                problems.append(f"{name!r} uses unknown symbols {sorted(map(str, stray))}")
        for c in self.contacts:
            norm = sp.simplify(c.normal[0] ** 2 + c.normal[1] ** 2)
            dot = sp.simplify(c.normal[0] * c.tangent[0] + c.normal[1] * c.tangent[1])
            if norm != 1 or dot != 0:
                problems.append(f"contact {c.name!r}: normal must be a unit vector orthogonal to the tangent")
            if c.guide is not None and c.guide not in self.bodies:
                problems.append(f"contact {c.name!r}: its guide {c.guide.name!r} is not a body of the mechanism")
        if not self.bodies:
            problems.append("no bodies")
        if problems:
            raise DescriptionError(f"mechanism {self.name!r}: " + "; ".join(problems))
