"""The numeric equations-of-motion interface at the centre of the solver.

A mechanism, planar or spatial, in m redundant coordinates q with r holonomic constraints::

    M(q) q'' + Phi_q(q)^T lambda = Q(t, q, q')
    Phi(q) = 0,   Phi_q q'' = gamma(q, q'),   gamma = -(Phi_q q')_q q'

The solver only ever sees this object. It comes from a :class:`study.model.Mechanism` (a planar description's
generated equations) or a spatial description (:mod:`study.spatial`), or is written by hand from plain callables.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

from study.errors import EquationsError

Array = np.ndarray


@dataclass(frozen=True)
class SlidingContact:
    """A sliding joint whose normal reaction is the multiplier of one constraint row.

    The constraint row ``constraint_index`` must be the normal gap of the contact point (a distance,
    unit normal), so that its multiplier is a force: the guide pushes the body with N = -lambda
    along the normal. The tangential velocity is ``v_t = tangent_jacobian(q) @ qd`` and its
    acceleration ``a_t = tangent_jacobian(q) @ qdd + tangent_bias(q, qd)``.

    Attributes
    ----------
    name : str
    constraint_index : int
    tangent_jacobian : callable (q) -> (m,)
    tangent_bias : callable (q, qd) -> float
    mu_static, mu_kinetic : float
        Coulomb coefficients; equal unless a parameter set says otherwise.
    resistance : float
        Constant extra resistance opposing sliding [N] (paper 000's F); part of the static limit too.
    """

    name: str
    constraint_index: int
    tangent_jacobian: Callable[[Array], Array]
    tangent_bias: Callable[[Array, Array], float]
    mu_static: float
    mu_kinetic: float
    resistance: float = 0.0

    def __post_init__(self) -> None:
        for key in ("mu_static", "mu_kinetic", "resistance"):
            value = getattr(self, key)
            if not np.isfinite(value) or value < 0:
                raise ValueError(f"contact {self.name!r}: {key} = {value!r} must be finite and >= 0")


@dataclass(frozen=True)
class FrictionalPin:
    """Coulomb friction of a joint whose reaction R is the multipliers of constraint rows ``rows`` (two rows: a
    planar revolute joint's x, y; a spatial revolute joint's two rows across its axis, or a spatial prismatic joint's
    two transverse rows, :mod:`study.spatial.friction`).

    The friction torque (a revolute joint) or force (a prismatic one, ``radius`` 1) on the relative motion is
    tau = -(mu_kinetic radius |R|_delta + torque) s(omega_rel), omega_rel = rate_jacobian(q) @ qd the relative
    angular velocity [rad/s] or sliding velocity [m/s], and its generalized force rate_jacobian(q) * tau (the load on
    one body, minus it on the other). |R|_delta = sqrt(Rx^2 + Ry^2 + delta^2) (``pin_friction_norm_width`` in
    reference/tolerances.toml). At rest the joint holds up to mu_static radius |R|_delta + torque (the exact
    treatment); its relative acceleration is rate_jacobian(q) @ qdd + rate_bias(q, qd).
    """

    name: str
    rows: tuple[int, int]
    rate_jacobian: Callable[[Array], Array]
    rate_bias: Callable[[Array, Array], float]
    mu_static: float
    mu_kinetic: float
    radius: float
    torque: float = 0.0

    def __post_init__(self) -> None:
        for key in ("mu_static", "mu_kinetic", "radius", "torque"):
            value = getattr(self, key)
            if not np.isfinite(value) or value < 0 or (key == "radius" and value == 0):
                raise ValueError(f"pin {self.name!r}: {key} = {value!r} must be finite and "
                                 f"{'> 0' if key == 'radius' else '>= 0'}")


def _no_forces(t: float, q: Array, qd: Array) -> dict[str, Array]:
    return {}


@dataclass(frozen=True)
class EquationsOfMotion:
    """Callables describing a constrained planar mechanism (shapes: q, qd (m,), Phi (r,)).

    Parameters
    ----------
    n_coordinates, n_constraints : int
        m and r.
    mass : callable (q) -> (m, m)
        Symmetric positive-definite mass matrix.
    forces : callable (t, q, qd[, mode]) -> (m,)
        Everything on the right-hand side: applied loads, gravity and the velocity-dependent
        terms (-C(q, qd) qd). It must accept ``mode=`` if ``indicators`` is given.
    phi : callable (q) -> (r,)
    phi_q : callable (q) -> (r, m)
    gamma : callable (q, qd) -> (r,)
        ``-(Phi_q qd)_q qd``.
    contacts : sequence of SlidingContact
        Sliding joints with Coulomb friction (optional).
    pin_frictions : sequence of FrictionalPin
        Revolute joints with Coulomb friction (optional; a user's equations run them on backend 'reference' only).
    potential_energy : callable (q) -> float, optional
        Potential of the conservative loads included in ``forces`` (gravity, springs).
    applied_forces : callable (t, q, qd[, mode]) -> dict[str, (m,)], optional
        Generalized force of every non-conservative applied load, by name (their work is tracked).
    points : mapping name -> callable (q) -> (2,), optional
        Positions of named points (generated equations: ``<body>.<point>`` and ``<body>.com``).
    kinematics : mapping name -> callable, optional
        The generated equations' kinematic functions: ``pos__<point>`` (q) -> (2,), ``jac__<point>``
        (q) -> (2, m), ``bias__<point>`` (q, qd) -> (2,) (= Jdot qd), ``angle__<body>``,
        ``angle_jac__<body>``, ``angle_bias__<body>``.
    indicators : callable (t, q, qd) -> (k,), optional
        Switching functions of discontinuous loads. Between two zero crossings the loads use a
        frozen ``mode`` (tuple of +-1, the indicators' signs), so an integrator can locate switches.
    redundant_rows : int
        How many of the r rows are dependent at every configuration (Bricard's linkage: 1), so that
        rank(Phi_q) = r - redundant_rows < m; 0 (the default) for independent rows, r < m.
    """

    n_coordinates: int
    n_constraints: int
    mass: Callable[[Array], Array]
    forces: Callable[..., Array]
    phi: Callable[[Array], Array]
    phi_q: Callable[[Array], Array]
    gamma: Callable[[Array, Array], Array]
    name: str = "user"
    coordinate_names: tuple[str, ...] = ()
    constraint_names: tuple[str, ...] = ()
    contacts: tuple[SlidingContact, ...] = ()
    pin_frictions: tuple[FrictionalPin, ...] = ()
    potential_energy: Callable[[Array], float] | None = None
    applied_forces: Callable[..., Mapping[str, Array]] = _no_forces
    indicators: Callable[[float, Array, Array], Array] | None = None
    indicator_names: tuple[str, ...] = ()
    parameter_hash: str = ""
    points: Mapping[str, Callable[[Array], Array]] = field(default_factory=dict)
    kinematics: Mapping[str, Callable[..., Array]] = field(default_factory=dict)
    redundant_rows: int = 0

    def __post_init__(self) -> None:
        for key in ("n_coordinates", "n_constraints"):   # numpy's integers too, kept as Python ints
            value = getattr(self, key)
            if isinstance(value, numbers.Integral) and not isinstance(value, bool):
                object.__setattr__(self, key, int(value))
        m, r = self.n_coordinates, self.n_constraints
        problems = []
        if not isinstance(m, int) or m < 1:
            problems.append(f"n_coordinates = {m!r} must be a positive integer")
        k = self.redundant_rows
        if not isinstance(k, int) or not 0 <= k <= (r if isinstance(r, int) else 0):
            problems.append(f"redundant_rows = {k!r} must be an integer with 0 <= redundant_rows <= r = {r!r}")
        elif not isinstance(r, int) or not 0 <= r - k < (m if isinstance(m, int) else 1):
            problems.append(f"n_constraints = {r!r} must be an integer with 0 <= r - redundant_rows ({k}) < "
                            f"n_coordinates = {m!r}")
        for key in ("mass", "forces", "phi", "phi_q", "gamma"):
            if not callable(getattr(self, key)):
                problems.append(f"{key} must be callable, got {type(getattr(self, key)).__name__}")
        if self.coordinate_names and len(self.coordinate_names) != m:
            problems.append(f"{len(self.coordinate_names)} coordinate_names for {m} coordinates")
        if self.constraint_names and len(self.constraint_names) != r:
            problems.append(f"{len(self.constraint_names)} constraint_names for {r} constraints")
        for pin in self.pin_frictions:
            if not all(0 <= k < (r if isinstance(r, int) else 0) for k in pin.rows):
                problems.append(f"pin {pin.name!r}: rows {pin.rows} outside 0..{r - 1}")
        for c in self.contacts:
            if not 0 <= c.constraint_index < (r if isinstance(r, int) else 0):
                problems.append(f"contact {c.name!r}: constraint_index {c.constraint_index} outside 0..{r - 1}")
        if problems:
            raise ValueError(f"EquationsOfMotion {self.name!r}: " + "; ".join(problems))
        if not self.coordinate_names:
            object.__setattr__(self, "coordinate_names", tuple(f"q{i + 1}" for i in range(m)))
        if not self.constraint_names:
            object.__setattr__(self, "constraint_names", tuple(f"phi{i + 1}" for i in range(r)))

    @property
    def dof(self) -> int:
        """Degrees of freedom n = m - r + redundant_rows."""
        return self.n_coordinates - self.n_constraints + self.redundant_rows

    def redundancy_note(self) -> dict:
        """Result metadata of redundant rows (none for independent rows): their count and why the multipliers are
        not unique."""
        if not self.redundant_rows:
            return {}
        return {"redundant_rows": self.redundant_rows,
                "reactions_unique": False,
                "reactions_note": f"{self.redundant_rows} of the {self.n_constraints} constraint rows are dependent "
                                  f"at every configuration: any lam + z with Phi_q^T z = 0 gives the same motion; the "
                                  f"stored lam is the acceleration solver's (augmented_lagrangian, from lam = 0: the "
                                  f"minimum-norm one, up to the share of the constraints' drift); only Phi_q^T lam, "
                                  f"the joints' generalized force, is unique"}

    def kinetic_energy(self, q: Array, qd: Array) -> float:
        """T = 1/2 qd^T M(q) qd."""
        return 0.5 * float(qd @ self.mass(q) @ qd)

    def outputs(self) -> tuple[tuple[str, Callable[..., object], tuple[int, ...]], ...]:
        """(name, callable, expected shape) of the callables a run evaluates; potential_energy (a scalar) if given."""
        m, r = self.n_coordinates, self.n_constraints
        calls = (("mass", self.mass, (m, m)), ("forces", self.forces, (m,)), ("phi", self.phi, (r,)),
                 ("phi_q", self.phi_q, (r, m)), ("gamma", self.gamma, (r,)))
        return calls + ((("potential_energy", self.potential_energy, ()),) if self.potential_energy else ())

    def check_shapes(self, q: Array, qd: Array, t: float = 0.0) -> None:
        """Evaluate every callable once at the initial state (t0, q0, qd0) = (t, q, qd) and raise an
        :class:`study.errors.EquationsError` (a ValueError) naming each one that raises, returns something
        other than real numbers (None, text, complex values) or has the wrong shape."""
        args = {"mass": "(q0)", "forces": "(t0, q0, qd0)", "phi": "(q0)", "phi_q": "(q0)", "gamma": "(q0, qd0)",
                "potential_energy": "(q0)"}
        bad = []
        for name, f, shape in self.outputs():
            label = name + args[name]
            try:
                value = f(t, q, qd) if name == "forces" else f(q, qd) if name == "gamma" else f(q)
            except Exception as exc:  # noqa: BLE001 - reported as a problem of the user's callable
                bad.append(f"{label} raised {type(exc).__name__}: {' '.join(str(exc).split())}")
                continue
            problem = output_problem(value, shape)
            if problem:
                bad.append(f"{label} {problem}")
        if bad:
            raise EquationsError(f"EquationsOfMotion {self.name!r}: " + "; ".join(bad), tuple(bad))


def _show(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def output_problem(value: object, shape: tuple[int, ...]) -> str | None:
    """What is wrong with a callable's returned ``value`` for the ``shape`` it must have (``()``: a scalar), as
    the end of a sentence starting with the callable's name; None if it is a real array of that shape.
    Complex values are reported (with 'complex' in the sentence) even with a zero imaginary part: the
    solver would drop the imaginary part silently."""
    expected = "a scalar" if shape == () else f"{shape}"
    try:
        array = np.asarray(value)
    except Exception:  # noqa: BLE001 - e.g. a ragged sequence
        return f"returned {_show(value)}, not an array of shape {expected}"
    if array.dtype.kind == "c":
        return f"returned complex values {_show(value)}: the equations must be real"
    if array.dtype.kind not in "biuf":
        kind = "" if value is None else f" (a {type(value).__name__})"
        return f"returned {_show(value)}{kind}, expected real numbers of shape {expected}"
    if array.shape != shape:
        return f"has shape {array.shape}, expected {expected}"
    return None
