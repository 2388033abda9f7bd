"""Joint-level description of a planar mechanism: bodies with local points, joints, loads as data.

One description per mechanism is the single source from which every engine's model is generated:

* the in-house equations in the coordinates the description chooses (relative joint coordinates,
  with loop-closure constraints) and in absolute coordinates (x, y, theta per body, one constraint
  block per joint): :func:`study.model.coordinates.lower`;
* the Exudyn model (:mod:`study.exudyn_models.translate`);
* the joint reactions (:mod:`study.model.reactions`) and the compiled kernels (:mod:`study.fast`).

Conventions
-----------
* A body's local frame has its origin at the centre of mass and turns with the body's angle; its
  named points are given in that frame. Ground points are given in the global frame.
* ``revolute(name, (A, a), (B, b))``: point a of body A coincides with point b of body B (either may
  be ``GROUND``). Constraint rows ``r_A(a) - r_B(b) = 0`` (two rows, ``<name>_x`` and ``<name>_y``).
  ``friction=Friction(mu, mu, T0), radius=r``: Coulomb pin friction, a torque -(mu r |R|_delta + T0) s(omega_rel)
  on the relative rotation (R = the two rows' multipliers, so the joint is always a cut joint; see :class:`Revolute`).
* ``prismatic(name, slider=(S, s), guide=(G, g), axis, normal)``: point s of body S slides on the
  line through point g of G along ``axis`` (G's frame); ``normal`` (G's frame, unit, orthogonal to
  the axis) orients the gap row ``<name> = n . (r_S(s) - r_G(g))``, so its multiplier lambda is a
  force: the guide pushes the slider with ``-lambda n``. The relative rotation is locked
  (row ``<name>_angle = theta_S - theta_G - angle_offset``). Optional Coulomb contact data
  (:class:`Friction`) makes it a sliding contact with friction (a cut joint: no ``travel``). The guide may
  be ground or a moving body: the normal force is the gap row's multiplier (along the guide's normal,
  turning with it), the sliding velocity is the slider point's velocity relative to the guide's
  coincident point along the guide's axis, and the friction acts on both bodies, equal and opposite.
* Loads are data: sympy expressions in named inputs (:meth:`Description.position`,
  :meth:`~Description.velocity`, :meth:`~Description.angle`, :meth:`~Description.rate`,
  :attr:`~Description.t`) and parameters (``d.p.<name>``). A switching law declares its switching
  functions with :meth:`~Description.switch`, which returns a mode symbol (+1 or -1: the sign of the
  switching function, frozen between located switches); the law is then smooth in every mode.
* The relative coordinates: every body's angle is an expression of q (``body(..., angle=...)``).
  Bodies are placed from ground along a spanning tree of revolute joints and prismatic joints with a
  travel, taken in description order; the joints left over are cut joints, whose rows are the
  constraints. A free body gives its centre of mass too (``body(..., position=(x, y))``, expressions of
  q): it is placed by its own coordinates, held by loads or by joints, which are then cut joints.
* ``spring_damper(name, a, b, k, c, L0)``: a linear spring (a potential) and a viscous damper along the
  line between two points (forces on both, equal and opposite; a ground point carries nothing).
"""

from __future__ import annotations

import dataclasses
import hashlib
from types import SimpleNamespace
from typing import Any, Mapping, Sequence

import sympy as sp

from study.model.description_checks import description_problems
from study.model.elements import (GROUND, Body, DescriptionError, Distance, Expr, Friction, Input, Load,  # noqa: F401
                                 Potential, Prismatic, Revolute)


class Description:
    """Collect a planar mechanism's joint-level description.

    Parameters
    ----------
    name : str
    coordinates : sequence of str
        Names of the relative coordinates q (``d.q``, ``d.qd`` hold their symbols).
    parameters : mapping str -> float or str
        Numeric values; ``d.p.<name>`` is the sympy symbol. Parameters stay symbolic in the
        generated code, so one derivation serves every variant that shares the description.
        String values (a parameter file's choices) select the description's form and get no symbol.
    label : str, optional
        Human-readable name for reports.
    """

    def __init__(self, name: str, coordinates: Sequence[str], parameters: Mapping[str, float], label: str = ""):
        if not coordinates or len(set(coordinates)) != len(coordinates):
            raise DescriptionError(f"mechanism {name!r}: coordinates {list(coordinates)} must be non-empty and unique")
        self.name = name
        self.label = label or name
        self.coordinate_names = tuple(coordinates)
        self.q = sp.Matrix(sp.symbols([f"q_{c}" for c in coordinates], real=True))
        self.qd = sp.Matrix(sp.symbols([f"qd_{c}" for c in coordinates], real=True))
        self.values = {k: float(v) for k, v in parameters.items() if not isinstance(v, str)}
        self.p = SimpleNamespace(**{k: sp.Symbol(f"p_{k}", real=True) for k in self.values})
        self.t = sp.Symbol("t", real=True)
        self.bodies: dict[str, Body] = {}
        self.ground_points: dict[str, tuple[Expr, Expr]] = {}
        self.joints: list[Revolute | Prismatic | Distance] = []
        self.loads: list[Load] = []
        self.potentials: list[Potential] = []
        self.gravity_g: Expr | None = None
        self.inputs: dict[sp.Symbol, Input] = {}
        self.switches: list[tuple[str, Expr, sp.Symbol]] = []
        self.branch: tuple[Expr, str] | None = None

    # --- bodies and points -------------------------------------------------------------------
    def body(self, name: str, mass: Any, inertia: Any, points: Mapping[str, tuple[Any, Any]], angle: Any,
             position: tuple[Any, Any] | None = None) -> str:
        """A rigid body; ``points`` in its COM frame, ``angle`` its angle as an expression of q; ``position`` (a
        free body) its centre of mass as expressions of q, so that it needs no joint to be placed."""
        if name == GROUND or name in self.bodies:
            raise DescriptionError(f"mechanism {self.name!r}: body name {name!r} is reserved or used twice")
        pts = {k: (sp.sympify(v[0]), sp.sympify(v[1])) for k, v in points.items()}
        where = None if position is None else (sp.sympify(position[0]), sp.sympify(position[1]))
        self.bodies[name] = Body(name, sp.sympify(mass), sp.sympify(inertia), pts, sp.sympify(angle), where)
        return name

    def ground(self, name: str, x: Any, y: Any) -> tuple[str, str]:
        """A named point fixed in the global frame (each name once: a second definition would move the first)."""
        if name in self.ground_points:
            first = ", ".join(map(str, self.ground_points[name]))
            raise DescriptionError(f"mechanism {self.name!r}: ground point {name!r} is defined twice (at ({first}) "
                                   f"and at ({x}, {y})): give each ground point its own name")
        self.ground_points[name] = (sp.sympify(x), sp.sympify(y))
        return (GROUND, name)

    # --- joints ------------------------------------------------------------------------------
    def revolute(self, name: str, a: tuple[str, str], b: tuple[str, str], cut: bool | None = None,
                 friction: Friction | None = None, radius: Any = None) -> None:
        """Point a[1] of body a[0] coincides with point b[1] of body b[0]; ``cut`` forces a loop closure.
        ``friction`` and ``radius`` [m]: Coulomb pin friction (see :class:`Revolute`); the joint is then a cut joint."""
        self.joints.append(Revolute(name, tuple(a), tuple(b), cut, friction,
                                    None if radius is None else sp.sympify(radius)))

    def prismatic(self, name: str, slider: tuple[str, str], guide: tuple[str, str], axis, normal,
                  angle_offset: Any = 0, friction: Friction | None = None, travel: Any = None) -> None:
        """Point slider[1] of slider[0] slides on the line through guide[1] along ``axis`` (guide frame), the
        slider's angle being the guide's plus ``angle_offset``. ``travel`` (an expression of q, usually a
        coordinate) is the slider point's position along the axis: given, the joint can place the slider (or the
        guide) in relative coordinates, like a revolute joint with its angle (a cart on a rail, a piston in a
        rotating cylinder); a joint with friction cannot have one (its normal force is its gap row's multiplier)."""
        self.joints.append(Prismatic(name, tuple(slider), tuple(guide), tuple(sp.sympify(v) for v in axis),
                                     tuple(sp.sympify(v) for v in normal), sp.sympify(angle_offset), friction,
                                     None if travel is None else sp.sympify(travel)))

    def distance(self, name: str, a: tuple[str, str], b: tuple[str, str], length: Any) -> None:
        """Point a keeps its distance ``length`` from point b (a massless rod pinned at both ends; one row)."""
        self.joints.append(Distance(name, tuple(a), tuple(b), sp.sympify(length)))

    # --- load-law inputs ---------------------------------------------------------------------
    def _input(self, kind: str, body: str, point: str | None) -> sp.Symbol:
        tag = f"{kind}__{body}" + (f"__{point}" if point else "")
        sym = sp.Symbol(f"in_{tag}", real=True)
        self.inputs[sym] = Input(kind, body, point)
        return sym

    def position(self, body: str, point: str) -> tuple[sp.Symbol, sp.Symbol]:
        """Global position (x, y) of a body point, as input symbols of a load law."""
        return self._input("x", body, point), self._input("y", body, point)

    def velocity(self, body: str, point: str) -> tuple[sp.Symbol, sp.Symbol]:
        """Global velocity (vx, vy) of a body point, as input symbols of a load law."""
        return self._input("vx", body, point), self._input("vy", body, point)

    def angle(self, body: str) -> sp.Symbol:
        return self._input("angle", body, None)

    def rate(self, body: str) -> sp.Symbol:
        return self._input("rate", body, None)

    def switch(self, name: str, expr: Any) -> sp.Symbol:
        """Declare a switching function of the inputs; returns its mode symbol (+1 / -1)."""
        mode = sp.Symbol(f"mode_{len(self.switches)}", real=True)
        self.switches.append((name, sp.sympify(expr), mode))
        return mode

    # --- loads -------------------------------------------------------------------------------
    def gravity(self, g: Any) -> None:
        """Uniform gravity of magnitude g along -y on every body."""
        self.gravity_g = sp.sympify(g)

    def torque(self, name: str, body: str, law: Any) -> None:
        """A torque on a body (counter-clockwise positive), law in the inputs."""
        self.loads.append(Load(name, body, None, (sp.sympify(law),)))

    def force(self, name: str, body: str, point: str, fx: Any, fy: Any) -> None:
        """A force (global frame) at a body point, law in the inputs."""
        self.loads.append(Load(name, body, point, (sp.sympify(fx), sp.sympify(fy))))

    def torsion_spring(self, name: str, body: str, stiffness: Any, rest_angle: Any = 0) -> None:
        """A torsion spring between ground and a body: V = k (theta - theta0)^2 / 2."""
        th = self.angle(body)
        self.potentials.append(Potential(name, sp.sympify(stiffness) * (th - sp.sympify(rest_angle)) ** 2 / 2))

    def spring(self, name: str, a: tuple[str, str], b: tuple[str, str], stiffness: Any, rest_length: Any) -> None:
        """A linear spring between two body points: V = k (|r_a - r_b| - L0)^2 / 2."""
        length = self._length(a, b)[0]
        self.potentials.append(Potential(name, sp.sympify(stiffness) * (length - sp.sympify(rest_length)) ** 2 / 2))

    def _length(self, a: tuple[str, str], b: tuple[str, str]) -> tuple[Expr, Expr, Expr]:
        """|r_b - r_a| and the unit vector from a to b, in the points' position inputs (singular where they meet)."""
        (xa, ya), (xb, yb) = self.position(*a), self.position(*b)
        length = sp.sqrt((xa - xb) ** 2 + (ya - yb) ** 2)
        return length, (xb - xa) / length, (yb - ya) / length

    def spring_damper(self, name: str, a: tuple[str, str], b: tuple[str, str], stiffness: Any, damping: Any,
                      rest_length: Any) -> None:
        """A spring (V = k (l - L0)^2 / 2, l = |r_b - r_a|) and a viscous damper (force c dl/dt along the line,
        opposing the change of length) between two points. The damper is two loads, ``<name>_a`` and ``<name>_b``
        (the one on a ground point left out); the spring is the potential ``<name>``."""
        self.spring(name, a, b, stiffness, rest_length)
        (vxa, vya), (vxb, vyb) = self.velocity(*a), self.velocity(*b)
        _, ex, ey = self._length(a, b)
        pull = sp.sympify(damping) * (ex * (vxb - vxa) + ey * (vyb - vya))   # force on b is -pull e, on a +pull e
        for end, sign in ((a, 1), (b, -1)):
            if end[0] != GROUND:
                self.force(f"{name}_{'a' if sign > 0 else 'b'}", end[0], end[1], sign * pull * ex, sign * pull * ey)

    # --- metadata ----------------------------------------------------------------------------
    def assembly_branch(self, expr: Any, label: str) -> None:
        """The assembly branch: ``expr(q) > 0`` on the intended configuration."""
        self.branch = (sp.sympify(expr), label)

    def pins(self) -> list[Revolute]:
        """The revolute joints with friction (cut joints whose reaction sets a friction torque)."""
        return [j for j in self.joints if isinstance(j, Revolute) and j.friction is not None]

    def contacts(self) -> list[Prismatic]:
        return [j for j in self.joints if isinstance(j, Prismatic) and j.friction is not None]

    def fingerprint(self) -> str:
        """SHA-256 (16 hex) of the description's content: bodies, joints, loads, switches, branch, parameter values
        (everything but the report label), so that an edit that changes the mechanism changes it and nothing else does."""
        content = {k: v for k, v in vars(self).items() if k != "label"}
        return hashlib.sha256(_canonical(content).encode()).hexdigest()[:16]

    # --- checks ------------------------------------------------------------------------------
    def validate(self) -> None:
        """Report every problem of the description in one DescriptionError, each naming its body, joint, load, point
        or input and why (:mod:`study.model.description_checks`). What needs the coordinate set (the placement tree,
        the degrees of freedom) is checked by :func:`study.model.coordinates.lower`."""
        problems = description_problems(self)
        if problems:
            raise DescriptionError(f"mechanism {self.name!r}: " + "; ".join(problems))


def _canonical(obj: Any) -> str:
    """A text that is the same for equal content in every process: sympy objects by srepr, containers recursively."""
    if isinstance(obj, (sp.Basic, sp.MatrixBase)):
        return sp.srepr(obj)
    if dataclasses.is_dataclass(obj):
        return type(obj).__name__ + _canonical({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)})
    if isinstance(obj, SimpleNamespace):
        obj = vars(obj)
    if isinstance(obj, dict):
        return "{" + ", ".join(f"{_canonical(k)}: {_canonical(v)}" for k, v in obj.items()) + "}"
    if isinstance(obj, (list, tuple)):
        return "[" + ", ".join(map(_canonical, obj)) + "]"
    if obj is None or isinstance(obj, (str, int, float, bool)):
        return repr(obj)
    raise TypeError(f"a description holds a {type(obj).__name__}, which has no canonical form")


def rotation(angle: Expr) -> sp.Matrix:
    """The planar rotation matrix R(angle)."""
    return sp.Matrix([[sp.cos(angle), -sp.sin(angle)], [sp.sin(angle), sp.cos(angle)]])
