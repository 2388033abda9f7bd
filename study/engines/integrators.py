"""The in-house run's integrator, as an object: scipy's adaptive ones (``rtol``, ``atol``, ``min_step``), RK4 and the
index-3 ALI3P (a fixed step ``h``). The names are :data:`study.run_arguments.INTEGRATOR_NAMES`; each object flattens to
the keyword arguments of :func:`study.simulate` (``arguments``) and back (:func:`integrator_from`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from study.run_arguments import DEFAULT_ATOL, DEFAULT_RTOL


class Integrator:
    """An integrator: its ``name`` and its settings as :func:`study.simulate`'s keyword arguments (checked where
    the run specification is made, :class:`study.engines.inhouse.InHouse`)."""

    name: ClassVar[str] = ""

    def arguments(self) -> dict:
        raise NotImplementedError


@dataclass(frozen=True)
class Adaptive(Integrator):
    """scipy's adaptive integrators: relative and absolute tolerance, smallest step [s] (None: ``min_step_fraction``
    of the horizon, reference/tolerances.toml)."""

    rtol: float = DEFAULT_RTOL
    atol: float = DEFAULT_ATOL
    min_step: float | None = None
    takes: ClassVar[tuple[str, ...]] = ("rtol", "atol", "min_step")

    def arguments(self) -> dict:
        return {"integrator": self.name, "rtol": self.rtol, "atol": self.atol, "min_step": self.min_step, "step": None}


@dataclass(frozen=True)
class FixedStep(Integrator):
    """A fixed step ``h`` [s]."""

    h: float

    def arguments(self) -> dict:
        return {"integrator": self.name, "rtol": None, "atol": None, "min_step": None, "step": self.h}


@dataclass(frozen=True)
class RK45(Adaptive):
    """Dormand-Prince 5(4), scipy's default."""

    name: ClassVar[str] = "RK45"


@dataclass(frozen=True)
class RK23(Adaptive):
    """Bogacki-Shampine 3(2)."""

    name: ClassVar[str] = "RK23"


@dataclass(frozen=True)
class DOP853(Adaptive):
    """Dormand-Prince 8(5,3): the study's reference runs."""

    name: ClassVar[str] = "DOP853"


@dataclass(frozen=True)
class Radau(Adaptive):
    """Radau IIA of order 5 (implicit)."""

    name: ClassVar[str] = "Radau"


@dataclass(frozen=True)
class LSODA(Adaptive):
    """Adams / BDF with automatic stiffness detection."""

    name: ClassVar[str] = "LSODA"


@dataclass(frozen=True)
class RK4(FixedStep):
    """The classic fourth-order Runge-Kutta rule."""

    name: ClassVar[str] = "RK4"


@dataclass(frozen=True)
class ALI3P(FixedStep):
    """The index-3 augmented Lagrangian of Bayo and Ledesma (study.solver.index3), on the trapezoidal rule."""

    name: ClassVar[str] = "ALI3P"


INTEGRATORS: dict[str, type[Integrator]] = {c.name: c for c in (RK45, DOP853, RK23, Radau, LSODA, RK4, ALI3P)}


def integrator_from(flat: dict) -> Integrator:
    """The integrator of :func:`study.simulate`'s keyword arguments, already checked
    (:func:`study.run_arguments.check_arguments`); the keys it reads are removed from ``flat``."""
    cls = INTEGRATORS[flat.pop("integrator", "RK45")]
    step = flat.pop("step", None)
    given = {k: v for k in Adaptive.takes if (v := flat.pop(k, None)) is not None}
    return cls(h=step) if issubclass(cls, FixedStep) else cls(**given)
