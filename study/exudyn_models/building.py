"""Building blocks of an Exudyn model: planar rigid bodies, joints, loads and sensors, read back as arrays."""

from __future__ import annotations

import math
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
    ObjectConnectorDistance,
    ObjectGround,
    ObjectJointPrismatic2D,
    ObjectJointRevolute2D,
    ObjectRigidBody2D,
    SensorNode,
    SensorObject,
)

from study.exudyn_models.settings import RunGrid

OVT = exu.OutputVariableType
esym = exu.symbolic
Array = np.ndarray


def _chained(calls) -> Callable:
    """One pre/post-step user function calling every function of ``calls`` in order."""
    calls = tuple(calls)

    def run(mbs, t):
        for f in calls:
            f(mbs, t)
        return True
    return run


@dataclass(frozen=True)
class BodyState:
    """Centre-of-mass position, angle, COM velocity and angular velocity of a planar body."""

    position: tuple[float, float]
    angle: float
    velocity: tuple[float, float]
    omega: float


def unit(a: float) -> Array:
    return np.array([math.cos(a), math.sin(a)])


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

    def distance(self, name: str, marker0: int, marker1: int, length: float) -> int:
        """DistanceConstraint: the markers' points stay ``length`` apart; sensor 'Force' = its scalar force."""
        obj = self.mbs.AddObject(ObjectConnectorDistance(markerNumbers=[marker0, marker1], distance=float(length)))
        self.joints[name] = (obj, "distance")
        self.sensors[(name, "force")] = self.mbs.AddSensor(SensorObject(objectNumber=obj, outputVariableType=OVT.Force,
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
            ovt = OVT.ForceLocal if kind == "prismatic" else OVT.Force
        return np.atleast_1d(np.asarray(self.mbs.GetObjectOutput(obj, ovt), dtype=float))   # distance: a scalar

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
