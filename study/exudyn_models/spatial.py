"""The Exudyn model of a spatial description (:class:`study.spatial.SpatialDescription`), and its run.

The model is built from the description alone, one handler per element kind; the in-house equations give only the
consistent initial state (the caller's q0, qd0, as for the planar models) and, in the result, the in-house Phi on
Exudyn's coordinates and the norm rows' multipliers (below).

* body: NodeRigidBodyEP at the centre of mass (reference coordinates = the body's (r, p) of q0, initial velocities
  its (r_dot, p_dot) of qd0: the same seven coordinates as the description's) with ObjectRigidBody (mass, the
  inertia tensor at the centre of mass), and gravity as LoadMassProportional.
* spherical: JointSpherical, marker 0 at body b's point, marker 1 at body a's point (Exudyn's rows p_m1 - p_m0 are
  the description's r_a + A_a s_a - r_b - A_b s_b).
* revolute, cylindrical, universal, fixed, prismatic: JointGeneric, marker 0 on body b with the joint frame R_b,
  marker 1 on body a with R_a (:func:`study.spatial.joints.joint_frames`), the kind's axes locked (GENERIC_AXES).
  Exudyn's rows are then the description's (:mod:`study.spatial.joints`): all three translations locked, the gap
  in global components; two (cylindrical, prismatic), its components along marker 0's x and y columns; the
  revolute's rotation rows (A_b h_b)^T (A_a f_a), (A_b h_b)^T (A_a g_a); the universal's (A_b h_b)^T (A_a h_a); all
  three rotations locked, (A_b R_b e_2)^T (A_a R_a e_1), (A_b R_b e_2)^T (A_a R_a e_0), (A_b R_b e_0)^T (A_a R_a
  e_1), two of them the description's lock rows with the vectors swapped (sign -1 in JOINT_ROWS).
* distance: ConnectorDistance, marker 0 at body b's point, marker 1 at body a's (the row |p_m1 - p_m0| - L).
* point force: LoadForceVector at a MarkerBodyPosition (global components); torque: LoadTorqueVector at a
  MarkerBodyRigid, ``bodyFixed`` for the 'body' frame. A law of time is a Python load user function.
* friction in a revolute or prismatic joint (``d.frictions``): the regularized law's torque or force pair from
  Python load user functions that read the joint's reaction (:mod:`study.exudyn_models.spatial_friction`, which
  says what lag that reading has), with friction='regularized'; a sensor of the joint's reaction either way.

Result mapping (:func:`result`): q, qd, qdd = the nodes' coordinates (reference + displacement), rates and
accelerations (Exudyn's, not finite differences). lam, in ``eom.constraint_names`` order: a joint row's multiplier
is Exudyn's algebraic coordinate of the matching equation (JOINT_ROWS: the same function of q, so the same multiplier,
with the sign -1 where Exudyn's row is the description's with its two vectors swapped, whose gradients are opposite
on the constraint manifold). A revolute with friction has its position rows in body b's joint frame
(:mod:`study.spatial.joints`) while Exudyn's are the gap's global components: their multipliers are Exudyn's turned
by (A_b R_b)^T (:func:`framed_multipliers`). A norm row p^T p - 1 has no physical reaction and its multiplier depends
on the formulation (the in-house mass matrix adds c p p^T, :mod:`study.spatial.derive`; Exudyn's own Euler-parameter
multiplier stays 0): the result carries the in-house convention's value, the p-block's component along p of
Q - M qdd - Phi_q,joints^T lam on Exudyn's state, divided by 2 p^T p. Energies: kinetic from Exudyn's centre
velocities and body-frame angular velocities, potential -sum m g . r, and work_<load> the trapezoidal integral of
each load's power (law value . the sensed point velocity or angular velocity). A joint with friction adds
``normal_<joint>``, ``friction_<joint>`` and ``work_friction_<joint>``, and its friction forces' part to the norm
rows' multipliers (:mod:`study.exudyn_models.spatial_friction`): the in-house equations hold the friction as the
pins' generalized force P^T tau, not in ``eom.forces``, so this part is the one the in-house norm rows take up
(tests/test_spatial_friction_carriage.py checks the two at t = 0 row by row).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import exudyn as exu
import numpy as np
import sympy as sp
from exudyn.itemInterface import (LoadForceVector, LoadMassProportional, LoadTorqueVector, MarkerBodyMass,
                                  MarkerBodyPosition, MarkerBodyRigid, NodeRigidBodyEP, ObjectConnectorDistance,
                                  ObjectJointGeneric, ObjectJointSpherical, ObjectRigidBody, SensorBody, SensorNode,
                                  SensorObject)

import study.exudyn_models.settings as settings
import study.exudyn_models.solve as solve
import study.exudyn_models.spatial_friction as spatial_friction
from study.exudyn_models.building import OVT, Model
from study.exudyn_models.guards import seed_reaction_guards
from study.model.eom import EquationsOfMotion
from study.reference_data import tolerance
from study.results import SimulationResult, package_versions
from study.spatial.description import SpatialDescription, spatial_only
from study.spatial.elements import (GROUND, Cylindrical, Distance, FixedJoint, PointLoad, Prismatic, Revolute,
                                    Spherical, Universal)
from study.spatial.joints import joint_frames

Array = np.ndarray

#: joint kind -> (suffix of the description's row, index of Exudyn's algebraic coordinate in the joint, sign).
#: Verified at t = 0 against the in-house multipliers (tests/test_spatial_exudyn.py).
JOINT_ROWS = {
    Spherical: (("x", 0, 1.0), ("y", 1, 1.0), ("z", 2, 1.0)),
    Revolute: (("x", 0, 1.0), ("y", 1, 1.0), ("z", 2, 1.0), ("f", 3, 1.0), ("g", 4, 1.0)),
    FixedJoint: (("x", 0, 1.0), ("y", 1, 1.0), ("z", 2, 1.0), ("rx", 5, -1.0), ("ry", 3, 1.0), ("rz", 4, -1.0)),
    Prismatic: (("tx", 0, 1.0), ("ty", 1, 1.0), ("rx", 5, -1.0), ("ry", 3, 1.0), ("rz", 4, -1.0)),
    Cylindrical: (("tx", 0, 1.0), ("ty", 1, 1.0), ("f", 3, 1.0), ("g", 4, 1.0)),
    Universal: (("x", 0, 1.0), ("y", 1, 1.0), ("z", 2, 1.0), ("h", 3, 1.0)),
    Distance: (("length", 0, 1.0),),
}
#: a revolute with friction in the equations: its three position rows in body b's joint frame, from Exudyn's global
#: rows 0, 1, 2 (:func:`framed_multipliers`), in place of the revolute's x, y, z
FRAMED_ROWS = ("tx", "ty", "tz")
NORM_NOTE = ("the norm rows' multipliers are the in-house convention's (Exudyn's Euler-parameter multiplier belongs "
             "to its own mass matrix): the p-block's component along p of Q - M qdd - Phi_q,joints^T lam on Exudyn's "
             "state, / (2 p^T p)")


@dataclass
class SpatialBuilt:
    """A built spatial model: the Exudyn system, its nodes and joints by name, the loads' laws and their power
    sensors, and the algebraic coordinates recorded at every step (``ae``, filled while it runs)."""

    d: SpatialDescription
    model: Model
    nodes: dict = field(default_factory=dict)     # body -> node
    objects: dict = field(default_factory=dict)   # body -> object
    joints: dict = field(default_factory=dict)    # joint name -> object
    laws: dict = field(default_factory=dict)      # load name -> callable t -> (3,) values
    frictions: dict = field(default_factory=dict)  # joint name -> its SpatialJointFriction (friction 'regularized')
    options: dict = field(default_factory=dict)    # the friction option and eps of a description with friction
    ae: list = field(default_factory=list)        # (t, algebraic coordinates) at t = 0 and after every step

    def marker(self, body: str, point, rotation: Array | None = None) -> int:
        """A rigid marker at a body's named point (ground: a global point), its frame turned by ``rotation``."""
        local = point if body == GROUND else self.d.bodies[body].points[point]
        obj = self.model.ground if body == GROUND else self.objects[body]
        frame = np.eye(3) if rotation is None else rotation
        return self.model.mbs.AddMarker(MarkerBodyRigid(bodyNumber=obj, localHT=exu.HT(
            rotation=frame.tolist(), translation=[float(v) for v in local])))

    def sensor(self, key, item) -> None:
        self.model.sensors[key] = self.model.mbs.AddSensor(item)


def _store(**kwargs) -> dict:
    return {**kwargs, "storeInternal": True, "writeToFile": False}


def add_bodies(b: SpatialBuilt, q0: Array, qd0: Array) -> None:
    """Every body at its (r, p) of q0 with its rates of qd0, under gravity; sensors of its coordinates, rates,
    accelerations and angular velocity (body frame)."""
    mbs = b.model.mbs
    for i, (name, body) in enumerate(b.d.bodies.items()):
        k = slice(7 * i, 7 * i + 7)
        node = mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[float(v) for v in q0[k]],
                                           initialVelocities=[float(v) for v in qd0[k]]))
        j = body.inertia
        obj = mbs.AddObject(ObjectRigidBody(nodeNumber=node, mass=body.mass, inertia=[
            j[0, 0], j[1, 1], j[2, 2], j[1, 2], j[0, 2], j[0, 1]]))
        b.nodes[name], b.objects[name] = node, obj
        if np.any(b.d.gravity_vector):
            mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=obj)),
                                             loadVector=[float(v) for v in b.d.gravity_vector]))
        for key, ovt in (("coordinates", OVT.Coordinates), ("rates", OVT.Coordinates_t),
                         ("accelerations", OVT.Coordinates_tt), ("omega_body", OVT.AngularVelocityLocal)):
            b.sensor((name, key), SensorNode(**_store(nodeNumber=node, outputVariableType=ovt)))


def add_spherical(b: SpatialBuilt, j: Spherical) -> int:
    return b.model.mbs.AddObject(ObjectJointSpherical(markerNumbers=[b.marker(j.body_b, j.b),
                                                                     b.marker(j.body_a, j.a)]))


def add_distance(b: SpatialBuilt, j: Distance) -> int:
    return b.model.mbs.AddObject(ObjectConnectorDistance(markerNumbers=[b.marker(j.body_b, j.b),
                                                                        b.marker(j.body_a, j.a)], distance=j.length))


#: joint kind -> ObjectJointGeneric's constrainedAxes (translations x, y, z, rotations about x, y, z of marker 0's
#: frame); the markers' frames are :func:`study.spatial.joints.joint_frames`'
GENERIC_AXES = {
    Revolute: [1, 1, 1, 1, 1, 0],
    Cylindrical: [1, 1, 0, 1, 1, 0],
    Universal: [1, 1, 1, 1, 0, 0],
    FixedJoint: [1, 1, 1, 1, 1, 1],
    Prismatic: [1, 1, 0, 1, 1, 1],
}


def add_generic(b: SpatialBuilt, j) -> int:
    """A JointGeneric: marker 0 on body b with the frame R_b, marker 1 on body a with R_a, the kind's locked axes."""
    frame_a, frame_b = joint_frames(b.d, j)
    return b.model.mbs.AddObject(ObjectJointGeneric(
        markerNumbers=[b.marker(j.body_b, j.b, frame_b), b.marker(j.body_a, j.a, frame_a)],
        constrainedAxes=GENERIC_AXES[type(j)]))


#: joint class -> its handler
JOINTS = {Spherical: add_spherical, Distance: add_distance, **{kind: add_generic for kind in GENERIC_AXES}}


def add_joint(b: SpatialBuilt, j) -> None:
    """The handler of the joint's kind."""
    handler = JOINTS.get(type(j))
    if handler is None:
        raise TypeError(f"joint {j.name!r} of kind {type(j).__name__} has no Exudyn handler (kinds: "
                        f"{', '.join(k.__name__ for k in JOINTS)})")
    b.joints[j.name] = handler(b, j)


def _law(components, t: sp.Symbol):
    """(constant values or None, callable t -> (3,) values) of three expressions of time."""
    if all(not sp.sympify(c).free_symbols for c in components):
        values = [float(c) for c in components]
        return values, lambda _t: np.array(values)
    f = sp.lambdify(t, list(components), modules="numpy")
    return None, lambda time: np.array(f(time), dtype=float)


def add_load(b: SpatialBuilt, load) -> None:
    """A point force (global) or a torque ('global' or 'body' frame); a law of time as a load user function; a
    sensor of the loaded point's velocity or of the body's angular velocity in the law's frame (the power)."""
    mbs, obj = b.model.mbs, b.objects[load.body]
    constant, law = _law(load.components, b.d.t)
    b.laws[load.name] = law
    user = {} if constant is not None else {"loadVectorUserFunction": lambda mbs_, t, vector: list(law(t))}
    vector = constant if constant is not None else [0.0, 0.0, 0.0]
    if isinstance(load, PointLoad):
        local = [float(v) for v in b.d.bodies[load.body].points[load.point]]
        marker = mbs.AddMarker(MarkerBodyPosition(bodyNumber=obj, localPosition=local))
        mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=vector, **user))
        b.sensor((load.name, "power"), SensorBody(**_store(bodyNumber=obj, localPosition=local,
                                                            outputVariableType=OVT.Velocity)))
        return
    body_frame = load.frame == "body"
    marker = mbs.AddMarker(MarkerBodyRigid(bodyNumber=obj, localPosition=[0.0, 0.0, 0.0]))
    mbs.AddLoad(LoadTorqueVector(markerNumber=marker, loadVector=vector, bodyFixed=body_frame, **user))
    b.sensor((load.name, "power"), SensorNode(**_store(
        nodeNumber=b.nodes[load.body], outputVariableType=OVT.AngularVelocityLocal if body_frame else
        OVT.AngularVelocity)))


def build(d: SpatialDescription, q0, qd0, friction: str = "regularized", eps: float = settings.DEFAULT_EPS) -> \
        SpatialBuilt:
    """The Exudyn model of a spatial description at the state (q0, qd0) (the description's coordinates), with the
    algebraic coordinates recorded at t = 0 (first pre-step call) and after every step. A joint with friction gets a
    sensor of its reaction (ForceLocal) and, with ``friction`` 'regularized', its friction loads of width ``eps``
    (:mod:`study.exudyn_models.spatial_friction`); 'none' leaves them out."""
    d = spatial_only(d)
    b = SpatialBuilt(d, Model(), options={"friction": friction, "eps": eps} if d.frictions else {})
    add_bodies(b, np.asarray(q0, dtype=float), np.asarray(qd0, dtype=float))
    for j in d.joints:
        add_joint(b, j)
    for load in d.loads:
        add_load(b, load)
    for j in d.joints:
        if j.name in d.frictions:
            b.sensor((j.name, "reaction"), SensorObject(**_store(objectNumber=b.joints[j.name],
                                                                 outputVariableType=OVT.ForceLocal)))
            if friction == "regularized" and spatial_friction.active(d.frictions[j.name]):
                b.frictions[j.name] = spatial_friction.add_joint_friction(
                    b, j, d.frictions[j.name], eps, tolerance("pin_friction_norm_width"))

    def record_start(mbs, t):
        if not b.ae:
            b.ae.append((t, np.array(mbs.systemData.GetAECoordinates(), dtype=float)))

    def record(mbs, t):
        b.ae.append((t, np.array(mbs.systemData.GetAECoordinates(), dtype=float)))
    b.model.pre_step.append(record_start)
    b.model.post_step.append(record)
    b.model.assemble()
    return b


def joint_multipliers(b: SpatialBuilt, eom: EquationsOfMotion, ae: Array, q: Array) -> tuple[Array, list[int]]:
    """(n, r) multipliers of the joint rows, in ``eom.constraint_names`` order, from Exudyn's algebraic coordinates
    ``ae`` at the states ``q`` (norm rows left 0), and the indices of the norm rows. A revolute whose rows in
    ``eom`` are in body b's joint frame (``_tx``, ``_ty``, ``_tz``: the equations of a description with its friction,
    :mod:`study.spatial.joints`) takes FRAMED_ROWS; one with ``_x``, ``_y``, ``_z`` (the equations without it) the
    global rows as they are."""
    names = eom.constraint_names
    lam = np.zeros((ae.shape[0], len(names)))
    sources, framed = {}, []
    for j in b.d.joints:
        ltg = list(b.model.mbs.systemData.GetObjectLTGAE(b.joints[j.name]))
        rows = JOINT_ROWS[type(j)]
        if isinstance(j, Revolute) and f"{j.name}_{FRAMED_ROWS[0]}" in names:
            framed.append((j, [names.index(f"{j.name}_{suffix}") for suffix in FRAMED_ROWS], ltg[:3]))
            rows = rows[3:]
        for suffix, index, sign in rows:
            sources[f"{j.name}_{suffix}"] = (ltg[index], sign)
    for j, rows, coordinates in framed:
        lam[:, rows] = framed_multipliers(b.d, j, eom, q, ae[:, coordinates], rows)
    done = {k for _, rows, _ in framed for k in rows}
    norms = []
    for k, row in enumerate(names):
        if row in sources:
            lam[:, k] = sources[row][1] * ae[:, sources[row][0]]
        elif row.endswith("_norm") and row[:-5] in b.d.bodies:
            norms.append(k)
        elif k not in done:
            raise ValueError(f"constraint row {row!r} has no Exudyn counterpart in {b.d.name!r}")
    return lam, norms


def framed_multipliers(d: SpatialDescription, j: Revolute, eom: EquationsOfMotion, q: Array, global_: Array,
                       rows: list[int]) -> Array:
    """(n, 3) multipliers of the rows (A_b R_b e_k)^T gap of a revolute with friction from Exudyn's multipliers
    ``global_`` of the gap's global components: (A_b R_b)^T times them (both sets of rows give the same force on
    the manifold gap = 0). (A_b R_b)^T is the rows' gradient with respect to body a's centre (ground as body a:
    minus it with respect to body b's), read off the description's own Jacobian at each state."""
    body, sign = (j.body_a, 1.0) if j.body_a != GROUND else (j.body_b, -1.0)
    k = 7 * list(d.bodies).index(body)
    return np.array([sign * eom.phi_q(x)[rows, k:k + 3] @ g for x, g in zip(q, global_)])


def norm_multipliers(eom: EquationsOfMotion, t: Array, q: Array, qd: Array, qdd: Array, lam: Array,
                     norms: list[int], radial: dict[int, Array]) -> None:
    """Fill the norm rows of ``lam`` with the in-house convention's value (module docstring), in place; ``radial``
    (norm row -> values) adds p . Q_p of loads that ``eom.forces`` does not hold (the joints' friction)."""
    joints = [k for k in range(lam.shape[1]) if k not in norms]
    for n in range(len(t)):
        jac = eom.phi_q(q[n])
        rest = eom.forces(t[n], q[n], qd[n]) - eom.mass(q[n]) @ qdd[n] - jac[joints].T @ lam[n, joints]
        for k in norms:
            block = np.flatnonzero(jac[k])       # the body's four Euler parameters (2 p^T)
            p = 0.5 * jac[k, block]
            along = p @ rest[block] + radial[k][n] if k in radial else p @ rest[block]
            lam[n, k] = along / (2 * p @ p)


def _energies(b: SpatialBuilt, t: Array, series: dict) -> dict[str, Array]:
    """Kinetic, potential and every load's work at every step (module docstring)."""
    kinetic, potential = np.zeros(len(t)), np.zeros(len(t))
    for name, body in b.d.bodies.items():
        rates, w = series[(name, "rates")], series[(name, "omega_body")]
        kinetic += 0.5 * body.mass * (rates[:, :3] ** 2).sum(axis=1) + 0.5 * np.einsum("ni,ij,nj->n", w, body.inertia, w)
        potential -= body.mass * (series[(name, "coordinates")][:, :3] @ b.d.gravity_vector)
    out = {"kinetic": kinetic, "potential": potential}
    for name, law in b.laws.items():
        power = np.einsum("ni,ni->n", np.array([law(ti) for ti in t]), series[(name, "power")])
        out[f"work_{name}"] = solve.cumulative_trapezoid(power, t)
    return out


def result(b: SpatialBuilt, eom: EquationsOfMotion, q0: Array, grid: settings.RunGrid, solver: str,
           stats: dict) -> SimulationResult:
    """The SimulationResult of a solved spatial model (module docstring)."""
    t = grid.h * np.arange(grid.n_steps + 1)
    series = {key: b.model.series(key, grid) for key in b.model.sensors}
    for i, name in enumerate(b.d.bodies):
        series[(name, "coordinates")] = series[(name, "coordinates")] + q0[7 * i:7 * i + 7]
    q, qd, qdd = (np.hstack([series[(name, key)] for name in b.d.bodies])
                  for key in ("coordinates", "rates", "accelerations"))
    ae = np.array([row for _, row in b.ae], dtype=float)
    if ae.shape[0] != len(t) or np.abs(np.array([time for time, _ in b.ae]) - t).max() > 1e-9 * max(grid.t_end, 1.0):
        raise RuntimeError(f"recorded {ae.shape[0]} rows of multipliers, expected one per step ({len(t)}) on k*h")
    idx = grid.output_indices
    t, q, qd, qdd = t[idx], q[idx], qd[idx], qdd[idx]
    lam, norms = joint_multipliers(b, eom, ae[idx], q)
    forces, powers, radial = spatial_friction.friction_results(b, eom, q, series, grid, stats)
    norm_multipliers(eom, t, q, qd, qdd, lam, norms, radial)
    steps = grid.h * np.arange(grid.n_steps + 1)
    energies = _energies(b, steps, series)
    energies.update({f"work_{k}": solve.cumulative_trapezoid(v, steps) for k, v in powers.items()})
    meta = {
        "engine": "exudyn", "exudyn_version": settings.exudyn_version(), "method": f"exudyn_{solver}",
        "solver": solver, "solver_description": settings.SOLVER_DESCRIPTIONS[solver], "h": grid.h,
        "t_end": grid.t_end, "output_step": grid.h * grid.stride, "mechanism": b.d.name,
        "coordinate_names": list(eom.coordinate_names), "constraint_names": list(eom.constraint_names),
        "newton_tolerance": stats["newton_tolerance"], "configuration": stats["configuration"],
        "spectral_radius": settings.SPECTRAL_RADIUS if solver == "index3" else None,
        "qdd_source": "Exudyn node accelerations (Coordinates_tt sensors), not finite differences",
        "norm_multipliers": NORM_NOTE, "work_integration": solve.WORK_NOTE, **eom.redundancy_note(),
        "versions": package_versions(),
    }
    if b.options:
        meta.update(b.options, friction_law=spatial_friction.FRICTION_LAW,
                    friction_evaluation=spatial_friction.REACTION_READING)
    return SimulationResult(t=t, q=q, qd=qd, qdd=qdd, lam=lam, phi=np.array([eom.phi(x) for x in q]),
                            phidot=np.array([eom.phi_q(x) @ v for x, v in zip(q, qd)]),
                            energies={k: v[idx] for k, v in energies.items()},
                            forces={k: v[idx] for k, v in forces.items()}, stats=stats, meta=meta)


def check_run(d: SpatialDescription, t_end: float, h: float, solver: str, output_step: float | None, friction: str,
              eps: float, configuration: str, linear_solver: str, ignore_singular: bool,
              newton_tolerance: float) -> settings.RunGrid:
    """The time grid of a run of ``d`` with these options, each checked (the friction options by
    :func:`study.exudyn_models.spatial_friction.check_options`, the others by
    :func:`study.exudyn_models.settings.check_arguments`)."""
    spatial_friction.check_options(spatial_only(d), friction, eps)
    return settings.check_arguments(t_end, h, solver, output_step, friction, eps, configuration, linear_solver,
                                    ignore_singular, newton_tolerance)


def run_spatial(d: SpatialDescription, eom: EquationsOfMotion, q0, qd0, t_end: float, h: float,
                solver: str = "index3", output_step: float | None = None, configuration: str = "python",
                ignore_singular: bool = False, linear_solver: str = "dense",
                newton_tolerance: float = settings.NEWTON_TOLERANCE, friction: str = "regularized",
                eps: float = settings.DEFAULT_EPS) -> SimulationResult:
    """Simulate a spatial description in Exudyn from the consistent state (q0, qd0) (:func:`study.spatial.
    initial_state`); ``eom`` (:func:`study.spatial.spatial_equations` of the same description, or of any description
    with the same bodies, joints and loads: its coordinates, rows, Phi and applied forces) maps the result.

    ``solver``: 'index3' (generalized-alpha, index-3 constraints) or 'index2' (trapezoidal, index-2); Exudyn's
    explicit solvers refuse the joints and the Euler-parameter rows (``exudyn.ModelError``). ``t_end`` a whole
    number of fixed steps ``h``; ``output_step`` a whole multiple of h (default: every step); ``configuration``,
    ``ignore_singular``, ``linear_solver``, ``newton_tolerance`` as for :func:`study.exudyn_models.run`.
    ``friction`` 'regularized' (the joints' friction, :mod:`study.exudyn_models.spatial_friction`, of width ``eps``
    [m/s, rad/s]) or 'none' (left out); a description without friction takes neither another mode nor another eps
    (:func:`study.exudyn_models.spatial_friction.check_options`).
    """
    grid = check_run(d, t_end, h, solver, output_step, friction, eps, configuration, linear_solver, ignore_singular,
                     newton_tolerance)
    q0 = np.asarray(q0, dtype=float)
    b = build(d, q0, qd0, friction, eps)
    # loads of time only: no load Jacobian (the joints' friction: spatial_friction.loads_jacobian). Redundant rows
    # (eom.redundant_rows): Newton's singular matrix factorized with the dependent equations left out
    # (linearSolver.ignoreSingularJacobian) by Eigen's dense full-pivoting LU, as in Exudyn's
    # TestModels/bricardMechanism.py; Exudyn's own dense inverse (EXUdense) stops at the first step of Bricard's
    # mechanism with the flag set ('reduction of step size reached minimum step size')
    redundant = eom.redundant_rows > 0
    ignore = ignore_singular or redundant
    simulation = settings.simulation_settings(grid, solver, spatial_friction.loads_jacobian(d), configuration, ignore,
                                              linear_solver, newton_tolerance)
    if redundant:
        simulation.linearSolver.solverType = exu.LinearSolverType.EigenDense
    stats = {"configuration": configuration, "linear_solver": "eigen_dense" if redundant else linear_solver,
             "newton_tolerance": newton_tolerance, "ignore_singular_jacobian": ignore}
    if solver in settings.IMPLICIT_SOLVERS:
        stats.update(seed_reaction_guards(b.model, simulation, list(b.frictions.values())))
    stats.update(solve.solve(b.model, simulation, solver))
    return result(b, eom, q0, grid, solver, stats)


def run(mechanism, t_end: float, h: float, solver: str = "index3", output_step: float | None = None,
        friction: str = "regularized", eps: float = settings.DEFAULT_EPS, configuration: str = "python",
        ignore_singular: bool = False, linear_solver: str = "dense",
        newton_tolerance: float = settings.NEWTON_TOLERANCE) -> SimulationResult:
    """:func:`run_spatial` of a :class:`study.spatial.SpatialMechanism` from its consistent initial state, with the
    options of :func:`study.exudyn_models.run` (``study.run(mechanism, Exudyn(...), t_end)`` calls it for a spatial
    mechanism); ``friction`` and ``eps`` as for :func:`run_spatial`; every option is checked before any work."""
    check_run(mechanism.description, t_end, h, solver, output_step, friction, eps, configuration, linear_solver,
              ignore_singular, newton_tolerance)
    state = mechanism.initial_state()
    return run_spatial(mechanism.description, mechanism.equations(), state.q, state.qd, t_end, h, solver,
                       output_step, configuration, ignore_singular, linear_solver, newton_tolerance, friction, eps)
