"""The in-house run's friction treatment, as an object (``study.solver.friction``): the parameter set's own
(:class:`Default`, ``study.friction_default``), none, the exact stick/slip, the regularized sgn of width ``eps`` and
the plain sgn. Each flattens to the friction keywords of :func:`study.simulate` (``arguments``) and back
(:func:`friction_from`).

With friction, a result gains forces ``normal_<c>``, ``friction_<c>``, ``stick_<c>`` and energies
``work_friction_<c>`` per contact; joints with friction (pins: planar revolute joints, ``Description.revolute(...,
friction=, radius=)``, and spatial revolute and prismatic joints, ``SpatialDescription.friction``) follow the contacts
in these outputs (``normal_<pin>`` = |R| [N], ``friction_<pin>`` = the torque [N m] of a revolute joint or the force
[N] of a prismatic one on the joint's first body, ``eps`` read in rad/s or m/s, the unit of the joint's relative
rate), with every treatment on both backends. ``eps`` of 'regularized' and
'sign' is also the band |v_t| <= eps reported as apparent stick."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from study.run_arguments import DEFAULT_FRICTION
from study.solver.friction import DEFAULT_EPS


class Friction:
    """A friction treatment: its ``name`` (:func:`study.simulate`'s ``friction``) and its settings (checked where the
    run specification is made, :class:`study.engines.inhouse.InHouse`)."""

    name: ClassVar[str] = ""

    def arguments(self) -> dict:
        return {"friction": self.name, "friction_eps": getattr(self, "eps", None), "friction_sgn": getattr(self, "sgn", None)}


@dataclass(frozen=True)
class Default(Friction):
    """The parameter set's treatment of every friction entry; ``eps`` and ``sgn`` apply if it is one that takes them."""

    eps: float | None = None
    sgn: str | None = None
    name: ClassVar[str] = DEFAULT_FRICTION


@dataclass(frozen=True)
class NoFriction(Friction):
    """Every friction entry left out (named in the result's ``meta['friction_left_out']``)."""

    name: ClassVar[str] = "none"


@dataclass(frozen=True)
class Exact(Friction):
    """Event-located stick/slip."""

    name: ClassVar[str] = "exact"


@dataclass(frozen=True)
class Regularized(Friction):
    """sgn replaced by the smooth ``sgn`` ('tanh', 'sat', 'arctan', 'sqrt') of width ``eps`` [m/s; rad/s at a revolute
    joint]."""

    eps: float = DEFAULT_EPS
    sgn: str = "tanh"
    name: ClassVar[str] = "regularized"


@dataclass(frozen=True)
class Sign(Friction):
    """Paper 000's plain sgn; ``eps`` is the band |v_t| <= eps reported as apparent stick."""

    eps: float = DEFAULT_EPS
    name: ClassVar[str] = "sign"


FRICTIONS: dict[str, type[Friction]] = {c.name: c for c in (Default, NoFriction, Exact, Regularized, Sign)}


def friction_from(flat: dict) -> Friction:
    """The friction treatment of :func:`study.simulate`'s keyword arguments (None is 'none'), already checked
    (:func:`study.run_arguments.check_arguments`); the keys it reads are removed from ``flat``."""
    cls = FRICTIONS[flat.pop("friction", DEFAULT_FRICTION) or "none"]
    given = {k: v for k in ("eps", "sgn") if (v := flat.pop(f"friction_{k}", None)) is not None}
    return cls(**given)
