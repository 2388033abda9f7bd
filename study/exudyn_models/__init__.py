"""Exudyn models of the study's mechanisms, generated from their joint-level descriptions (the only
package that imports ``exudyn``).

``run(ps, t_end, h, solver='index3', output_step=None, friction='regularized', eps=..., configuration='python',
ignore_singular=False, linear_solver='dense', newton_tolerance=NEWTON_TOLERANCE) ->
study.results.SimulationResult`` builds the Exudyn model of ``ps``'s description
(:mod:`study.exudyn_models.translate`); there is no per-mechanism code. The in-house equations of
motion are used for nothing but the consistent initial state and for evaluating the in-house Phi on
Exudyn's coordinates (so both codes are compared like for like); the load laws are evaluated from
Exudyn's own kinematics.

Modules
-------
settings
    Solvers and configurations by name, argument checks, SimulationSettings (and the verified Exudyn
    behaviour the models rely on).
building
    Model building blocks: planar rigid bodies, joints, loads, sensors read back as arrays.
guards
    The guarded joint-reaction reading in a user function, and the regularized friction along a guide and in a
    revolute joint (the law itself from its one home, study.laws.friction and study.kernels.signs).
solve
    Running a built model (SolveDynamic, CPU timing) and assembling the SimulationResult from its series.
translate
    Description -> Exudyn model -> SimulationResult, and the initial accelerations / multipliers; the modules of
    the translation (one handler module per element kind: elements, loads, friction; the result mapping: mapping,
    series, conventions; kinematics, load_law, assembly) are listed in its docstring.
"""

from study.exudyn_models.settings import (
    CONFIGURATIONS,
    DEFAULT_EPS,
    EXPLICIT_SOLVERS,
    FRICTION_MODES,
    IMPLICIT_SOLVERS,
    LINEAR_SOLVERS,
    ExudynModelError,
    ExudynSolverError,
    exudyn_version,
)
from study.exudyn_models.translate import initial_accelerations, run

__all__ = [
    "CONFIGURATIONS",
    "DEFAULT_EPS",
    "EXPLICIT_SOLVERS",
    "FRICTION_MODES",
    "IMPLICIT_SOLVERS",
    "LINEAR_SOLVERS",
    "ExudynModelError",
    "ExudynSolverError",
    "exudyn_version",
    "initial_accelerations",
    "run",
]
