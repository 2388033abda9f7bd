"""The in-house run specification: :class:`InHouse` = stabilization method, integrator, friction treatment, backend
and the run's bounds, checked when made (by :func:`study.run_arguments.check_arguments`, the one checker of a run's
arguments, and by what the compiled backend supports, ``study.fast.support``), and serialized as the keyword arguments
of :func:`study.simulate` (a case list's options)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from study.engines.friction import Default, Friction, friction_from
from study.engines.integrators import RK45, Integrator, integrator_from
from study.engines.spec import refuse_unknown
from study.fast.support import check_supported
from study.run_arguments import DEFAULT_OUTPUT_STEP, check_arguments
from study.solver.index3 import NAME as INDEX3
from study.solver.stabilization import (STABILIZATIONS, NoStabilization, Stabilization, make_stabilization,
                                        method_options)

#: The keys of an in-house run's dict besides its method's options (those are the method's fields).
KEYS = ("engine", "method", "integrator", "rtol", "atol", "min_step", "step", "friction", "friction_eps", "friction_sgn",
        "resistance_reading", "backend", "acceleration_solver", "output_step", "check", "max_evaluations",
        "max_output_bytes")


@dataclass(frozen=True)
class InHouse:
    """An in-house run: ``method`` (a :class:`study.solver.stabilization.Stabilization`, e.g. ``Baumgarte(omega=10)``),
    ``integrator`` (``study.engines.integrators``, e.g. ``DOP853(rtol=1e-10)`` or ``RK4(h=1e-3)``), ``friction``
    (``study.engines.friction``, e.g. ``Exact()``), ``backend`` ('reference' or 'compiled'), and the options of
    :func:`study.simulate` of the same names (``acceleration_solver`` None: 'multiplier', or the augmented Lagrangian
    for ALI3P). A combination the run would ignore or the backend cannot do is refused here, by name."""

    method: Stabilization = NoStabilization()
    integrator: Integrator = RK45()
    friction: Friction = Default()
    backend: str = "reference"
    acceleration_solver: str | None = None
    resistance_reading: str | None = None
    output_step: float = DEFAULT_OUTPUT_STEP
    check: bool = True
    max_evaluations: float | None = None
    max_output_bytes: float | None = None
    engine: ClassVar[str] = "inhouse"

    def __post_init__(self) -> None:
        for key, kind, example in (("method", Stabilization, "Baumgarte(omega=10)"),
                                   ("integrator", Integrator, "DOP853(rtol=1e-10)"), ("friction", Friction, "Exact()")):
            if not isinstance(getattr(self, key), kind):
                raise ValueError(f"InHouse: {key} = {getattr(self, key)!r} must be a {kind.__name__} object (e.g. "
                                 f"{example}); by name: InHouse.from_dict({{{key!r}: ...}})")
        self.checked()

    def arguments(self) -> dict[str, Any]:
        """The run as :func:`study.simulate`'s keyword arguments (the method as its object)."""
        return {"method": self.method, **self.integrator.arguments(), **self.friction.arguments(),
                **{f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in
                   ("method", "integrator", "friction")}}

    def checked(self, t_end: float | None = None, progress=None, names: dict | None = None) -> dict:
        """The checks of :func:`study.run_arguments.check_arguments` (with ``t_end``, those against the horizon too)
        and of the compiled backend's support; returns the numbers converted."""
        i, f = self.integrator.name, type(self.friction).__name__
        names = {"rtol": f"{i}.rtol", "atol": f"{i}.atol", "min_step": f"{i}.min_step", "step": f"{i}.h",
                 "friction_eps": f"{f}.eps", "friction_sgn": f"{f}.sgn"} if names is None else names
        given = check_arguments(**self.arguments(), t_end=t_end, variant=None, progress=progress, names=names)
        if self.backend == "compiled":   # before anything compiles: importing the compiled path compiles its kernels
            check_supported(i, self.solver(), progress)
        return given

    def solver(self) -> str:
        """The acceleration solver the run takes."""
        default = "augmented_lagrangian" if self.integrator.name == INDEX3 else "multiplier"
        return default if self.acceleration_solver is None else self.acceleration_solver

    def to_dict(self) -> dict[str, Any]:
        """A plain dict (numbers, text, lists; None left out): :meth:`from_dict` makes the same run of it."""
        method = type(self.method)
        if not dataclasses.is_dataclass(self.method) or STABILIZATIONS.get(self.method.name) is not method:
            raise ValueError(f"InHouse: method = {self.method!r} is not one of the study's methods "
                             f"({', '.join(STABILIZATIONS)}): a run with it cannot be written as a dict")
        options = {f.name: getattr(self.method, f.name) for f in dataclasses.fields(self.method)
                   if f.name in method_options(self.method.name)}
        flat = {"engine": self.engine, **self.arguments(), "method": self.method.name, **options}
        return {k: list(v) if isinstance(v, (tuple, np.ndarray)) else v for k, v in flat.items() if v is not None}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "InHouse":
        """The run of :func:`study.simulate`'s keyword arguments (a case list's options): ``method`` by name with its
        options as further keys (or a Stabilization object), ``integrator``, ``rtol``, ``step``, ``friction``,
        ``friction_eps``, ...; a key that is neither an argument nor an option of the method is refused by name."""
        flat = dict(d)
        if flat.pop("engine", cls.engine) != cls.engine:
            raise ValueError(f"engine = {d['engine']!r}: not an in-house run (InHouse is engine {cls.engine!r})")
        method = flat.pop("method", "none")
        options = {k: flat.pop(k) for k in list(flat) if k not in KEYS}
        if not isinstance(method, Stabilization) and method in STABILIZATIONS:
            refuse_unknown(f"method {method!r} nor of an in-house run", options, [*method_options(method), *KEYS[1:]])
        check_arguments(**{k: flat.get(k) for k in ("rtol", "atol", "step", "min_step", "friction_eps", "friction_sgn",
                                                    "acceleration_solver", "resistance_reading", "max_evaluations",
                                                    "max_output_bytes")},
                        method=method, integrator=flat.get("integrator", "RK45"), t_end=None, variant=None,
                        progress=None, friction=flat.get("friction", Default.name), backend=flat.get("backend", "reference"),
                        check=flat.get("check", True), output_step=flat.get("output_step", DEFAULT_OUTPUT_STEP))
        return cls(method=make_stabilization(method, **options), integrator=integrator_from(flat),
                   friction=friction_from(flat), **flat)
