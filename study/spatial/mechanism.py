"""A spatial mechanism: a :class:`~study.spatial.description.SpatialDescription` with its initial state by body, what
every engine takes, as :class:`study.Mechanism` is for a planar description.

The one public way to a spatial mechanism::

    d = study.spatial.SpatialDescription("crank")
    ...                                                   # bodies, joints, loads (study.spatial.description)
    mech = study.spatial.SpatialMechanism(d, positions={"crank": (0, 0.1, 0.16), ...},
                                          angular_velocities={"crank": (-6.28, 0, 0)})
    study.run(mech, study.InHouse(...), t_end)            # or study.Exudyn(h=...), or study.validate(mech, ...)

The initial state is given per body (:func:`study.spatial.initial.initial_state`): centres, Euler parameters,
angular velocities in the 'global' or the 'body' frame (a body left out turns as the joints make it), centres'
velocities. :class:`SpatialMechanism` is a :class:`study.Mechanism` of ``kind`` 'spatial' (the engines dispatch on
the kind): ``equations()`` are the spatial equations (:func:`study.spatial.spatial_equations`, in the
description's own coordinates, r and p per body), ``initial_state()`` the consistent state. A planar description is
refused here by name, as a spatial one is by :class:`study.Mechanism`: neither is run as the other.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from types import MappingProxyType
from typing import ClassVar, Mapping, Sequence

import numpy as np

from study.model.eom import EquationsOfMotion
from study.model.initial_state import ConsistentState
from study.model.mechanism import Mechanism
from study.params import InitialConditions, ParameterSet, values_class
from study.spatial.description import FRAMES, SpatialDescription, spatial_only
from study.spatial.elements import SpatialDescriptionError
from study.spatial.equations import spatial_equations
from study.spatial.initial import initial_state

SOURCE = "given in code (study.spatial.SpatialMechanism(description, positions=..., ...))"
COORDINATES = "relative"   # a spatial description has one coordinate set: r and p of every body


def _plain(given: Mapping[str, Sequence[float]] | None, what: str) -> dict[str, list[float]]:
    """A mapping body -> vector as plain floats (the values are checked by the initial state)."""
    if given is None:
        return {}
    if not isinstance(given, Mapping):
        raise SpatialDescriptionError(f"{what} = {given!r} must be a mapping from body names to vectors")
    try:
        return {str(k): [float(x) for x in v] for k, v in given.items()}
    except (TypeError, ValueError):
        raise SpatialDescriptionError(f"{what} = {given!r}: every value must be a vector of numbers") from None


def _parameters(name: str, start: dict) -> ParameterSet:
    """The parameter set of a spatial mechanism: no values (they are in the description), the start as given."""
    initial = InitialConditions(printed_q=(), printed_qd=(), printed_source=SOURCE, independent=(), q_independent=(),
                                qd_independent=(), branch="", source=SOURCE)
    canonical = json.dumps({"mechanism": name, "start": start}, sort_keys=True)
    return ParameterSet(mechanism=name, variant="seed", values=values_class(name, [])(), units=MappingProxyType({}),
                        sources=MappingProxyType({}), initial=initial, variant_note="",
                        path=Path(f"{name} (parameters given in code)"),
                        sha256=hashlib.sha256(canonical.encode()).hexdigest())


@dataclasses.dataclass(frozen=True, eq=False, init=False)
class SpatialMechanism(Mechanism):
    """A spatial description with its initial state by body (module docstring): ``positions`` (every body's centre
    [m]), ``orientations`` (Euler parameters, default no rotation), ``angular_velocities`` [rad/s] in ``frame``
    ('global' or 'body'), ``velocities`` (centres' [m/s], default zero)."""

    kind: ClassVar[str] = "spatial"

    def __init__(self, description: SpatialDescription, *, positions: Mapping[str, Sequence[float]],
                 orientations: Mapping[str, Sequence[float]] | None = None,
                 angular_velocities: Mapping[str, Sequence[float]] | None = None, frame: str = "global",
                 velocities: Mapping[str, Sequence[float]] | None = None):
        d = spatial_only(description)
        if frame not in FRAMES:
            raise SpatialDescriptionError(f"{d.name}: frame = {frame!r} of the angular velocities must be one of "
                                          f"{FRAMES}")
        start = {"positions": _plain(positions, "positions"), "orientations": _plain(orientations, "orientations"),
                 "angular_velocities": _plain(angular_velocities, "angular_velocities"), "frame": frame,
                 "velocities": _plain(velocities, "velocities")}
        for key, value in (("description", d), ("parameters", _parameters(d.name, start)), ("guess", None),
                           ("_equations", {}), ("start", start)):
            object.__setattr__(self, key, value)

    def equations(self, coordinates: str = COORDINATES) -> EquationsOfMotion:
        """The spatial equations (r and p of every body; the only coordinate set of a spatial description)."""
        if coordinates != COORDINATES:
            raise ValueError(f"{self.name}: coordinates = {coordinates!r}: a spatial mechanism has one coordinate set, "
                             f"{COORDINATES!r} (every body's centre r and Euler parameters p)")
        if coordinates not in self._equations:
            self._equations[coordinates] = spatial_equations(self.description)
        return self._equations[coordinates]

    def initial_state(self) -> ConsistentState:
        """The consistent q(0), qd(0) of the start given by body (:func:`study.spatial.initial.initial_state`)."""
        if "state" not in self._equations:
            eom = self.equations()
            q, qd = initial_state(self.description, eom, **self.start)
            self._equations["state"] = ConsistentState(
                q=q, qd=qd, iterations=0, phi_residual=float(np.max(np.abs(eom.phi(q)), initial=0.0)),
                velocity_residual=float(np.max(np.abs(eom.phi_q(q) @ qd), initial=0.0)), newton_history=())
        return self._equations["state"]
