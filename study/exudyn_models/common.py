"""Shared machinery of the Exudyn models: argument checks, solver settings, model building,
the guarded reaction-force reading, sensors -> arrays, CPU timing.

Everything Exudyn-specific the translator (:mod:`study.exudyn_models.translate`) needs that does not
depend on a description lives here.

Verified Exudyn 1.13.6 behaviour this module relies on (see the docstrings for where it matters):

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
* Explicit solvers refuse joint constraints with ``exudyn.ModelError`` ("SolverExplicit: explicit
  integrator detected object <n> which contains constraints that cannot be solved; aborting solver").
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.itemInterface import (
    LoadForceVector,
    LoadMassProportional,
    LoadTorqueVector,
    MarkerBodyMass,
    MarkerBodyPosition,
    MarkerBodyRigid,
    MarkerNodeCoordinate,
    NodePointGround,
    NodeRigidBody2D,
    ObjectConnectorCartesianSpringDamper,
    ObjectConnectorCoordinateSpringDamper,
    ObjectGround,
    ObjectJointPrismatic2D,
    ObjectJointRevolute2D,
    ObjectRigidBody2D,
    SensorNode,
    SensorObject,
)

from study import mechanisms
from study.results import SimulationResult, package_versions
from study.solver.friction import DEFAULT_EPS  # noqa: F401  (re-exported: exudyn_models.DEFAULT_EPS)

OVT = exu.OutputVariableType
esym = exu.symbolic
Array = np.ndarray

#: Implicit solvers of a run: 'index3' = GeneralizedAlpha with index-3 (position-level) constraints;
#: 'index2' = Newmark trapezoidal rule (beta = 1/4, gamma = 1/2) with index-2 (velocity-level)
#: constraints, i.e. Exudyn's TrapezoidalIndex2.
IMPLICIT_SOLVERS = ("index3", "index2")
#: Exudyn's explicit integrators. They are valid names only to document that Exudyn refuses them on
#: models with joint constraints: ``run`` raises Exudyn's own ``ModelError`` (see ExudynModelError).
EXPLICIT_SOLVERS = ("explicit_euler", "rk44", "dopri5")
SOLVERS = IMPLICIT_SOLVERS + EXPLICIT_SOLVERS

#: 'regularized': Coulomb friction -mu |N| tanh(v/eps) (and the resistance -F tanh(v/eps));
#: 'none': friction and resistance left out (the frictionless reference model).
FRICTION_MODES = ("regularized", "none")

#: Default velocity scale of the tanh regularization of the friction sign [m/s]: the in-house
#: default, ``study.solver.friction.DEFAULT_EPS`` (imported above), so both engines agree.

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
#: CONFIGURATION_DESCRIPTIONS and study.exudyn_models.translate for what stays Python and why.
CONFIGURATIONS = ("python", "tuned")
CONFIGURATION_DESCRIPTIONS = {
    "python": "load laws as Python user functions (LoadForceVector/LoadTorqueVector), full Newton",
    "tuned": "load laws as Exudyn symbolic user functions of connectors (no Python in the time loop) where "
             "Exudyn offers one, constant loads as plain loads, modified Newton (Jacobian reused); laws Exudyn "
             "cannot express that way, and the friction reading a joint reaction, stay Python user functions",
}

ExudynModelError = exu.ModelError
ExudynSolverError = exu.SolverError

_SOLVER_TYPES = {
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


# --------------------------------------------------------------------------------------------
# argument checks and settings
# --------------------------------------------------------------------------------------------
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
                    friction: str, eps: float, configuration: str = "python") -> RunGrid:
    """Validate the arguments of a ``run`` and return its time grid.

    Raises
    ------
    ValueError
        Unknown solver or friction mode (the message lists the valid choices), ``t_end <= 0``,
        ``h <= 0``, ``t_end`` not a whole number of steps, ``output_step`` not a positive whole
        multiple of ``h``, ``eps <= 0``.
    """
    problems = []
    if solver not in SOLVERS:
        problems.append(f"unknown solver {solver!r}; valid choices: {', '.join(SOLVERS)}")
    if friction not in FRICTION_MODES:
        problems.append(f"unknown friction mode {friction!r}; valid choices: {', '.join(FRICTION_MODES)}")
    if configuration not in CONFIGURATIONS:
        problems.append(f"unknown Exudyn configuration {configuration!r}; valid choices: {', '.join(CONFIGURATIONS)}")
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
                        configuration: str = "python", ignore_singular: bool = False) -> exu.SimulationSettings:
    """Exudyn settings of a fixed-step run; writes no files.

    Parameters
    ----------
    grid : RunGrid
    solver : one of SOLVERS
    loads_jacobian : {0, 2}
        ``timeIntegration.computeLoadsJacobian``: 2 differentiates the user-function loads
        numerically w.r.t. position and velocity coordinates (needed for the regularized friction:
        with 0, Newton diverges on tanh(v/1e-3) friction); 0 leaves loads out of the Jacobian
        (the translator says when that is enough: study.exudyn_models.translate.loads_jacobian).
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
    """
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime = grid.t_end
    ti.numberOfSteps = grid.n_steps
    ti.verboseMode = 0
    ti.adaptiveStep = False                  # fixed step h; a Newton failure raises
    ti.newton.relativeTolerance = NEWTON_TOLERANCE
    ti.newton.absoluteTolerance = NEWTON_TOLERANCE
    ti.newton.useModifiedNewton = configuration == "tuned"   # else full Newton: Jacobian every iteration
    ti.newton.modifiedNewtonJacUpdatePerStep = configuration == "tuned"
    ti.newton.maxIterations = NEWTON_MAX_ITERATIONS
    ti.generalizedAlpha.spectralRadius = SPECTRAL_RADIUS
    ti.generalizedAlpha.computeInitialAccelerations = True
    if solver == "index2":
        ti.generalizedAlpha.useIndex2Constraints = True
        ti.generalizedAlpha.useNewmark = True
    ti.computeLoadsJacobian = loads_jacobian
    s.linearSolver.ignoreSingularJacobian = bool(ignore_singular)
    s.solution.file.write = False            # no solution/coordinatesSolution.txt
    s.solution.sensors.writePeriod = 0.5 * grid.h   # < h: store every step (storage follows writePeriod)
    return s


# --------------------------------------------------------------------------------------------
# model building
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BodyState:
    """Centre-of-mass position, angle, COM velocity and angular velocity of a planar body."""

    position: tuple[float, float]
    angle: float
    velocity: tuple[float, float]
    omega: float


def unit(a: float) -> Array:
    return np.array([math.cos(a), math.sin(a)])


def unit_normal(a: float) -> Array:
    """d unit(a) / da = unit(a + pi/2)."""
    return np.array([-math.sin(a), math.cos(a)])


@dataclass
class Model:
    """An Exudyn system under construction, with named bodies, joints and sensors.

    Bodies are NodeRigidBody2D + ObjectRigidBody2D with the node at the centre of mass (so the
    inertia is the centroidal one); the node's reference configuration is the initial state
    (initial displacements 0) and its initial velocities are the given consistent ones.
    """

    SC: exu.SystemContainer = field(default_factory=exu.SystemContainer)
    mbs: exu.MainSystem = None
    ground: int = None
    bodies: dict = field(default_factory=dict)      # name -> (node, object, mass, inertia, reference[3])
    joints: dict = field(default_factory=dict)      # name -> (object, kind)
    sensors: dict = field(default_factory=dict)     # key -> sensor number
    symbolic: list = field(default_factory=list)    # symbolic user functions (kept alive for the run)
    pre_step: list = field(default_factory=list)    # callables (mbs, t) -> None
    post_step: list = field(default_factory=list)

    def __post_init__(self) -> None:
        self.mbs = self.SC.AddSystem()
        self.ground = self.mbs.AddObject(ObjectGround(referencePosition=[0.0, 0.0, 0.0]))

    def body(self, name: str, mass: float, inertia: float, state: BodyState, gravity: float) -> int:
        """Add a rigid body with gravity -gravity along y; sensors for coordinates and rates."""
        ref = [float(state.position[0]), float(state.position[1]), float(state.angle)]
        node = self.mbs.AddNode(NodeRigidBody2D(referenceCoordinates=ref, initialCoordinates=[0.0, 0.0, 0.0],
                                                initialVelocities=[float(state.velocity[0]),
                                                                   float(state.velocity[1]), float(state.omega)]))
        obj = self.mbs.AddObject(ObjectRigidBody2D(nodeNumber=node, mass=float(mass),
                                                   inertia=float(inertia)))
        self.mbs.AddLoad(LoadMassProportional(markerNumber=self.mbs.AddMarker(MarkerBodyMass(bodyNumber=obj)),
                                              loadVector=[0.0, -float(gravity), 0.0]))
        self.bodies[name] = (node, obj, float(mass), float(inertia), np.array(ref))
        for key, ovt in (("coordinates", OVT.Coordinates), ("rates", OVT.Coordinates_t),
                         ("accelerations", OVT.Coordinates_tt)):
            self.sensors[(name, key)] = self.mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=ovt,
                                                                      storeInternal=True, writeToFile=False))
        return obj

    def node(self, name: str) -> int:
        return self.bodies[name][0]

    def marker(self, body: str, local: tuple[float, float]) -> int:
        """A rigid marker at ``local`` (body frame, x along the body angle; 'ground' = global frame)."""
        obj = self.ground if body == "ground" else self.bodies[body][1]
        return self.mbs.AddMarker(MarkerBodyRigid(bodyNumber=obj, localPosition=[float(local[0]),
                                                                                 float(local[1]), 0.0]))

    def revolute(self, name: str, marker0: int, marker1: int) -> int:
        """RevoluteJoint2D; sensor 'Force' = force on the marker-0 body, global frame."""
        obj = self.mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[marker0, marker1]))
        self.joints[name] = (obj, "revolute")
        self.sensors[(name, "force")] = self.mbs.AddSensor(SensorObject(objectNumber=obj, outputVariableType=OVT.Force,
                                                                        storeInternal=True, writeToFile=False))
        return obj

    def prismatic(self, name: str, marker0: int, marker1: int, axis0=(1.0, 0.0), normal1=(0.0, 1.0)) -> int:
        """PrismaticJoint2D along ``axis0`` (marker 0's body frame), ``normal1`` the normal in marker 1's body
        frame, relative rotation locked.

        Sensor 'ForceLocal' = force on the marker-0 body in the marker-0 *body* frame (the constraint
        torque is not part of it).
        """
        obj = self.mbs.AddObject(ObjectJointPrismatic2D(markerNumbers=[marker0, marker1],
                                                        axisMarker0=[float(axis0[0]), float(axis0[1]), 0.0],
                                                        normalMarker1=[float(normal1[0]), float(normal1[1]), 0.0],
                                                        constrainRotation=True))
        self.joints[name] = (obj, "prismatic")
        self.sensors[(name, "force")] = self.mbs.AddSensor(SensorObject(objectNumber=obj,
                                                                        outputVariableType=OVT.ForceLocal,
                                                                        storeInternal=True, writeToFile=False))
        return obj

    def torque(self, marker: int, value: float | None = None, user: Callable | None = None) -> int:
        if user is None:
            return self.mbs.AddLoad(LoadTorqueVector(markerNumber=marker, loadVector=[0.0, 0.0, float(value)]))
        return self.mbs.AddLoad(LoadTorqueVector(markerNumber=marker, loadVector=[0.0, 0.0, 0.0],
                                                 loadVectorUserFunction=user))

    def force(self, marker: int, user: Callable | None = None, value: tuple[float, float] | None = None) -> int:
        """A global-frame force at a marker: constant ``value`` (fx, fy) or a user function."""
        if user is None:
            return self.mbs.AddLoad(LoadForceVector(markerNumber=marker,
                                                    loadVector=[float(value[0]), float(value[1]), 0.0]))
        return self.mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=[0.0, 0.0, 0.0],
                                                loadVectorUserFunction=user))

    def point_law(self, marker: int, law: Callable) -> int:
        """A force at a body marker given by ``law(t, (x, y), (vx, vy)) -> (fx, fy)`` (global frame) of the
        marker's global position and velocity, as an Exudyn symbolic user function (no Python per call).

        Built as ObjectConnectorCartesianSpringDamper between a ground marker at the origin (marker 0)
        and the body marker (marker 1), with zero stiffness and damping: its ``displacement`` is the
        marker's global position and ``velocity`` its velocity, and the force returned by the user
        function acts on marker 1 with the opposite sign (verified against LoadForceVector in
        tests/test_exudyn_tuned.py), so the function returns -law.
        """
        origin = self.mbs.AddMarker(MarkerBodyPosition(bodyNumber=self.ground, localPosition=[0.0, 0.0, 0.0]))
        obj = self.mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[origin, marker],
                                                                      stiffness=[0.0] * 3, damping=[0.0] * 3,
                                                                      offset=[0.0] * 3))

        def springForceUserFunction(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            fx, fy = law(t, (displacement[0], displacement[1]), (velocity[0], velocity[1]))
            return [-fx, -fy, 0.0 * fx]
        self._symbolic(obj, springForceUserFunction)
        return obj

    def angle_law(self, body: str, law: Callable) -> int:
        """A torque on a body given by ``law(t, angle, rate) -> torque`` of its absolute angle and angular
        velocity, as an Exudyn symbolic user function (no Python per call).

        Built as ObjectConnectorCoordinateSpringDamper between a ground coordinate (marker 0) and the
        node's rotation coordinate (marker 1), zero stiffness and damping: ``displacement`` is the
        rotation coordinate (the displacement from the node's reference angle, which is added here),
        ``velocity`` the angular velocity; the returned force acts on marker 1 with the opposite sign
        (verified against LoadTorqueVector in tests/test_exudyn_tuned.py), so the function returns -law.
        """
        node, _, _, _, ref = self.bodies[body]
        ground = self.mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=self.mbs.AddNode(NodePointGround()), coordinate=0))
        rotation = self.mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=2))
        obj = self.mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[ground, rotation], stiffness=0.0,
                                                                       damping=0.0))
        reference = float(ref[2])

        def springForceUserFunction(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            return -law(t, displacement + reference, velocity)
        self._symbolic(obj, springForceUserFunction)
        return obj

    def _symbolic(self, obj: int, function: Callable) -> None:
        sym = CreateSymbolicUserFunction(self.mbs, function, "springForceUserFunction", obj)
        self.mbs.SetObjectParameter(obj, "springForceUserFunction", sym)
        self.symbolic.append(sym)

    def joint_output(self, name: str, ovt=None) -> Array:
        obj, kind = self.joints[name]
        if ovt is None:
            ovt = OVT.Force if kind == "revolute" else OVT.ForceLocal
        return np.asarray(self.mbs.GetObjectOutput(obj, ovt), dtype=float)

    def node_output(self, name: str, ovt) -> Array:
        return np.asarray(self.mbs.GetNodeOutput(self.node(name), ovt), dtype=float)

    def assemble(self) -> None:
        if self.pre_step:
            self.mbs.SetPreStepUserFunction(_chained(self.pre_step))
        if self.post_step:
            self.mbs.SetPostStepUserFunction(_chained(self.post_step))
        self.mbs.Assemble()

    # --- stored sensor data -----------------------------------------------------------------
    def series(self, key, grid: RunGrid) -> Array:
        """Stored values of a sensor, shape (n_steps + 1, k), after checking the times are the step grid."""
        data = np.asarray(self.mbs.GetSensorStoredData(self.sensors[key]), dtype=float)
        expected = grid.h * np.arange(grid.n_steps + 1)
        if data.ndim != 2 or data.shape[0] != grid.n_steps + 1 or \
                np.max(np.abs(data[:, 0] - expected)) > 1e-9 * max(grid.t_end, 1.0):
            raise RuntimeError(f"sensor {key}: stored {data.shape[0] if data.ndim == 2 else 0} rows, expected one "
                               f"per step ({grid.n_steps + 1}) on the grid k*h")
        return data[:, 1:]

    def body_series(self, name: str, grid: RunGrid) -> tuple[Array, Array, Array]:
        """Global (x, y, angle), their rates and accelerations of a body, each (n_steps + 1, 3)."""
        ref = self.bodies[name][4]
        return (self.series((name, "coordinates"), grid) + ref, self.series((name, "rates"), grid),
                self.series((name, "accelerations"), grid))


# --------------------------------------------------------------------------------------------
# the guarded reaction reading and the regularized guide friction
# --------------------------------------------------------------------------------------------
def _chained(calls) -> Callable:
    """One pre/post-step user function calling every function of ``calls`` in order."""
    calls = tuple(calls)

    def run(mbs, t):
        for f in calls:
            f(mbs, t)
        return True
    return run


class ReactionGuard:
    """'Hybrid' reading of a joint reaction inside a load user function.

    ``read(mbs)`` returns the live value, i.e. the current Newton iterate of the multiplier. It is
    exactly 0 at the first Newton iteration of every step (the predictor resets the algebraic
    coordinates) and during the initial-acceleration solve. The guard then returns the value of the
    last accepted step instead (``accepted``, updated in a post-step function); otherwise it returns
    the live value, so the converged step uses the converged reaction (no lag).
    """

    def __init__(self, read: Callable[[exu.MainSystem], float]):
        self.read = read
        self.accepted: float | None = None
        self.calls = 0
        self.substitutions = 0

    def value(self, mbs) -> float:
        live = self.read(mbs)
        self.calls += 1
        if live == 0.0 and self.accepted is not None:
            self.substitutions += 1
            return self.accepted
        return live

    def accept(self, mbs, t=None) -> None:
        self.accepted = self.read(mbs)


class GuideFriction:
    """Regularized Coulomb friction plus constant resistance at a point sliding along a fixed axis.

    Tangential force on the slider at its point (along the unit ``axis``, global frame):
    ``coulomb = -mu |N| tanh(v/eps)``, ``resistance = -F tanh(v/eps)``, with v = axis . (velocity of
    the slider point, from the point's marker) and N the guide's normal reaction from ``guard``. The
    values of the last user-function call of each step (the converged residual evaluation) are recorded
    in ``history`` (one row per step plus the initial-acceleration solve at t = 0):
    [N used, v, coulomb, resistance].
    """

    def __init__(self, model: Model, marker: int, axis, guard: ReactionGuard, mu: float, resistance: float,
                 eps: float):
        self.marker = marker
        self.axis = (float(axis[0]), float(axis[1]))
        self.guard = guard
        self.mu, self.resistance, self.eps = float(mu), float(resistance), float(eps)
        self.last = (float("nan"),) * 4
        self.history: list[tuple[float, ...]] = []
        model.pre_step.append(self._pre_step)
        model.post_step.append(self._post_step)

    def __call__(self, mbs, t, load_vector):
        vel = mbs.GetMarkerOutput(self.marker, OVT.Velocity)
        v = self.axis[0] * vel[0] + self.axis[1] * vel[1]
        n = self.guard.value(mbs)
        s = math.tanh(v / self.eps)
        coulomb, resistance = -self.mu * abs(n) * s, -self.resistance * s
        self.last = (n, v, coulomb, resistance)
        f = coulomb + resistance
        return [f * self.axis[0], f * self.axis[1], 0.0]

    def _pre_step(self, mbs, t) -> None:
        if not self.history:           # before the first step: the initial-acceleration evaluation
            self.history.append(self.last)

    def _post_step(self, mbs, t) -> None:
        self.history.append(self.last)
        self.guard.accept(mbs)

    def reset(self) -> None:
        self.history.clear()
        self.last = (float("nan"),) * 4
        self.guard.calls = self.guard.substitutions = 0


def initialize(model: Model, settings: exu.SimulationSettings, read: Callable[[], object]):
    """Run only Exudyn's solver initialization at the initial state and return ``read()``.

    The initialization computes the initial accelerations and multipliers (with
    ``computeInitialAccelerations``) exactly as SolveDynamic does before its first step.
    """
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(model.mbs, settings)
    try:
        return read()
    finally:
        solver.FinalizeSolver(model.mbs, settings)


def seed_reaction_guards(model: Model, settings: exu.SimulationSettings, frictions: list[GuideFriction]) -> dict:
    """Make the initial-acceleration solve use the consistent normal force.

    At t = 0 Exudyn computes the initial accelerations with all multipliers 0, so a friction law
    reading the reaction would see N = 0 and the initial accelerations (and the generalized-alpha
    start) would miss the friction. This fixed-point iteration runs only Exudyn's solver
    initialization repeatedly, each time feeding the guards the normal forces of the previous
    initialization, until they no longer change. Purely Exudyn: no in-house quantity enters.

    Returns
    -------
    dict with 'seed_iterations' and 'seed_change' (last relative change of N); empty without friction.
    """
    if not frictions:
        return {}
    change = float("inf")
    it = 0
    for it in range(1, SEED_MAX_ITERATIONS + 1):
        new = initialize(model, settings, lambda: [f.guard.read(model.mbs) for f in frictions])
        change = max(abs(n - (f.guard.accepted if f.guard.accepted is not None else 0.0)) / max(abs(n), 1e-300)
                     for n, f in zip(new, frictions))
        for n, f in zip(new, frictions):
            f.guard.accepted = n
        if change <= SEED_TOLERANCE:
            break
    for f in frictions:
        f.reset()
    return {"seed_iterations": it, "seed_change": float(change)}


# --------------------------------------------------------------------------------------------
# running a built model
# --------------------------------------------------------------------------------------------
# ``build(ps, q0, qd0, friction, eps)`` returns an object with ``model`` (Model), ``frictions``
# (list of GuideFriction), ``loads_jacobian`` (0 or 2), ``initial_values()`` -> (qdd, lam) and
# ``result(eom, grid, solver, stats)`` -> SimulationResult (see study.exudyn_models.translate).
def run_model(build, ps, t_end: float, h: float, solver: str, output_step: float | None, friction: str,
              eps: float, configuration: str = "python", ignore_singular: bool = False) -> SimulationResult:
    """Build the model at the in-house consistent initial state, solve it, return its result."""
    grid = check_arguments(t_end, h, solver, output_step, friction, eps, configuration)
    eom = mechanisms.equations(ps)
    state0 = mechanisms.initial_state(ps, eom)
    built = build(ps, state0.q, state0.qd, friction, eps, configuration)
    settings = simulation_settings(grid, solver, built.loads_jacobian, configuration, ignore_singular)
    stats = {"configuration": configuration}
    if solver in IMPLICIT_SOLVERS:
        stats.update(seed_reaction_guards(built.model, settings, built.frictions))
    stats.update(solve(built.model, settings, solver))
    return built.result(eom, grid, solver, stats)


def initial_accelerations(build, ps, q, qd, friction: str, eps: float) -> tuple[Array, Array]:
    """Accelerations and multipliers at a state, from Exudyn's solver initialization alone."""
    check_arguments(1.0, 1.0, "index3", None, friction, eps)
    built = build(ps, q, qd, friction, eps)
    settings = simulation_settings(RunGrid(1.0, 1.0, 1, 1), "index3", built.loads_jacobian)
    seed_reaction_guards(built.model, settings, built.frictions)
    return initialize(built.model, settings, built.initial_values)


# --------------------------------------------------------------------------------------------
# solving and post-processing
# --------------------------------------------------------------------------------------------
def solve(model: Model, settings: exu.SimulationSettings, solver: str) -> dict:
    """Run SolveDynamic; return timing and iteration statistics.

    ``cpu_seconds`` is Exudyn's own solver timer (``timer.total``, the time spent in the solver
    including the Python user functions); ``process_cpu_seconds`` and ``wall_seconds`` are measured
    around the call. Exudyn's exceptions propagate unchanged (explicit solvers raise
    ``exudyn.ModelError``); a failed implicit run (``exudyn.SolverError``) gets a note with the
    solver's error string and the time reached.
    """
    wall0, cpu0 = time.perf_counter(), time.process_time()
    try:
        model.mbs.SolveDynamic(settings, solverType=_SOLVER_TYPES[solver], storeSolver=True)
    except exu.SolverError as exc:
        slv = model.mbs.sys.get("dynamicSolver")
        if slv is not None:
            exc.add_note(f"Exudyn: {slv.GetErrorString()!r} at t = {slv.it.currentTime}")
        raise
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    slv = model.mbs.sys["dynamicSolver"]
    return {
        "cpu_seconds": float(slv.timer.total),
        "process_cpu_seconds": cpu,
        "wall_seconds": wall,
        "steps": int(settings.timeIntegration.numberOfSteps),
        "newton_iterations": int(slv.it.newtonStepsCount),
        "jacobian_evaluations": int(slv.it.newtonJacobiCount),
    }


def friction_history(fric: GuideFriction, grid: RunGrid, stats: dict) -> Array:
    """The friction user function's record at every step (checked), its call counts added to ``stats``."""
    hist = np.asarray(fric.history, dtype=float)
    if hist.shape != (grid.n_steps + 1, 4):
        raise RuntimeError(f"friction history has {hist.shape[0]} rows, expected {grid.n_steps + 1}")
    stats.update(friction_user_function_calls=fric.guard.calls, friction_guard_substitutions=fric.guard.substitutions)
    return hist


def joint_forces(model: Model, grid: RunGrid, joints) -> dict[str, Array]:
    """``joint_<J>_x/_y``: global force of each revolute joint J on its distal body, at every step."""
    out = {}
    for joint in joints:
        f = -model.series((joint, "force"), grid)
        out[f"joint_{joint}_x"], out[f"joint_{joint}_y"] = f[:, 0], f[:, 1]
    return out


def cumulative_trapezoid(y: Array, t: Array) -> Array:
    """Integral of y from t[0] to every t[k] by the trapezoidal rule (same length as t)."""
    out = np.zeros_like(np.asarray(y, dtype=float))
    if len(t) > 1:
        out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))
    return out


WORK_NOTE = ("work_<load> = trapezoidal integral of the load's power sampled at every solver step (then "
             "sampled at the output times): error <= t_end h^2 max|P''| / 12 for smooth power, O(h) "
             "locally at a jump of a discontinuous (on/off) load")


def body_energies(bodies: dict[str, tuple[float, float]], pos: dict[str, Array], vel: dict[str, Array],
                  g: float) -> tuple[Array, Array]:
    """Kinetic and gravity potential energy from body states; ``bodies`` maps name -> (mass, inertia)."""
    kinetic = sum(0.5 * m * (vel[b][:, 0] ** 2 + vel[b][:, 1] ** 2) + 0.5 * J * vel[b][:, 2] ** 2
                  for b, (m, J) in bodies.items())
    potential = g * sum(m * pos[b][:, 1] for b, (m, _) in bodies.items())
    return kinetic, potential


def assemble_result(eom, ps, grid: RunGrid, solver: str, eps: float, friction: str, *, t: Array, q: Array,
                    qd: Array, qdd: Array, lam: Array, kinetic: Array, potential: Array,
                    works: dict[str, Array], forces: dict[str, Array], stats: dict, meta: dict):
    """The study's SimulationResult from per-step Exudyn series, sampled at the output times.

    Phi and Phidot are the in-house ones evaluated on Exudyn's q; work is integrated from the
    loads' power (see ``WORK_NOTE``). ``meta`` adds the mechanism-specific entries.
    """
    energies = {"kinetic": kinetic, "potential": potential}
    for name, power in works.items():
        energies[f"work_{name}"] = cumulative_trapezoid(power, t)
    idx = grid.output_indices
    phi = np.array([eom.phi(qi) for qi in q[idx]])
    phidot = np.array([eom.phi_q(qi) @ qdi for qi, qdi in zip(q[idx], qd[idx])])
    common_meta = {
        "engine": "exudyn",
        "exudyn_version": exudyn_version(),
        "method": f"exudyn_{solver}",
        "solver": solver,
        "solver_description": SOLVER_DESCRIPTIONS[solver],
        "configuration": stats.get("configuration", "python"),
        "configuration_description": CONFIGURATION_DESCRIPTIONS[stats.get("configuration", "python")],
        "h": grid.h,
        "t_end": grid.t_end,
        "output_step": grid.h * grid.stride,
        "eps": eps,
        "friction": friction,
        "mechanism": ps.mechanism,
        "variant": ps.variant,
        "parameter_hash": ps.sha256,
        "coordinate_names": list(eom.coordinate_names),
        "constraint_names": list(eom.constraint_names),
        "newton_tolerance": NEWTON_TOLERANCE,
        "spectral_radius": SPECTRAL_RADIUS if solver == "index3" else None,
        "qdd_source": "Exudyn node accelerations (Coordinates_tt sensors), not finite differences",
        "work_integration": WORK_NOTE,
        "versions": package_versions(),
    }
    return SimulationResult(
        t=t[idx], q=q[idx], qd=qd[idx], qdd=qdd[idx], lam=lam[idx], phi=phi, phidot=phidot,
        energies={k: val[idx] for k, val in energies.items()},
        forces={k: np.asarray(val, dtype=float)[idx] for k, val in forces.items()},
        stats=stats, meta={**common_meta, **meta},
    )
