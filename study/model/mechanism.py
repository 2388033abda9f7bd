"""A mechanism: a joint-level description, its parameters and its initial state, what every engine takes.

The one public way to a mechanism of one's own is Description -> Mechanism::

    d = study.Description("pendulum", ["th"], {"m": 1.0, "L": 0.5, "g": 9.81})
    ...                                              # bodies, joints, loads (study.model.joints)
    mech = study.Mechanism(d, q0={"th": 1.0}, qd0={"th": 0.0})

The parameter values are then the description's own and the initial state is given by coordinate name: the named
coordinates are independent, the others are solved from the constraints (:mod:`study.inline_parameters`). A
parameter file with provenance (:mod:`study.params`) is how the study's own mechanisms are written; it is optional
for a user (``Mechanism(d, ps)``). The study's mechanisms by name come from the catalogue
(:func:`study.mechanisms.named_mechanism`). The body-level :class:`study.model.builder.MechanismBuilder` the
description lowers to is an internal detail of the derivation.
"""

from __future__ import annotations

import hashlib
from dataclasses import InitVar, dataclass, field
from typing import ClassVar, Mapping

import numpy as np
import sympy as sp

from study.inline_parameters import inline_parameters
from study.model.compile import compile_description
from study.model.coordinates import COORDINATE_SETS, lower
from study.model.eom import EquationsOfMotion
from study.model.initial_state import ConsistentState, InitialConditionError, consistent_initial_conditions
from study.model.joints import Description
from study.params import ParameterSet


def equations_of(d: Description, coordinates: str = "relative", parameter_hash: str = "") -> EquationsOfMotion:
    """The compiled equations of motion of any description, a user's or the study's, in 'relative' (the
    description's own coordinates) or 'absolute' coordinates (x, y, theta of every body)."""
    if coordinates not in COORDINATE_SETS:
        raise ValueError(f"unknown coordinate set {coordinates!r}; valid choices: {', '.join(COORDINATE_SETS)}")
    return compile_description(lower(d, coordinates), parameter_hash)


@dataclass(frozen=True, eq=False)
class Mechanism:
    """A description with its parameters: what the engines take (the in-house paths, the Exudyn translator).

    ``Mechanism(d, q0={"th": 1.0}, qd0={"th": 0.0})``: the parameter values are the description's own, the initial
    state is given by coordinate name (the named coordinates independent, the others solved from the constraints).
    ``Mechanism(d, ps)``: a parameter set with provenance (:mod:`study.params`) gives the values and the initial
    state in its ``[initial_conditions]``. ``guess``: Newton's start for q(0) (default: the parameter set's printed
    q(0), or q0 and zeros). The equations are derived once per coordinate set and kept.
    """

    description: Description
    parameters: ParameterSet | None = None
    guess: np.ndarray | None = None
    _equations: dict = field(default_factory=dict, repr=False)
    q0: InitVar[Mapping[str, float] | None] = None
    qd0: InitVar[Mapping[str, float] | None] = None
    #: what the engines dispatch on: 'planar' here, 'spatial' for :class:`study.spatial.SpatialMechanism`
    kind: ClassVar[str] = "planar"

    def __post_init__(self, q0, qd0) -> None:
        if not isinstance(self.description, Description):
            raise TypeError(f"Mechanism(description=...) takes a planar study.Description, got "
                            f"{type(self.description).__name__}; a spatial description's mechanism is "
                            f"study.spatial.SpatialMechanism(description, positions=..., ...), never a planar one")
        self.description.validate()
        if self.parameters is None:
            if q0 is None:
                raise ValueError(f"Mechanism({self.description.name}): give the initial state by coordinate name, "
                                 f"q0={{...}} (and qd0), or a parameter set")
            d = self.description
            object.__setattr__(self, "parameters", inline_parameters(d.name, d.values, d.coordinate_names, q0, qd0))
        elif not isinstance(self.parameters, ParameterSet):
            raise TypeError(f"Mechanism({self.description.name}): parameters = {self.parameters!r} must be a "
                            f"ParameterSet (study.load_parameters); a description's own values need none: give the "
                            f"initial state as q0={{...}}, qd0={{...}}")
        elif q0 is not None or qd0 is not None:
            raise ValueError(f"Mechanism({self.description.name}): q0/qd0 and a parameter set both give the initial "
                             f"state; the parameter set's is in its [initial_conditions]: give one of them")

    @property
    def name(self) -> str:
        return self.description.name

    def equations(self, coordinates: str = "relative") -> EquationsOfMotion:
        if coordinates not in self._equations:
            self._equations[coordinates] = equations_of(self.description, coordinates, self.parameters.sha256)
        return self._equations[coordinates]

    def initial_state(self) -> ConsistentState:
        """Consistent q(0), qd(0) in relative coordinates (:func:`consistent_state`)."""
        return consistent_state(self.description, self.parameters, self.equations(), self.guess)

    def fingerprint(self) -> str:
        """SHA-256 (16 hex) of what a run of this mechanism depends on besides the engine's code: the description's
        content, the parameter file and Newton's start."""
        guess = "" if self.guess is None else np.asarray(self.guess, dtype=float).tobytes().hex()
        text = "\n".join((self.description.fingerprint(), self.parameters.sha256, guess))
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def on_branch(d: Description, q: np.ndarray) -> bool:
    """Whether relative coordinates q lie on the description's assembly branch (True without one)."""
    return d.branch is None or _branch_value(d, q) > 0


def _branch_value(d: Description, q: np.ndarray) -> float:
    """The description's branch condition evaluated at q (> 0 on the branch)."""
    expr = d.branch[0].xreplace({getattr(d.p, k): float(v) for k, v in d.values.items()})
    return float(sp.lambdify([list(d.q)], expr, "math")(list(map(float, q))))


def consistent_state(d: Description, ps: ParameterSet, eom: EquationsOfMotion, guess=None) -> ConsistentState:
    """Consistent q(0), qd(0) of any description in its relative coordinates (``eom``: its relative equations)
    from a parameter set's ``[initial_conditions]``: Newton from ``guess`` (default: the printed q(0)) with the
    independent coordinates set to the specified values, then the rates; the result must lie on the
    description's assembly branch (InitialConditionError otherwise)."""
    ic = ps.initial
    start = "the printed q(0)" if guess is None else "the initial guess"
    guess = np.array(ic.printed_q if guess is None else guess, dtype=float)
    if guess.shape != (eom.n_coordinates,):
        raise ValueError(f"{d.name}: the initial guess has {guess.size} positions, the equations have "
                         f"{eom.n_coordinates} coordinates")
    guess[list(ic.independent)] = ic.q_independent
    state = consistent_initial_conditions(eom, guess, ic.independent, ic.qd_independent)
    if not on_branch(d, state.q):
        expr, label = d.branch
        raise InitialConditionError(
            f"{d.name}: Newton from {start} converged to q = {state.q}, which is not on the "
            f"assembly branch '{label}' (the parameter file's '{ic.branch}'): its condition {expr} > 0 is "
            f"{_branch_value(d, state.q):.6g} there; change the printed q(0) or the guess")
    return state
