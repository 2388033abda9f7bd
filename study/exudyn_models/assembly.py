"""What the element handlers share while an Exudyn model is built (:class:`Assembly`), and what the build returns
(:class:`Built`: the model, its laws and frictions, and what the result mapping needs to read it back)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from study.exudyn_models.building import BodyState, Model
from study.exudyn_models.guards import RecordedFriction
from study.exudyn_models.kinematics import Kinematics
from study.exudyn_models.load_law import Readers
from study.model import Mechanism
from study.model.joints import GROUND, Description

Array = np.ndarray


@dataclass
class Built:
    """The built Exudyn model of a mechanism, with what its result mapping (:mod:`study.exudyn_models.mapping`)
    reads: the load laws, the potentials, the frictions, the prismatic joints' normals and the reference q."""

    mech: Mechanism
    d: Description
    kin: Kinematics
    model: Model
    friction: str
    eps: float
    loads_jacobian: int
    configuration: str = "python"
    laws: dict = field(default_factory=dict)          # load name -> Law
    evaluation: dict = field(default_factory=dict)    # law name -> how Exudyn evaluates it
    potentials: dict = field(default_factory=dict)    # potential name -> Law (energy)
    frictions_by_contact: dict = field(default_factory=dict)
    frictions_by_pin: dict = field(default_factory=dict)
    normals: dict = field(default_factory=dict)       # prismatic joint -> n in the guide's body frame
    q0: Array = None                                  # the relative coordinates of the reference configuration

    @property
    def frictions(self) -> list[RecordedFriction]:
        return [*self.frictions_by_contact.values(), *self.frictions_by_pin.values()]


class Assembly:
    """The model being built: the parameter values (:meth:`val`), the markers made so far, one per (body, point)
    (:meth:`marker`, :meth:`com`), the bodies' reference angles (``refs``) and the live readers of the
    description's inputs (``readers``, made by :meth:`read_inputs` once the joints' markers exist)."""

    def __init__(self, built: Built, states: dict[str, BodyState]):
        self.built, self.model, self.d, self.subs = built, built.model, built.d, built.kin.subs
        self.states = states
        self.refs = {b: states[b].angle for b in self.d.bodies}
        self.markers: dict[tuple[str, str], int] = {}
        self.readers: Readers | None = None

    def val(self, e) -> float:
        """A parameter expression's value."""
        return float(sp.sympify(e).xreplace(self.subs))

    def marker(self, body: str, point: str) -> int:
        """The marker at a body's (or the ground's) named point."""
        if (body, point) not in self.markers:
            xy = self.d.ground_points[point] if body == GROUND else self.d.bodies[body].points[point]
            self.markers[(body, point)] = self.model.marker(body, (self.val(xy[0]), self.val(xy[1])))
        return self.markers[(body, point)]

    def com(self, body: str) -> int:
        """The marker at a body's centre of mass."""
        key = (body, "__com__")
        if key not in self.markers:
            self.markers[key] = self.model.marker(body, (0.0, 0.0))
        return self.markers[key]

    def read_inputs(self) -> None:
        """Markers at the description's input points, and the live readers of every input."""
        for inp in self.d.inputs.values():
            if inp.point is not None:
                self.marker(inp.body, inp.point)
        self.readers = Readers(self.model, self.markers, self.refs)
