"""Mechanisms: one joint-level description module per mechanism, built from its parameter set.

A mechanism ``name`` is a parameter file ``reference/<name>.toml`` plus a module
``study.mechanisms.<name>`` with ``describe(ps) -> study.model.joints.Description`` (and ``LABEL``).
Nothing else is per-mechanism code: the equations in either coordinate set, the compiled kernels,
the Exudyn model and the joint reactions are all generated from the description.
"""

from __future__ import annotations

import hashlib
import importlib
from dataclasses import InitVar, dataclass, field
from functools import lru_cache
from pathlib import Path
from types import ModuleType
from typing import Mapping

import numpy as np
import sympy as sp

from study.model import EquationsOfMotion
from study.model.builder import MechanismBuilder
from study.model.compile import compile_description
from study.model.coordinates import COORDINATE_SETS, lower
from study.model.joints import Description
from study.inline_parameters import inline_parameters
from study.params import ParameterSet, available_mechanisms, load_parameters
from study.user_mechanism import load_parts
from study.solver.initial import ConsistentState, InitialConditionError, consistent_initial_conditions


def module(name: str) -> ModuleType:
    """The description module of a mechanism (ValueError naming the valid choices)."""
    known = available_mechanisms()
    if name not in known:
        raise ValueError(f"unknown mechanism {name!r}; valid choices: {', '.join(known)}")
    return importlib.import_module(f"study.mechanisms.{name}")


def description(ps: ParameterSet) -> Description:
    """The joint-level description of a parameter set's mechanism."""
    return module(ps.mechanism).describe(ps)


def label(name: str) -> str:
    """Human-readable name of a mechanism (its module's ``LABEL``)."""
    return getattr(module(name), "LABEL", name)


def coordinate_unit(name: str) -> str:
    """Unit of a mechanism's relative coordinates (its module's ``COORDINATE_UNIT``, default 'rad')."""
    return getattr(module(name), "COORDINATE_UNIT", "rad")


def time_scale(name: str) -> float:
    """Characteristic time of a mechanism's motion [s] (its module's ``TIME_SCALE``, default 1 s).

    Generic checks that run every mechanism scale their horizons and fixed steps by it, so a fast
    mechanism (a benchmark over milliseconds) is run over a comparable part of its motion.
    """
    return float(getattr(module(name), "TIME_SCALE", 1.0))


def constraint_unit(name: str) -> str:
    """Unit of a mechanism's constraint rows: 'm' (joint gaps), 'rad', or 'm, rad' when mixed."""
    rows = equations(load_parameters(name)).constraint_names
    units = sorted({"rad" if r.endswith("_angle") else "m" for r in rows})
    return ", ".join(units)


def equations_of(d: Description, coordinates: str = "relative", parameter_hash: str = "") -> EquationsOfMotion:
    """The compiled equations of motion of any description, a user's or the study's, in 'relative' (the
    description's own coordinates) or 'absolute' coordinates (x, y, theta of every body)."""
    if coordinates not in COORDINATE_SETS:
        raise ValueError(f"unknown coordinate set {coordinates!r}; valid choices: {', '.join(COORDINATE_SETS)}")
    return compile_description(lower(d, coordinates), parameter_hash)


@dataclass(frozen=True, eq=False)
class Mechanism:
    """A description with its parameter set: what the engines take (the in-house paths, the Exudyn translator).

    A user builds one from a description alone, its parameter values being the description's own and the initial
    state given by coordinate name (``Mechanism(d, q0={"th": 1.0}, qd0={"th": 0.0})``: the named coordinates are
    independent, the others solved from the constraints; :mod:`study.inline_parameters`), or from a description
    and a parameter file with provenance (``Mechanism(describe(ps), ps)``); the study's mechanisms come from
    :func:`mechanism`. ``guess``: Newton's start for q(0) (default: the parameter set's printed q(0), or q0 and
    zeros). The equations are derived once per coordinate set and kept.
    """

    description: Description
    parameters: ParameterSet | None = None
    guess: np.ndarray | None = None
    _equations: dict = field(default_factory=dict, repr=False)
    q0: InitVar[Mapping[str, float] | None] = None
    qd0: InitVar[Mapping[str, float] | None] = None

    def __post_init__(self, q0, qd0) -> None:
        if not isinstance(self.description, Description):
            raise TypeError(f"Mechanism(description=...) takes a study.Description, got {type(self.description).__name__}")
        self.description.validate()
        if self.parameters is None:
            if q0 is None:
                raise ValueError(f"Mechanism({self.description.name}): give the initial state by coordinate name, "
                                 f"q0={{...}} (and qd0), or a parameter set")
            d = self.description
            object.__setattr__(self, "parameters", inline_parameters(d.name, d.values, d.coordinate_names, q0, qd0))
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


_MECHANISMS: dict[tuple, Mechanism] = {}


def mechanism(ps: ParameterSet) -> Mechanism:
    """The study's mechanism of a parameter set (its description module's ``describe`` and ``initial_guess``)."""
    key = (ps.mechanism, ps.variant, ps.sha256, ps.values)   # values too: a replaced parameter set keeps its sha256
    if key not in _MECHANISMS:
        _MECHANISMS[key] = Mechanism(description(ps), ps, initial_guess(ps)[0])
    return _MECHANISMS[key]


def load_mechanism(path: str | Path, variant: str = "seed") -> Mechanism:
    """A user's mechanism file (``describe(ps)``, optional ``initial_guess(ps)``) and its parameter file beside it
    (:mod:`study.user_mechanism`: whatever is wrong in the file is one UserFileError naming the file, the function,
    the line and the cause)."""
    return Mechanism(*load_parts(path, variant))


def is_user_file(name: str) -> bool:
    """Whether a case's mechanism names a user's file (``path/to/name.py``) rather than a study mechanism."""
    return name.endswith(".py")


@lru_cache(maxsize=None)
def named_mechanism(name: str, variant: str = "seed") -> Mechanism:
    """A study mechanism by name, or a user's mechanism file by its path (``.py``), in a variant."""
    return load_mechanism(name, variant) if is_user_file(name) else mechanism(load_parameters(name, variant))


def as_mechanism(given: Mechanism | ParameterSet) -> Mechanism:
    """A :class:`Mechanism`; a study mechanism's parameter set stands for its mechanism."""
    if isinstance(given, ParameterSet):
        return mechanism(given)
    if not isinstance(given, Mechanism):
        raise TypeError(f"expected a study.Mechanism (a description with its parameter set) or a ParameterSet, got "
                        f"{type(given).__name__}")
    return given


def builder(ps: ParameterSet, coordinates: str = "relative") -> MechanismBuilder:
    """The body-level equations' builder of a parameter set in a coordinate set."""
    return lower(description(ps), coordinates)


def equations(ps: ParameterSet, coordinates: str = "relative") -> EquationsOfMotion:
    """Compiled equations of motion of a parameter set ('relative' or 'absolute' coordinates)."""
    return mechanism(ps).equations(coordinates)


def load(name: str, variant: str = "seed", coordinates: str = "relative") -> tuple[ParameterSet, EquationsOfMotion]:
    """Parameter set and compiled equations of a mechanism variant."""
    ps = load_parameters(name, variant)
    return ps, equations(ps, coordinates)


def on_branch(ps: ParameterSet, q: np.ndarray) -> bool:
    """Whether relative coordinates q lie on the description's assembly branch (True without one)."""
    return _on_branch(description(ps), q)


def _on_branch(d: Description, q: np.ndarray) -> bool:
    return d.branch is None or _branch_value(d, q) > 0


def _branch_value(d: Description, q: np.ndarray) -> float:
    """The description's branch condition evaluated at q (> 0 on the branch)."""
    expr = d.branch[0].xreplace({getattr(d.p, k): float(v) for k, v in d.values.items()})
    return float(sp.lambdify([list(d.q)], expr, "math")(list(map(float, q))))


def initial_guess(ps: ParameterSet) -> tuple[np.ndarray, np.ndarray]:
    """Newton's start (q, qd): the module's ``initial_guess(ps)`` if it has one, else the printed q(0), qd(0).

    Raises ValueError when the guess's length is not the description's number of coordinates.
    """
    mod = module(ps.mechanism)
    if hasattr(mod, "initial_guess"):
        q, qd = (np.asarray(v, dtype=float) for v in mod.initial_guess(ps))
    else:
        q, qd = np.array(ps.initial.printed_q, dtype=float), np.array(ps.initial.printed_qd, dtype=float)
    n = len(description(ps).coordinate_names)
    if q.shape != (n,) or qd.shape != (n,):
        raise ValueError(f"{ps.mechanism} (variant {ps.variant}): the initial guess has {q.size} positions and "
                         f"{qd.size} rates, the description has {n} coordinates")
    return q, qd


def initial_state(ps: ParameterSet, eom: EquationsOfMotion | None = None) -> ConsistentState:
    """Consistent q(0), qd(0) (relative coordinates) from the parameter file, checked against its branch.

    Newton starts from the printed q(0) with the independent coordinates replaced by the
    specified values (``[initial_conditions.consistent]``). A description whose size is a parameter
    (its number of coordinates follows the parameter set) provides ``initial_guess(ps) -> (q, qd)``
    in its module, which replaces the printed q(0).
    """
    m = mechanism(ps)
    return m.initial_state() if eom is None else consistent_state(m.description, ps, eom, m.guess)


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
    if not _on_branch(d, state.q):
        expr, label = d.branch
        raise InitialConditionError(
            f"{d.name}: Newton from {start} converged to q = {state.q}, which is not on the "
            f"assembly branch '{label}' (the parameter file's '{ic.branch}'): its condition {expr} > 0 is "
            f"{_branch_value(d, state.q):.6g} there; change the printed q(0) or the guess")
    return state
