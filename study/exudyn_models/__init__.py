"""Independent Exudyn models of the study's mechanisms (the only package that imports ``exudyn``).

Each mechanism module exposes ``run(ps, t_end, h, solver='index3', output_step=None,
friction='regularized', eps=...) -> study.results.SimulationResult``. The models are built from the
parameter set's values and the bodies' kinematics only; the in-house equations of motion are used
for nothing but the consistent initial state and for evaluating the in-house Phi on Exudyn's
coordinates (so both codes are compared like for like).

Modules
-------
common
    Solver settings, solver-name validation, sensors -> arrays, the reaction-force guard, CPU timing.
slider_crank
    Mechanism A (crank, rod, slider on a horizontal guide with Coulomb friction).
quick_return
    Mechanism B (crank, rocker, connecting rod, sliding block, ram).
"""

from study.exudyn_models import quick_return, slider_crank
from study.exudyn_models.common import (
    DEFAULT_EPS,
    EXPLICIT_SOLVERS,
    FRICTION_MODES,
    IMPLICIT_SOLVERS,
    ExudynModelError,
    ExudynSolverError,
    exudyn_version,
)

MODELS = {"slider_crank": slider_crank, "quick_return": quick_return}


def run(ps, t_end, h, **kwargs):
    """Dispatch to ``MODELS[ps.mechanism].run`` (see the mechanism modules for the arguments)."""
    if ps.mechanism not in MODELS:
        raise ValueError(f"no Exudyn model for mechanism {ps.mechanism!r}; valid choices: {', '.join(MODELS)}")
    return MODELS[ps.mechanism].run(ps, t_end, h, **kwargs)


__all__ = [
    "DEFAULT_EPS",
    "EXPLICIT_SOLVERS",
    "FRICTION_MODES",
    "IMPLICIT_SOLVERS",
    "MODELS",
    "ExudynModelError",
    "ExudynSolverError",
    "exudyn_version",
    "quick_return",
    "run",
    "slider_crank",
]
