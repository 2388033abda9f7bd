"""The Exudyn run specification: :class:`Exudyn` = solver, fixed step ``h`` and the options of
:func:`study.exudyn_models.run` of the same names, checked when made (``study.exudyn_models.settings``; Exudyn is
imported then, not with this module)."""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass
from typing import Any, ClassVar

from study.engines.spec import refuse_unknown
from study.solver.friction import DEFAULT_EPS


@dataclass(frozen=True, kw_only=True)
class Exudyn:
    """An Exudyn run: ``solver`` ('index3', 'index2'), step ``h`` [s], ``output_step`` (a whole multiple of h; None:
    every step), ``friction`` ('regularized', 'none') of width ``eps``, ``configuration`` ('python', 'tuned'),
    ``ignore_singular``, ``linear_solver`` ('dense', 'sparse') and ``newton_tolerance`` (None: Exudyn's settings'
    NEWTON_TOLERANCE); see :func:`study.exudyn_models.run`."""

    h: float
    solver: str = "index3"
    output_step: float | None = None
    friction: str = "regularized"
    eps: float = DEFAULT_EPS
    configuration: str = "python"
    ignore_singular: bool = False
    linear_solver: str = "dense"
    newton_tolerance: float | None = None
    engine: ClassVar[str] = "exudyn"

    def __post_init__(self) -> None:
        valid_h = isinstance(self.h, numbers.Real) and not isinstance(self.h, bool) and math.isfinite(self.h) \
            and self.h > 0
        self.checked(self.h if valid_h else 1.0, output_step=False)   # one step: what does not depend on the horizon

    def options(self) -> dict[str, Any]:
        """The keyword arguments of :func:`study.exudyn_models.run` after ``t_end``."""
        from study.exudyn_models.settings import NEWTON_TOLERANCE

        options = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        return options | {"newton_tolerance": NEWTON_TOLERANCE if self.newton_tolerance is None else self.newton_tolerance}

    def checked(self, t_end: float, output_step: bool = True):
        """The checks of ``study.exudyn_models.settings.check_arguments`` over ``t_end``; returns the run's grid."""
        from study import arguments
        from study.exudyn_models.settings import check_arguments

        arguments.flag("ignore_singular", self.ignore_singular)
        o = self.options()
        return check_arguments(t_end, self.h, self.solver, self.output_step if output_step else None, self.friction,
                               self.eps, self.configuration, self.linear_solver, self.ignore_singular,
                               o["newton_tolerance"])

    def to_dict(self) -> dict[str, Any]:
        """A plain dict (None left out): :meth:`from_dict` makes the same run of it."""
        return {"engine": self.engine, **{k: v for k, v in dataclasses.asdict(self).items() if v is not None}}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Exudyn":
        """The run of :func:`study.exudyn_models.run`'s keyword arguments (a case list's options); an unknown key is
        refused by name."""
        flat = dict(d)
        if flat.pop("engine", cls.engine) != cls.engine:
            raise ValueError(f"engine = {d['engine']!r}: not an Exudyn run (Exudyn is engine {cls.engine!r})")
        refuse_unknown("an Exudyn run", flat, [f.name for f in dataclasses.fields(cls)])
        if "h" not in flat:
            raise ValueError("an Exudyn run needs h (its fixed step [s])")
        return cls(**flat)

