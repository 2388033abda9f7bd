"""The study's mechanisms: a registry of describe functions, name -> :class:`Entry`; the spatial ones in
:data:`study.spatial.catalogue.SPATIAL` (:func:`named_mechanism` looks in both).

A study mechanism ``name`` is a parameter file ``reference/<name>.toml`` (with provenance, :mod:`study.params`) plus
an entry of :data:`CATALOGUE`: its module ``study.mechanisms.<name>`` gives ``describe(ps) -> Description``, the
``PARAMETERS`` the description reads, its ``LABEL``, and optionally ``initial_guess(ps)`` (Newton's start),
``COORDINATE_UNIT`` and ``TIME_SCALE``. :func:`named_mechanism` builds the :class:`study.model.Mechanism` of a name
and variant from the registry and the packaged parameter file. Nothing else is per-mechanism code: the equations in
either coordinate set, the compiled kernels, the Exudyn model and the joint reactions are all generated from the
description. The catalogue computes nothing itself (no solver): the consistent initial state is the model's
(:mod:`study.model.initial_state`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from types import MappingProxyType, ModuleType
from typing import Callable, Mapping

import numpy as np

from study.mechanisms import (a01_pendulum, andrews, exudyn_slider_crank, exudyn_slider_crank_floating, four_bar,
                              n_four_bar, pin_pendulum, quick_return, slider_crank, slider_crank_pins)
from study.model import EquationsOfMotion, Mechanism
from study.model.builder import MechanismBuilder
from study.model.coordinates import lower
from study.model.initial_state import ConsistentState
from study.model.joints import Description
from study.model.mechanism import consistent_state, on_branch as _on_branch
from study.params import (ParameterError, ParameterSet, available_mechanisms, available_variants,
                          check_parameter_names, load_parameters)
from study.spatial.catalogue import SPATIAL
from study.user_mechanism import load_mechanism


@dataclass(frozen=True)
class Entry:
    """One study mechanism: how to describe it from its parameter set, and what is known of it by name."""

    describe: Callable[[ParameterSet], Description]
    parameters: tuple[str, ...]        # the parameter file's entries the description reads, no more, no less
    label: str                         # human-readable name
    initial_guess: Callable[[ParameterSet], tuple] | None = None   # Newton's start (q, qd); None: the printed q(0)
    coordinate_unit: str = "rad"       # unit of the relative coordinates
    time_scale: float = 1.0            # characteristic time of the motion [s]


def _entry(mod: ModuleType) -> Entry:
    return Entry(mod.describe, tuple(mod.PARAMETERS), mod.LABEL, getattr(mod, "initial_guess", None),
                 getattr(mod, "COORDINATE_UNIT", "rad"), float(getattr(mod, "TIME_SCALE", 1.0)))


#: name -> entry, one per description module.
CATALOGUE: Mapping[str, Entry] = MappingProxyType({
    mod.__name__.rpartition(".")[2]: _entry(mod)
    for mod in (a01_pendulum, andrews, exudyn_slider_crank, exudyn_slider_crank_floating, four_bar, n_four_bar,
                pin_pendulum, quick_return, slider_crank, slider_crank_pins)})


def entry(name: str) -> Entry:
    """The catalogue's entry of a mechanism (a ParameterError, a ValueError, naming the valid choices)."""
    if name not in CATALOGUE:
        raise ParameterError(f"unknown mechanism {name!r}; valid choices: {', '.join(CATALOGUE)} (spatial: "
                             f"{', '.join(SPATIAL)})")
    return CATALOGUE[name]


def description(ps: ParameterSet) -> Description:
    """The joint-level description of a parameter set's mechanism, once the set is checked to hold exactly the
    parameters the description reads (ParameterError naming the missing and unknown ones)."""
    known = entry(ps.mechanism)
    check_parameter_names(ps, known.parameters)
    return known.describe(ps)


def label(name: str) -> str:
    """Human-readable name of a mechanism."""
    return entry(name).label


def coordinate_unit(name: str) -> str:
    """Unit of a mechanism's relative coordinates (default 'rad')."""
    return entry(name).coordinate_unit


def time_scale(name: str) -> float:
    """Characteristic time of a mechanism's motion [s] (default 1 s).

    Generic checks that run every mechanism scale their horizons and fixed steps by it, so a fast
    mechanism (a benchmark over milliseconds) is run over a comparable part of its motion.
    """
    return entry(name).time_scale


def constraint_unit(name: str) -> str:
    """Unit of a mechanism's constraint rows: 'm' (joint gaps), 'rad', or 'm, rad' when mixed."""
    rows = equations(parameters(name)).constraint_names
    units = sorted({"rad" if r.endswith("_angle") else "m" for r in rows})
    return ", ".join(units)


_MECHANISMS: dict[tuple, Mechanism] = {}


def mechanism(ps: ParameterSet) -> Mechanism:
    """The study's mechanism of a parameter set (its entry's ``describe`` and ``initial_guess``)."""
    key = (ps.mechanism, ps.variant, ps.sha256, ps.values)   # values too: a replaced parameter set keeps its sha256
    if key not in _MECHANISMS:
        _MECHANISMS[key] = Mechanism(description(ps), ps, initial_guess(ps)[0])
    return _MECHANISMS[key]


def is_user_file(name: str) -> bool:
    """Whether a case's mechanism names a user's file (``path/to/name.py``) rather than a study mechanism."""
    return name.endswith(".py")


def names() -> tuple[str, ...]:
    """Every study mechanism's name: the planar ones with a parameter file, then the spatial ones."""
    return (*available_mechanisms(), *SPATIAL)


def variants(name: str) -> tuple[str, ...]:
    """The variants of a study mechanism (a spatial one has its one start, 'seed')."""
    return ("seed",) if name in SPATIAL else tuple(available_variants(name))


@lru_cache(maxsize=None)
def named_mechanism(name: str, variant: str = "seed") -> Mechanism:
    """A study mechanism by name (its registry entry and packaged parameter file, or the spatial registry's), or a
    user's mechanism file by its path (``.py``), in a variant."""
    if is_user_file(name):
        return load_mechanism(name, variant)
    if name in SPATIAL:
        if variant not in variants(name):
            raise ParameterError(f"variant = {variant!r} is not a variant of the spatial mechanism {name}; valid "
                                 f"choices: {', '.join(variants(name))}")
        return SPATIAL[name]()
    return mechanism(parameters(name, variant))


def parameters(name: str, variant: str = "seed") -> ParameterSet:
    """A study mechanism's packaged parameter set, checked with every other problem of its file against the
    parameters its description reads."""
    return load_parameters(name, variant, required=entry(name).parameters)


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
    ps = parameters(name, variant)
    return ps, equations(ps, coordinates)


def on_branch(ps: ParameterSet, q: np.ndarray) -> bool:
    """Whether relative coordinates q lie on the description's assembly branch (True without one)."""
    return _on_branch(description(ps), q)


def initial_guess(ps: ParameterSet) -> tuple[np.ndarray, np.ndarray]:
    """Newton's start (q, qd): the entry's ``initial_guess(ps)`` if it has one, else the printed q(0), qd(0).

    Raises ValueError when the guess's length is not the description's number of coordinates.
    """
    guess = entry(ps.mechanism).initial_guess
    if guess is not None:
        q, qd = (np.asarray(v, dtype=float) for v in guess(ps))
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
