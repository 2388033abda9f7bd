"""A parameter set given in code: a description's own parameter values and an initial state by coordinate name.

The study's mechanisms keep their parameters in TOML files with units and provenance (:mod:`study.params`). A user's
mechanism may instead pass numbers, as PyDy and Exudyn users do::

    study.Mechanism(d, q0={"th": 1.0}, qd0={"th": 0.0})

The coordinates named in ``q0`` are held at the given values while Newton solves the constraints for the others
(the independent coordinates); ``qd0`` gives their rates (0 for a coordinate it leaves out), and the other rates
follow from the velocity constraints. Every name and value is checked here, before any equation is derived.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import numbers
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

from study.params import InitialConditions, ParameterSet, values_class

SOURCE = "given in code (study.Mechanism(description, q0=..., qd0=...))"


def _state(where: str, given: Any, names: tuple[str, ...]) -> dict[str, float]:
    """A state by coordinate name, checked: a mapping of known names to finite numbers."""
    if not isinstance(given, Mapping):
        raise ValueError(f"{where} = {given!r} must be a mapping from coordinate names to numbers, e.g. "
                         f"{where}={{{names[0]!r}: 0.0}}; the coordinates are {', '.join(names)}")
    out = {}
    for name, value in given.items():
        if name not in names:
            raise ValueError(f"{where}[{name!r}]: no coordinate of that name; the coordinates are {', '.join(names)}")
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
            raise ValueError(f"{where}[{name!r}] = {value!r} must be a finite number")
        out[name] = float(value)
    return out


def inline_parameters(name: str, values: Mapping[str, float], coordinate_names: tuple[str, ...],
                      q0: Mapping[str, float], qd0: Mapping[str, float] | None = None) -> ParameterSet:
    """The parameter set of a mechanism whose values and initial state are given in code (see the module docstring).

    Raises ValueError naming the state, the coordinate or the value that is wrong."""
    names = tuple(coordinate_names)
    q = _state("q0", q0, names)
    if not q:
        raise ValueError(f"q0 = {{}} names no coordinate: give the independent coordinates' values (of "
                         f"{', '.join(names)})")
    qd = _state("qd0", {} if qd0 is None else qd0, names)
    extra = sorted(set(qd) - set(q))
    if extra:
        raise ValueError(f"qd0 names {', '.join(extra)}, which q0 does not: the rates given are those of the "
                         f"independent coordinates, the ones q0 names ({', '.join(q)})")
    independent = tuple(names.index(k) for k in q)
    initial = InitialConditions(
        printed_q=tuple(q.get(k, 0.0) for k in names), printed_qd=tuple(qd.get(k, 0.0) for k in names),
        printed_source=SOURCE, independent=independent, q_independent=tuple(q.values()),
        qd_independent=tuple(qd.get(k, 0.0) for k in q), branch="", source=SOURCE)
    numbers_only = {k: float(v) for k, v in values.items()}
    canonical = json.dumps({"mechanism": name, "values": numbers_only, "initial": dataclasses.asdict(initial)},
                           sort_keys=True)
    return ParameterSet(mechanism=name, variant="seed", values=values_class(name, list(numbers_only))(**numbers_only),
                        units=MappingProxyType({}), sources=MappingProxyType(dict.fromkeys(numbers_only, SOURCE)),
                        initial=initial, variant_note="", path=Path(f"{name} (parameters given in code)"),
                        sha256=hashlib.sha256(canonical.encode()).hexdigest())
