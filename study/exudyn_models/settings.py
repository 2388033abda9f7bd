"""The settings of an Exudyn run: solvers and configurations by name, argument checks, SimulationSettings.

Verified Exudyn 1.13.6 behaviour the Exudyn models rely on (see the docstrings where it matters):

* ``SimulationSettings.solution.file.write = False`` stops Exudyn from writing ``solution/`` into
  the working directory; sensors use ``storeInternal=True, writeToFile=False``.
* Internal sensor storage follows ``solution.sensors.writePeriod`` (default 0.01 s), so it is set
  below the step size: one stored row per step, plus the row at t = 0.
* Exudyn does not project initial velocities: every node gets consistent initial velocities.
* ``timeIntegration.adaptiveStep`` is True by default (the step is cut when Newton fails); it is
  switched off so that a run really uses the fixed step h (a failure raises instead).
* A joint reaction read inside a load user function (``GetObjectOutput``) is the *current Newton
  iterate*; at the first Newton iteration of every step and during the initial-acceleration solve
  the algebraic coordinates are exactly 0. :class:`ReactionGuard` handles that, and
  :func:`seed_reaction_guards` gives the initial-acceleration solve the consistent normal force.
* The initial-acceleration solve forms the quadratic-velocity term of the index-3 joint
  constraints by numerical differentiation (relative step 1e-7): the initial multipliers differ
  from an exact solve by a few 1e-7 of that term (zero at zero velocity).
* ``linearSolver.ignoreSingularJacobian`` has no effect with the sparse solver (EigenSparse): N-four-bar
  seed, index 3, 2 s, the sparse run with the flag is bit-identical to the one without (Exudyn documents
  the flag for dense matrices only), hence ``check_arguments`` refuses the combination.
* Explicit solvers refuse joint constraints with ``exudyn.ModelError`` ("SolverExplicit: explicit
  integrator detected object <n> which contains constraints that cannot be solved; aborting solver").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import exudyn as exu
import numpy as np

from study.solver.friction import DEFAULT_EPS  # noqa: F401  (default eps of the tanh friction sign [m/s]: the in-house one)

Array = np.ndarray

#: Implicit solvers of a run: 'index3' = GeneralizedAlpha with index-3 (position-level) constraints;
#: 'index2' = Newmark trapezoidal rule (beta = 1/4, gamma = 1/2) with index-2 (velocity-level)
#: constraints, i.e. Exudyn's TrapezoidalIndex2.
IMPLICIT_SOLVERS = ("index3", "index2")
#: Exudyn's explicit integrators. They are valid names only to document that Exudyn refuses them on
#: models with joint constraints: ``run`` raises Exudyn's own ``ModelError`` (see ExudynModelError).
EXPLICIT_SOLVERS = ("explicit_euler", "rk44", "dopri5")
SOLVERS = IMPLICIT_SOLVERS + EXPLICIT_SOLVERS

#: 'regularized': Coulomb friction -mu |N| tanh(v/eps) (and the resistance -F tanh(v/eps)) along a guide, and
#: -(mu r |R|_delta + T0) tanh(omega_rel/eps) in a revolute joint (study.exudyn_models.guards.PinFrictionTorque);
#: 'none': friction and resistance left out (the frictionless reference model).
FRICTION_MODES = ("regularized", "none")

#: GeneralizedAlpha spectral radius at infinity (Exudyn's default; damps the index-3 oscillation
#: of the multipliers while keeping second order).
SPECTRAL_RADIUS = 0.9
#: Newton tolerances (relative and absolute, Exudyn's residual norms); full Newton.
NEWTON_TOLERANCE = 1e-10
NEWTON_MAX_ITERATIONS = 25

#: Seeding of the reaction guard before the run: fixed-point iteration on the normal force of the
#: initial-acceleration solve, stopped at this relative change (a few hundred ulps) ...
SEED_TOLERANCE = 1e-13
#: ... or after this many iterations (the map contracts by ~mu * |tan| of the guide geometry, < 0.1
#: for the study's cases, so 40 iterations are far more than ever needed).
SEED_MAX_ITERATIONS = 40

#: The two Exudyn configurations of a run (``configuration`` of ``run``):
#: 'python': every state-dependent load law is a Python load user function, full Newton (Jacobian
#: every iteration), the load Jacobian differentiated numerically where a friction contact needs it;
#: 'tuned': what Exudyn's documentation and examples recommend for speed (symbolic user functions,
#: ``exudyn.symbolic``, instead of Python ones wherever Exudyn has an element whose user function sees
#: the law's inputs; modified Newton, i.e. the Jacobian reused while the iteration contracts). See
#: CONFIGURATION_DESCRIPTIONS and study.exudyn_models.loads for what stays Python and why.
CONFIGURATIONS = ("python", "tuned")
CONFIGURATION_DESCRIPTIONS = {
    "python": "load laws as Python user functions (LoadForceVector/LoadTorqueVector), full Newton",
    "tuned": "load laws as Exudyn symbolic user functions of connectors (no Python in the time loop) where "
             "Exudyn offers one, constant loads as plain loads, modified Newton (Jacobian reused); laws Exudyn "
             "cannot express that way, and the friction reading a joint reaction, stay Python user functions",
}

#: The linear solver of Newton's iteration (``linearSolver.solverType``; the older name
#: ``SimulationSettings.linearSolverType`` is deprecated in Exudyn 1.13): 'dense' = Exudyn's own dense
#: matrix inverse (EXUdense, Exudyn's default); 'sparse' = Eigen's SparseLU (EigenSparse), which Exudyn
#: recommends for larger systems (the N-four-bar at N = 40). Both solve the same Newton systems; the accepted
#: steps differ only as far
#: as the Newton tolerance lets them. ``linearSolver.ignoreSingularJacobian`` is implemented for the dense
#: solvers only (Exudyn's documentation of LinearSolverSettings), so ``ignore_singular`` is refused with
#: 'sparse' rather than silently not applied.
LINEAR_SOLVERS = ("dense", "sparse")
LINEAR_SOLVER_TYPES = {
    "dense": exu.LinearSolverType.EXUdense,
    "sparse": exu.LinearSolverType.EigenSparse,
}
LINEAR_SOLVER_DESCRIPTIONS = {
    "dense": "Exudyn EXUdense (dense matrix inverse, Exudyn's default)",
    "sparse": "Exudyn EigenSparse (Eigen SparseLU factorization)",
}

ExudynModelError = exu.ModelError
ExudynSolverError = exu.SolverError

SOLVER_TYPES = {
    "index3": exu.DynamicSolverType.GeneralizedAlpha,
    "index2": exu.DynamicSolverType.GeneralizedAlpha,   # + useIndex2Constraints, useNewmark (below)
    "explicit_euler": exu.DynamicSolverType.ExplicitEuler,
    "rk44": exu.DynamicSolverType.RK44,
    "dopri5": exu.DynamicSolverType.DOPRI5,
}

SOLVER_DESCRIPTIONS = {
    "index3": f"Exudyn GeneralizedAlpha, index-3 constraints, spectralRadius {SPECTRAL_RADIUS}, full Newton",
    "index2": "Exudyn GeneralizedAlpha with useNewmark (trapezoidal, beta 1/4, gamma 1/2) and "
              "useIndex2Constraints (= TrapezoidalIndex2), full Newton",
    "explicit_euler": "Exudyn ExplicitEuler (fails on joint constraints)",
    "rk44": "Exudyn RK44 (fails on joint constraints)",
    "dopri5": "Exudyn DOPRI5 (fails on joint constraints)",
}


def exudyn_version() -> str:
    return str(exu.__version__)


@dataclass(frozen=True)
class RunGrid:
    """The fixed time grid of a run: ``n_steps`` steps of ``h``; output every ``stride`` steps."""

    t_end: float
    h: float
    n_steps: int
    stride: int

    @property
    def output_indices(self) -> Array:
        return np.arange(0, self.n_steps + 1, self.stride)


def check_arguments(t_end: float, h: float, solver: str, output_step: float | None,
                    friction: str, eps: float, configuration: str = "python", linear_solver: str = "dense",
                    ignore_singular: bool = False, newton_tolerance: float = NEWTON_TOLERANCE) -> RunGrid:
    """Validate the arguments of a ``run`` and return its time grid.

    Raises
    ------
    ValueError
        Unknown solver, friction mode, configuration or linear solver (the message lists the valid
        choices), ``ignore_singular`` with the sparse linear solver, ``t_end <= 0``,
        ``h <= 0``, ``t_end`` not a whole number of steps, ``output_step`` not a positive whole
        multiple of ``h``, ``eps <= 0``, ``newton_tolerance`` not in (0, 1).
    """
    problems = []
    if solver not in SOLVERS:
        problems.append(f"unknown solver {solver!r}; valid choices: {', '.join(SOLVERS)}")
    if friction not in FRICTION_MODES:
        problems.append(f"unknown friction mode {friction!r}; valid choices: {', '.join(FRICTION_MODES)}")
    if configuration not in CONFIGURATIONS:
        problems.append(f"unknown Exudyn configuration {configuration!r}; valid choices: {', '.join(CONFIGURATIONS)}")
    if linear_solver not in LINEAR_SOLVERS:
        problems.append(f"unknown linear solver {linear_solver!r}; valid choices: {', '.join(LINEAR_SOLVERS)}")
    elif linear_solver == "sparse" and ignore_singular:
        problems.append("ignore_singular = True needs the dense linear solver (Exudyn implements "
                        "ignoreSingularJacobian for dense matrices only), not linear_solver = 'sparse'")
    if isinstance(newton_tolerance, bool) or not isinstance(newton_tolerance, (int, float)) \
            or not 0 < newton_tolerance < 1:
        problems.append(f"newton_tolerance = {newton_tolerance!r} must be a number in (0, 1)")
    for name, value in (("t_end", t_end), ("h", h), ("eps", eps)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            problems.append(f"{name} = {value!r} must be a finite number > 0")
    if problems:
        raise ValueError("; ".join(problems))
    n_steps = int(round(t_end / h))
    if n_steps < 1 or abs(n_steps * h - t_end) > 1e-9 * t_end:
        raise ValueError(f"t_end = {t_end!r} must be a whole number of steps h = {h!r} (t_end/h = {t_end / h!r})")
    stride = 1
    if output_step is not None:
        if isinstance(output_step, bool) or not isinstance(output_step, (int, float)) or not output_step > 0:
            raise ValueError(f"output_step = {output_step!r} must be a number > 0 (or None: every step)")
        stride = int(round(output_step / h))
        if stride < 1 or abs(stride * h - output_step) > 1e-9 * output_step:
            raise ValueError(f"output_step = {output_step!r} must be a whole multiple of h = {h!r}")
    return RunGrid(float(t_end), float(h), n_steps, stride)


def simulation_settings(grid: RunGrid, solver: str, loads_jacobian: int,
                        configuration: str = "python", ignore_singular: bool = False,
                        linear_solver: str = "dense", newton_tolerance: float = NEWTON_TOLERANCE) -> exu.SimulationSettings:
    """Exudyn settings of a fixed-step run; writes no files.

    Parameters
    ----------
    grid : RunGrid
    solver : one of SOLVERS
    loads_jacobian : {0, 2}
        ``timeIntegration.computeLoadsJacobian``: 2 differentiates the user-function loads
        numerically w.r.t. position and velocity coordinates (needed for the regularized friction:
        with 0, Newton diverges on tanh(v/1e-3) friction); 0 leaves loads out of the Jacobian
        (the translator says when that is enough: study.exudyn_models.friction.loads_jacobian).
    configuration : one of CONFIGURATIONS
        'tuned' switches on modified Newton with one Jacobian per step (``newton.useModifiedNewton``,
        ``modifiedNewtonJacUpdatePerStep``: the step's Jacobian is reused by its iterations, and
        recomputed early only if they stop contracting); the tolerances are the same, so a converged
        step passes the same residual test. Measured on the quick-return (smooth law, 2 s, h = 1e-4,
        index 3): full Newton 2 iterations and 2 Jacobians per step, 1.44 s; this setting 2 iterations
        and 1 Jacobian, 1.09 s; Exudyn's default modified Newton (Jacobian kept across steps) 7
        iterations per step at this tolerance, 1.80 s.
    ignore_singular : bool
        Exudyn's documented option for redundant constraints and singular poses
        (``linearSolver.ignoreSingularJacobian``, Exudyn example fourBarMechanism3D.py): a singular
        Newton matrix is factorized anyway, the redundant equations left out, instead of stopping.
    linear_solver : one of LINEAR_SOLVERS
        ``linearSolver.solverType`` (LINEAR_SOLVER_TYPES): 'dense' (EXUdense, Exudyn's default) or 'sparse'
        (EigenSparse, for larger systems).
    newton_tolerance : float
        Newton's relative and absolute tolerance (default NEWTON_TOLERANCE).
    """
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime = grid.t_end
    ti.numberOfSteps = grid.n_steps
    ti.verboseMode = 0
    ti.adaptiveStep = False                  # fixed step h; a Newton failure raises
    ti.newton.relativeTolerance = newton_tolerance
    ti.newton.absoluteTolerance = newton_tolerance
    ti.newton.useModifiedNewton = configuration == "tuned"   # else full Newton: Jacobian every iteration
    ti.newton.modifiedNewtonJacUpdatePerStep = configuration == "tuned"
    ti.newton.maxIterations = NEWTON_MAX_ITERATIONS
    ti.generalizedAlpha.spectralRadius = SPECTRAL_RADIUS
    ti.generalizedAlpha.computeInitialAccelerations = True
    if solver == "index2":
        ti.generalizedAlpha.useIndex2Constraints = True
        ti.generalizedAlpha.useNewmark = True
    ti.computeLoadsJacobian = loads_jacobian
    s.linearSolver.solverType = LINEAR_SOLVER_TYPES[linear_solver]
    s.linearSolver.ignoreSingularJacobian = bool(ignore_singular)
    # Reuse the sparse matrix's analyzed pattern (its column ordering) from one factorization to the next; Exudyn
    # analyzes again when the number of nonzeros changes, and when a factorization with the reused pattern fails.
    # Measured on the N-four-bar at N = 40 (index 3, h = 1e-3, 4 s): the same results bit for bit, about 15 % less
    # CPU (factorization was 39 % of the run). The dense solvers have no pattern.
    s.linearSolver.reuseAnalyzedPattern = linear_solver == "sparse"
    s.solution.file.write = False            # no solution/coordinatesSolution.txt
    s.solution.sensors.writePeriod = 0.5 * grid.h   # < h: store every step (storage follows writePeriod)
    return s
