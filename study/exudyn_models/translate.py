"""The Exudyn model of any joint-level description (:class:`study.model.joints.Description`).

No mechanism is named here: bodies, joints, loads, friction and the result mapping are all read from
the description of a :class:`study.mechanisms.Mechanism` (a user's, or a study mechanism's). One concept,
the translation of a description into an Exudyn model and back into a result, hence its length; the run
settings, model building blocks, reaction guards and solving it uses are in the sibling modules.

Model
-----
* Every body: NodeRigidBody2D at its centre of mass with mass and centroidal inertia, gravity -g
  along y (LoadMassProportional). The node's reference configuration is the initial state (initial
  displacements 0); its initial velocities are the consistent ones. The initial state comes from the
  in-house consistent (q, qd) mapped through the description's kinematics (COM position from the
  generated point function ``eom.points['<body>.com']``, angle from the description's angle
  expression, rates from their Jacobians).
* ``revolute(J, a, b)``: RevoluteJoint2D between MarkerBodyRigid markers at a (marker 0) and b
  (marker 1); a ground point is a marker on the ground object.
* ``prismatic(J, slider, guide, axis, normal)``: PrismaticJoint2D with marker 0 at the guide point,
  ``axisMarker0`` = the description's axis (guide frame), marker 1 at the slider point,
  ``normalMarker1`` = the normal expressed in the slider's frame at the initial configuration,
  ``constrainRotation=True``.
* Loads: a law without state, time or mode dependence (after binding the parameter values) is a
  constant LoadTorqueVector / LoadForceVector (no Python in the loop); any other law is lambdified
  once with the parameter values bound and evaluated in a load user function from Exudyn's own
  kinematics: marker position / velocity of the input point, node angle = reference + displacement,
  node angular velocity. A mode symbol is +1 if its switching function (evaluated live on the same
  inputs) is >= 0, else -1: the law is evaluated without event location, as Exudyn cannot locate a
  switch within a step.
* ``configuration='tuned'`` (what Exudyn's documentation recommends for speed; 'python' is the
  above): a law whose inputs are all those of the element carrying it is recorded once as an Exudyn
  symbolic user function (``exudyn.symbolic``, evaluated in C++, no Python per call): a point force
  reading only its point's x, y, vx, vy as ObjectConnectorCartesianSpringDamper from the ground
  origin, a torque reading only its body's angle and rate as ObjectConnectorCoordinateSpringDamper on
  the rotation coordinate (see building.Model.point_law / angle_law); other laws and the friction (it
  reads a joint reaction, which only Python can) stay Python user functions; Newton reuses one
  Jacobian per step. tests/test_exudyn_tuned.py checks both configurations give the same answers.
* Potentials (springs): user-function torques / forces = minus the gradient of the energy with
  respect to the angle and point-position inputs; their energy is part of the result's potential.
* Friction: a prismatic joint with :class:`~study.model.joints.Friction` data whose kinetic
  coefficient or resistance is > 0 gets the regularized Coulomb law of
  :class:`~study.exudyn_models.guards.GuideFriction` along the guide's axis, with N read from the
  joint through a :class:`~study.exudyn_models.guards.ReactionGuard`; ``friction='none'`` leaves it out.
  On a moving guide the axis turns with the guide, the sliding velocity is relative to the guide's point
  under the slider, and the guide carries the opposite force (a force at its centre of mass and the torque
  of its lever: the same load as the force at the slider point).
  A revolute joint with friction data (a pin, ``friction=Friction(mu_s, mu_k, T0), radius=r``) whose mu_k or T0
  is > 0 gets the regularized law of :class:`~study.exudyn_models.guards.PinFriction`: the torque
  tau = -(mu_k r sqrt(|R|^2 + delta^2) + T0) tanh(omega_rel/eps) on its body a and -tau on its body b
  (LoadTorqueVector user functions; nothing on ground), omega_rel = theta_a' - theta_b' from the nodes, |R| the
  magnitude of the RevoluteJoint2D's 'Force' (its multipliers, a global vector; only the magnitude enters) through
  a ReactionGuard, delta = ``pin_friction_norm_width`` (reference/tolerances.toml, the in-house value), eps read
  in rad/s. Exudyn has only this regularized law: friction='exact' and 'sign' are not run modes
  (settings.FRICTION_MODES), for pins as for guides.

Result mapping (in-house relative coordinates, ``M qdd + Phi_q^T lam = Q``)
---------------------------------------------------------------------------
* q: where the body angles are linear in q with full rank, theta = A q + c; q = q0 + A^+ (theta - theta0) with
  A^+ the exact pseudo-inverse and theta - theta0 Exudyn's angle displacement (so q(0) = q0 exactly);
  qd, qdd = A^+ times the node angular velocities / accelerations (Exudyn's, not finite differences).
  Otherwise (a translation coordinate) q solves pose(q) = Exudyn's body poses (x, y, theta of every body) by
  Gauss-Newton, and qd, qdd follow through the pose Jacobian (Kinematics.coordinates).
* lam, in ``eom.constraint_names`` order: a revolute row ``<J>_x/_y`` is the row r_a - r_b, so lam =
  the force of joint J on its second body b, global = -Exudyn 'Force' (the force on the marker-0
  body a). A prismatic gap row ``<J>`` = n . (r_s - r_g): the guide pushes the slider with -lam n, so
  lam = ForceLocal . n_local, ForceLocal = Exudyn's force on the marker-0 (guide) body in the
  guide's body frame and n_local the normal in that frame.
* forces: ``normal_<c>`` = -lam of contact c's row; ``friction_<c>`` (Coulomb part) and
  ``resistance_<c>`` (if the description has a resistance) along the guide axis; after the contacts, every
  pin p: ``normal_<p>`` = |R| (the joint's reaction magnitude) and ``friction_<p>`` = tau, the whole friction
  torque on its body a (Coulomb and T0, as in the in-house result); ``<load>`` = the
  torque, or the force along the guide axis of the loaded body's prismatic joint (else along global
  x); ``joint_<J>_x/_y`` (every revolute joint) = force of J on its second body, global;
  ``joint_<J>_n`` (every prismatic joint) = force on the slider along the joint's normal = -lam.
* energies: kinetic, potential (gravity + springs), ``work_<load>``, ``work_friction_<c>`` and
  ``work_friction_<p>`` (the pair's power tau * omega_rel integrated).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from study.mechanisms import Mechanism, as_mechanism
import study.exudyn_models.building as building
import study.exudyn_models.settings as settings
import study.exudyn_models.solve as solve
from study.exudyn_models.building import OVT, BodyState, Model
from study.exudyn_models.guards import GuideFriction, PinFriction, ReactionGuard, RecordedFriction
from study.model.coordinates import poses
from study.model.joints import GROUND, Description, Distance, Prismatic, Revolute
from study.params import ParameterSet
from study.reference_data import tolerance
from study.results import SimulationResult

Array = np.ndarray


# --------------------------------------------------------------------------------------------
# the description, its bound values and kinematics (one per parameter set)
# --------------------------------------------------------------------------------------------
@dataclass
class Kinematics:
    """Body poses of the relative coordinates, and the map from Exudyn's body poses back to q.

    ``pinv`` is set when the body angles alone determine q (linear in q with full rank): q - q0 = pinv @
    (theta - theta0). Otherwise (a translation coordinate of a prismatic tree joint) q is recovered from every
    body's pose (x, y, theta) by Gauss-Newton (:meth:`coordinates`)."""

    d: Description
    subs: dict
    angle: dict           # body -> f(q) -> float
    angle_grad: dict      # body -> f(q) -> (m,) gradient
    com_jac: dict         # body -> f(q) -> (2, m)
    pinv: Array | None    # (m, n_bodies), or None
    pose: object = None        # f(q) -> (3 n_bodies,) [x, y, theta of every body]
    pose_jac: object = None    # f(q) -> (3 n_bodies, m)
    pose_bias: object = None   # f(q, qd) -> (3 n_bodies,) d(J)/dt qd, so that acc = J qdd + bias

    def coordinates(self, q0: Array, poses: Array, rates: Array, accelerations: Array) -> tuple[Array, Array, Array]:
        """q, qd, qdd at every sample from the bodies' (n, 3 n_bodies) poses, rates and accelerations.

        q: Gauss-Newton on pose(q) = pose, from the previous sample's q (q0 first); stopped at a step
        <= POSE_TOL (1 + |q|), or refused (ValueError) after POSE_MAX_ITER iterations. qd, qdd: least squares
        through the pose Jacobian, which has full column rank on a description whose bodies place q."""
        n = len(poses)
        q, qd, qdd = np.empty((n, len(q0))), np.empty((n, len(q0))), np.empty((n, len(q0)))
        qk = np.array(q0, dtype=float)
        for k in range(n):
            for _ in range(POSE_MAX_ITER):
                J = np.asarray(self.pose_jac(qk), dtype=float)
                step = np.linalg.lstsq(J, poses[k] - np.asarray(self.pose(qk), dtype=float).ravel(), rcond=None)[0]
                qk = qk + step
                if np.abs(step).max() <= POSE_TOL * (1 + np.abs(qk).max()):
                    break
            else:
                raise ValueError(f"{self.d.name}: q cannot be recovered from Exudyn's body poses at sample {k} "
                                 f"(Gauss-Newton did not converge in {POSE_MAX_ITER} iterations; last step "
                                 f"{np.abs(step).max():.3g}, q = {qk})")
            q[k] = qk
            qd[k], qdd[k] = self.rates(qk, rates[k], accelerations[k])
        return q, qd, qdd

    def rates(self, q: Array, pose_rates: Array, pose_accelerations: Array) -> tuple[Array, Array]:
        """qd, qdd at q from the bodies' pose rates and accelerations: pose' = J qd, pose'' = J qdd + dJ/dt qd."""
        J = np.asarray(self.pose_jac(q), dtype=float)
        qd = np.linalg.lstsq(J, pose_rates, rcond=None)[0]
        bias = np.asarray(self.pose_bias(q, qd), dtype=float).ravel()
        return qd, np.linalg.lstsq(J, pose_accelerations - bias, rcond=None)[0]


POSE_TOL, POSE_MAX_ITER = 1e-13, 30
_KINEMATICS: dict[Mechanism, Kinematics] = {}


def _kinematics(mech: Mechanism) -> Kinematics:
    """The description of ``mech`` and its bound kinematics (kept per mechanism)."""
    if mech not in _KINEMATICS:
        _KINEMATICS[mech] = _make_kinematics(mech.description)
    return _KINEMATICS[mech]


def _make_kinematics(d: Description) -> Kinematics:
    subs = {getattr(d.p, k): sp.Float(v) for k, v in d.values.items()}
    q = list(d.q)
    _, _, placed, _ = poses(d, "relative")
    angle, grad, jac, rows, pose = {}, {}, {}, [], []
    for b in d.bodies:
        r, th = placed[b]
        th = sp.sympify(th).xreplace(subs)
        g = sp.Matrix([th]).jacobian(q)
        angle[b] = sp.lambdify([q], th, "math")
        grad[b] = sp.lambdify([q], g, "numpy")
        jac[b] = sp.lambdify([q], r.xreplace(subs).jacobian(q), "numpy")
        rows.append(g)
        pose += [*r.xreplace(subs), th]
    a = sp.Matrix.vstack(*rows)
    if not a.free_symbols & set(q) and a.rank() == len(q):
        return Kinematics(d, subs, angle, grad, jac, np.array(a.pinv().evalf(), dtype=float))
    qd = sp.symbols(f"qd0:{len(q)}")
    P = sp.Matrix(pose)
    JP = P.jacobian(q)
    bias = (JP * sp.Matrix(qd)).jacobian(q) * sp.Matrix(qd)
    if JP.subs({s: 0.1 * (i + 1) for i, s in enumerate(q)}).rank() != len(q):
        raise ValueError(f"mechanism {d.name!r}: the bodies' poses do not determine its coordinates (pose Jacobian "
                         f"of rank < {len(q)}), so an Exudyn result cannot be mapped back to them")
    return Kinematics(d, subs, angle, grad, jac, None, sp.lambdify([q], P, "numpy"), sp.lambdify([q], JP, "numpy"),
                      sp.lambdify([q, qd], bias, "numpy"))


def body_states(mech: Mechanism | ParameterSet, q, qd) -> dict[str, BodyState]:
    """COM position, angle and their rates of every body at (q, qd) through the description's kinematics."""
    mech = as_mechanism(mech)
    k = _kinematics(mech)
    eom = mech.equations()
    q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
    out = {}
    for b in k.d.bodies:
        pos = np.asarray(eom.points[f"{b}.com"](q), dtype=float).ravel()
        vel = np.asarray(k.com_jac[b](q), dtype=float) @ qd
        omega = float(np.asarray(k.angle_grad[b](q), dtype=float).ravel() @ qd)
        out[b] = BodyState((float(pos[0]), float(pos[1])), float(k.angle[b](q)), (float(vel[0]), float(vel[1])),
                           omega)
    return out


def _rotation(a) -> Array:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s], [s, c]])


#: How a friction law that reads a joint reaction (a guide's normal force, a pin's |R|) is evaluated.
REACTION_LAW_EVALUATION = ("Python user function (reads the joint reaction through mbs.GetObjectOutput; no Exudyn "
                           "element or symbolic user function has access to it)")


# --------------------------------------------------------------------------------------------
# load laws: lambdified once, evaluated from Exudyn's kinematics (live) or from its body series
# --------------------------------------------------------------------------------------------
#: sympy function names -> Exudyn symbolic functions, for laws recorded as symbolic user functions
_ESYM = {name: getattr(building.esym, name) for name in ("sin", "cos", "tan", "tanh", "sinh", "cosh", "exp", "log",
                                                        "sqrt", "atan", "atan2", "asin", "acos", "sign")}
_ESYM["Abs"] = building.esym.abs


class Law:
    """Expressions in the description's inputs, t and mode symbols, with the parameter values bound."""

    def __init__(self, d: Description, subs: dict, exprs):
        exprs = [sp.sympify(e).xreplace(subs).xreplace(_ground_values(d, subs)) for e in exprs]
        self.exprs = exprs
        syms = set().union(*(e.free_symbols for e in exprs))
        switches = [(name, sp.sympify(e).xreplace(subs), m) for name, e, m in d.switches if m in syms]
        inputs = syms | set().union(set(), *(e.free_symbols for _, e, _ in switches))
        self.inputs = [s for s in d.inputs if s in inputs]          # description order
        self.kinds = [d.inputs[s] for s in self.inputs]
        self.modes = [m for _, _, m in switches]
        self.constant = not syms                                   # no input, t or mode left
        args = [d.t, *self.inputs]
        self.f = sp.lambdify([*args, *self.modes], exprs, "math")
        self.switch_f = [sp.lambdify(args, e, "math") for _, e, _ in switches]
        self.values = [float(e) for e in exprs] if self.constant else None
        self._args = [*args, *self.modes]
        self._switch_exprs = [e for _, e, _ in switches]

    def __call__(self, t: float, inputs) -> list[float]:
        modes = [1.0 if s(t, *inputs) >= 0 else -1.0 for s in self.switch_f]
        return self.f(t, *inputs, *modes)

    def symbolic(self):
        """The law as a function of Exudyn symbolic values (``exudyn.symbolic``), for recording a symbolic
        user function: same arguments as ``__call__``; a mode is IfThenElse(switch >= 0, 1, -1), the
        same rule as the Python evaluation."""
        esym = building.esym
        f = sp.lambdify(self._args, self.exprs, modules=[_ESYM])
        switch_f = [sp.lambdify(self._args[:1 + len(self.inputs)], e, modules=[_ESYM]) for e in self._switch_exprs]

        def evaluate(t, inputs):
            modes = [esym.IfThenElse(s(t, *inputs) >= 0, esym.Real(1.0), esym.Real(-1.0)) for s in switch_f]
            return f(t, *inputs, *modes)
        return evaluate


def _ground_values(d: Description, subs: dict) -> dict:
    """The inputs of ground points as the numbers they are (a fixed point's position; velocity 0), so a
    law between a body point and a ground point reads only the body point (e.g. Andrews' spring)."""
    values = {}
    for sym, inp in d.inputs.items():
        if inp.body == GROUND:
            x, y = d.ground_points[inp.point]
            values[sym] = {"x": x, "y": y}.get(inp.kind, sp.Integer(0))
    return {k: sp.sympify(v).xreplace(subs) for k, v in values.items()}


class Readers:
    """Live readers of the description's inputs from Exudyn (markers and nodes)."""

    def __init__(self, model: Model, markers: dict, refs: dict):
        self.model, self.markers, self.refs = model, markers, refs

    def reader(self, law: Law):
        mbs_reads = []
        for inp in law.kinds:
            if inp.point is not None:
                marker = self.markers[(inp.body, inp.point)]
                ovt = OVT.Position if inp.kind in ("x", "y") else OVT.Velocity
                k = 0 if inp.kind in ("x", "vx") else 1
                mbs_reads.append(lambda mbs, m=marker, o=ovt, k=k: mbs.GetMarkerOutput(m, o)[k])
            elif inp.kind == "angle":
                node, ref = self.model.node(inp.body), self.refs[inp.body]
                mbs_reads.append(lambda mbs, n=node, r=ref: r + mbs.GetNodeOutput(n, OVT.Coordinates)[2])
            else:
                node = self.model.node(inp.body)
                mbs_reads.append(lambda mbs, n=node: mbs.GetNodeOutput(n, OVT.AngularVelocity)[2])
        return lambda mbs: [r(mbs) for r in mbs_reads]


def _series_inputs(law: Law, d: Description, subs: dict, pos: dict, vel: dict) -> list[Array]:
    """The law's inputs at every step from Exudyn's body series (COM pose and rates)."""
    out = []
    for inp in law.kinds:
        if inp.point is None:
            out.append(pos[inp.body][:, 2] if inp.kind == "angle" else vel[inp.body][:, 2])
        else:
            out.append(_point_series(d, subs, pos, vel, inp.body, inp.point)[inp.kind])
    return out


def _point_series(d: Description, subs: dict, pos: dict, vel: dict, body: str, point: str) -> dict[str, Array]:
    """Global position and velocity of a body point (or a ground point) at every step from the body's COM
    pose and rates."""
    if body == GROUND:
        x, y = (float(sp.sympify(c).xreplace(subs)) for c in d.ground_points[point])
        n = len(next(iter(pos.values())))
        return {"x": np.full(n, x), "y": np.full(n, y), "vx": np.zeros(n), "vy": np.zeros(n)}
    local = np.array([float(sp.sympify(c).xreplace(subs)) for c in d.bodies[body].points[point]])
    th, w = pos[body][:, 2], vel[body][:, 2]
    rx = np.cos(th) * local[0] - np.sin(th) * local[1]
    ry = np.sin(th) * local[0] + np.cos(th) * local[1]
    return {"x": pos[body][:, 0] + rx, "y": pos[body][:, 1] + ry, "vx": vel[body][:, 0] - w * ry,
            "vy": vel[body][:, 1] + w * rx}


def _law_series(law: Law, t: Array, inputs: list[Array]) -> Array:
    """(n, k) values of the law at every step (mode = sign of the switching function at the state)."""
    if law.constant:
        return np.tile(np.asarray(law.values, dtype=float), (len(t), 1))
    return np.array([law(ti, [x[i] for x in inputs]) for i, ti in enumerate(t)], dtype=float)


# --------------------------------------------------------------------------------------------
# the built model
# --------------------------------------------------------------------------------------------
def _active(d: Description, j: Prismatic | Revolute) -> bool:
    """A contact or pin whose friction law is not identically zero (kinetic coefficient or resistance > 0)."""
    if j.friction is None:
        return False
    subs = {getattr(d.p, k): sp.Float(v) for k, v in d.values.items()}
    return float(j.friction.mu_kinetic.xreplace(subs)) > 0 or float(j.friction.resistance.xreplace(subs)) > 0


def loads_jacobian(d: Description) -> int:
    """``computeLoadsJacobian``: 2 when the description has an active friction contact or pin, else 0.

    The regularized friction and resistance tanh(v/eps) need their derivative in the Newton matrix
    (without it Newton diverges, see settings.simulation_settings); the frictionless runs of such a
    mechanism (``friction='none'``) keep the same setting, so the two differ only by the friction
    itself. Without friction the other laws do not need it: for the study's steepest smooth law (a tanh-ramped force)
    the Newton iteration counts with and without the load Jacobian agree within 0.5 % (20 s,
    h = 1e-3: 55 962 vs 55 735) while the extra user-function calls per iteration double the CPU
    time; an on/off law is piecewise constant, its numerical derivative across a switch meaningless.
    """
    return 2 if any(_active(d, j) for j in [*d.contacts(), *d.pins()]) else 0


@dataclass
class Built:
    mech: Mechanism
    d: Description
    kin: Kinematics
    model: Model
    friction: str
    eps: float
    loads_jacobian: int
    configuration: str = "python"
    laws: dict = field(default_factory=dict)          # load name -> Law
    evaluation: dict = field(default_factory=dict)    # law name -> how Exudyn evaluates it
    potentials: dict = field(default_factory=dict)    # potential name -> Law (energy)
    frictions_by_contact: dict = field(default_factory=dict)
    frictions_by_pin: dict = field(default_factory=dict)
    normals: dict = field(default_factory=dict)       # prismatic joint -> n in the guide's body frame
    q0: Array = None                                  # the relative coordinates of the reference configuration

    @property
    def frictions(self) -> list[RecordedFriction]:
        return [*self.frictions_by_contact.values(), *self.frictions_by_pin.values()]

    # --- lam mapping -----------------------------------------------------------------------------
    def _row_sources(self, names) -> list[tuple[str, int | None]]:
        joints = {j.name: j for j in self.d.joints}
        out = []
        for row in names:
            if row in joints and isinstance(joints[row], (Prismatic, Distance)):
                out.append((row, None))
            elif row[-2:] in ("_x", "_y") and isinstance(joints.get(row[:-2]), Revolute):
                out.append((row[:-2], 0 if row.endswith("_x") else 1))
            else:
                raise ValueError(f"constraint row {row!r} has no Exudyn counterpart (supported: revolute <J>_x/_y, "
                                 f"prismatic gap <J>, distance <J>)")
        return out

    def _lam(self, outputs: dict[str, Array], names, lead: tuple = ()) -> Array:
        """lam (*lead, r) from joint outputs (revolute 'Force', prismatic 'ForceLocal'), in-house convention."""
        if not len(names):
            return np.zeros((*lead, 0))
        cols = []
        for joint, k in self._row_sources(names):
            f = outputs[joint]
            if k is not None:                # revolute: minus the force on the marker-0 body
                cols.append(-f[..., k])
            elif joint in self.normals:      # prismatic: the local force along the normal
                cols.append(f[..., 0] * self.normals[joint][0] + f[..., 1] * self.normals[joint][1])
            else:                            # distance: its force is the multiplier of its row
                cols.append(f[..., 0])
        return np.stack(cols, axis=-1)

    def initial_values(self) -> tuple[Array, Array]:
        eom = self.mech.equations()
        acc = np.array([self.model.node_output(b, OVT.Coordinates_tt) for b in self.d.bodies], dtype=float)
        outputs = {j.name: self.model.joint_output(j.name) for j in self.d.joints}
        if self.kin.pinv is not None:
            qdd = self.kin.pinv @ acc[:, 2]
        else:
            vel = np.array([self.model.node_output(b, OVT.Coordinates_t) for b in self.d.bodies], dtype=float)
            qdd = self.kin.rates(self.q0, vel.ravel(), acc.ravel())[1]
        return qdd, self._lam(outputs, eom.constraint_names)

    # --- result ----------------------------------------------------------------------------------
    def result(self, eom, grid: settings.RunGrid, solver: str, stats: dict) -> SimulationResult:
        d, subs = self.d, self.kin.subs
        t = grid.h * np.arange(grid.n_steps + 1)
        pos, vel, acc, disp = {}, {}, {}, {}
        for b in d.bodies:
            pos[b], vel[b], acc[b] = self.model.body_series(b, grid)
            disp[b] = self.model.series((b, "coordinates"), grid)   # displacement from the reference
        if self.kin.pinv is not None:
            angles = lambda series: np.column_stack([series[b][:, 2] for b in d.bodies])  # noqa: E731
            q = self.q0 + angles(disp) @ self.kin.pinv.T      # q(0) = q0 exactly (zero displacement)
            qd = angles(vel) @ self.kin.pinv.T
            qdd = angles(acc) @ self.kin.pinv.T
        else:
            poses_of = lambda series: np.hstack([series[b] for b in d.bodies])  # noqa: E731
            q, qd, qdd = self.kin.coordinates(self.q0, poses_of(pos), poses_of(vel), poses_of(acc))
        outputs = {j.name: self.model.series((j.name, "force"), grid) for j in d.joints}
        lam = self._lam(outputs, eom.constraint_names, (len(t),))
        rows = list(eom.constraint_names)

        forces, works = {}, {}
        guides = {j.slider[0]: j for j in d.joints if isinstance(j, Prismatic)}
        for name, law in self.laws.items():
            load = next(ld for ld in d.loads if ld.name == name)
            values = _law_series(law, t, _series_inputs(law, d, subs, pos, vel))
            if load.point is None:
                forces[name] = values[:, 0]
                works[name] = values[:, 0] * vel[load.body][:, 2]
                continue
            pv = _point_series(d, subs, pos, vel, load.body, load.point)
            works[name] = values[:, 0] * pv["vx"] + values[:, 1] * pv["vy"]
            direction = self._axis_series(guides[load.body], pos) if load.body in guides else \
                np.tile([1.0, 0.0], (len(t), 1))
            forces[name] = values[:, 0] * direction[:, 0] + values[:, 1] * direction[:, 1]

        for j in d.contacts():
            if j.name in rows:
                forces[f"normal_{j.name}"] = -lam[:, rows.index(j.name)]
            if not _active(d, j):
                continue
            fric = self.frictions_by_contact.get(j.name)
            if fric is not None:
                hist = solve.friction_history(fric, grid, stats)
                coulomb, resistance, v_t = hist[:, 2], hist[:, 3], hist[:, 1]
            else:
                coulomb = resistance = v_t = np.zeros_like(t)
            forces[f"friction_{j.name}"] = coulomb
            if j.friction.resistance != 0:
                forces[f"resistance_{j.name}"] = resistance
            works[f"friction_{j.name}"] = (coulomb + resistance) * v_t
        for j in d.pins():
            forces[f"normal_{j.name}"] = np.hypot(outputs[j.name][:, 0], outputs[j.name][:, 1])
            if not _active(d, j):
                continue
            fric = self.frictions_by_pin.get(j.name)
            if fric is not None:
                hist = solve.friction_history(fric, grid, stats)
                omega, tau = hist[:, 1], hist[:, 2]
            else:
                omega = tau = np.zeros_like(t)
            forces[f"friction_{j.name}"] = tau
            works[f"friction_{j.name}"] = tau * omega
        for j in d.joints:
            f = outputs[j.name]
            if isinstance(j, Revolute):
                forces[f"joint_{j.name}_x"], forces[f"joint_{j.name}_y"] = -f[:, 0], -f[:, 1]
            elif isinstance(j, Distance):
                forces[f"joint_{j.name}_tension"] = f[:, 0]
            else:
                n = self.normals[j.name]
                forces[f"joint_{j.name}_n"] = -(f[:, 0] * n[0] + f[:, 1] * n[1])

        bodies = {b: (float(body.mass.xreplace(subs)), float(body.inertia.xreplace(subs)))
                  for b, body in d.bodies.items()}
        g = float(d.gravity_g.xreplace(subs)) if d.gravity_g is not None else 0.0
        kinetic, potential = solve.body_energies(bodies, pos, vel, g)
        for law in self.potentials.values():
            potential = potential + _law_series(law, t, _series_inputs(law, d, subs, pos, vel))[:, 0]

        active = [j for j in d.contacts() if _active(d, j)]
        active_pins = [j for j in d.pins() if _active(d, j)]
        meta = {
            "description": d.name,
            "loads_jacobian": self.loads_jacobian,
            "law_evaluation": dict(self.evaluation),
            "lam_mapping": self.lam_mapping(rows),
            "reaction_reading": ("hybrid guard: live Newton iterate of the guide's or pin's reaction, last accepted "
                                 "value while the live one is the zero of the first Newton iteration; initial "
                                 "accelerations use the fixed-point seeded reaction") if self.frictions else "not used",
            "force_conventions": self.force_conventions(forces),
            "load_evaluation": "laws lambdified with the parameter values bound, evaluated in Exudyn user functions "
                               "from marker positions/velocities and node angles/rates; a mode is the sign of its "
                               "switching function at the current state (no event location); the recorded "
                               "'<load>' series are the laws evaluated on the converged states",
        }
        if active or active_pins:
            meta["work_friction"] = ("work_friction_<c>: Coulomb plus resistance (the whole tangential guide force); "
                                     "work_friction_<p>: the pin's torque tau times omega_rel (Coulomb plus T0)")
        friction = self.friction if active or active_pins else \
            "none (no friction contact or pin with mu_k > 0 or resistance > 0)"
        return solve.assemble_result(eom, self.mech.parameters, grid, solver, self.eps, friction, t=t, q=q, qd=qd, qdd=qdd,
                                      lam=lam, kinetic=kinetic, potential=potential, works=works, forces=forces,
                                      stats=stats, meta=meta)

    def _axis_series(self, j: Prismatic, pos: dict) -> Array:
        axis = np.array([float(sp.sympify(c).xreplace(self.kin.subs)) for c in j.axis])
        if j.guide[0] == GROUND:
            return np.tile(axis, (len(next(iter(pos.values()))), 1))
        th = pos[j.guide[0]][:, 2]
        return np.column_stack([np.cos(th) * axis[0] - np.sin(th) * axis[1],
                                np.sin(th) * axis[0] + np.cos(th) * axis[1]])

    def lam_mapping(self, rows) -> str:
        parts = []
        for row, (joint, k) in zip(rows, self._row_sources(rows)):
            if k is not None:
                parts.append(f"{row} = -Force_{'xy'[k]} of RevoluteJoint2D '{joint}' (force on its second body, "
                             f"global)")
            elif joint not in self.normals:
                parts.append(f"{row} = Force of DistanceConstraint '{joint}' (its multiplier: the rod's tension)")
            else:
                n = self.normals[joint]
                parts.append(f"{row} = ForceLocal . ({n[0]:g}, {n[1]:g}) of PrismaticJoint2D '{joint}' (force on "
                             f"the guide body in the guide's body frame, along the joint normal)")
        return "; ".join(parts)

    def force_conventions(self, forces) -> dict[str, str]:
        out = {}
        pins = {j.name for j in self.d.pins()}
        for key in forces:
            if key.startswith("normal_") and key[7:] in pins:
                out[key] = f"magnitude |R| of the reaction of revolute joint '{key[7:]}' (its Exudyn 'Force')"
            elif key.startswith("friction_") and key[9:] in pins:
                out[key] = (f"friction torque on the first body of revolute joint '{key[9:]}', "
                            f"-(mu_k r sqrt(|R|^2 + delta^2) + T0) tanh(omega_rel/eps) (its opposite on the second)")
            elif key.startswith("normal_"):
                out[key] = f"force on the slider along the normal of '{key[7:]}' = -lam of its row"
            elif key.startswith("friction_"):
                out[key] = f"Coulomb force on the slider along the axis of '{key[9:]}', -mu_k |N| tanh(v_t/eps)"
            elif key.startswith("resistance_"):
                out[key] = f"resistance on the slider along the axis of '{key[11:]}', -F tanh(v_t/eps)"
            elif key.startswith("joint_") and key.endswith("_n"):
                out[key] = "force of the prismatic joint on its slider along the joint normal (= -lam of its row)"
            elif key.startswith("joint_") and key.endswith("_tension"):
                out[key] = "tension of the distance constraint (= lam of its row; > 0 pulls its points together)"
            elif key.startswith("joint_"):
                out[key] = "global force of the revolute joint on its second body b"
            else:
                out[key] = "the load's torque, or its force along the loaded slider's guide axis (else global x)"
        return out


def build(mechanism: Mechanism | ParameterSet, q0, qd0, friction: str = "regularized",
          eps: float = settings.DEFAULT_EPS, configuration: str = "python") -> Built:
    """Assemble the Exudyn model of a mechanism's description at the state (q0, qd0) (relative coordinates).

    ``configuration`` (settings.CONFIGURATIONS): 'python' evaluates every state-dependent law in a
    Python load user function; 'tuned' records it as an Exudyn symbolic user function where the law's
    inputs are those of the element carrying it (:func:`_symbolic_law`), else keeps the Python one, and
    leaves the numerical load Jacobian off unless a Python load remains that needs it (the friction).
    """
    mech = as_mechanism(mechanism)
    kin = _kinematics(mech)
    d, subs = kin.d, kin.subs
    val = lambda e: float(sp.sympify(e).xreplace(subs))  # noqa: E731
    g = val(d.gravity_g) if d.gravity_g is not None else 0.0
    model = Model()
    states = body_states(mech, q0, qd0)
    for b, body in d.bodies.items():
        model.body(b, val(body.mass), val(body.inertia), states[b], g)
    refs = {b: states[b].angle for b in d.bodies}
    markers: dict[tuple[str, str], int] = {}

    def marker(body: str, point: str) -> int:
        if (body, point) not in markers:
            xy = d.ground_points[point] if body == GROUND else d.bodies[body].points[point]
            markers[(body, point)] = model.marker(body, (val(xy[0]), val(xy[1])))
        return markers[(body, point)]

    built = Built(mech, d, kin, model, friction, eps, loads_jacobian(d), configuration)
    built.q0 = np.asarray(q0, dtype=float).copy()
    for j in d.joints:
        if isinstance(j, Revolute):
            model.revolute(j.name, marker(*j.a), marker(*j.b))
            continue
        if isinstance(j, Distance):
            model.distance(j.name, marker(*j.a), marker(*j.b), val(j.length))
            continue
        axis = (val(j.axis[0]), val(j.axis[1]))
        n_guide = np.array([val(j.normal[0]), val(j.normal[1])])
        guide_angle = refs[j.guide[0]] if j.guide[0] != GROUND else 0.0
        slider_angle = refs[j.slider[0]] if j.slider[0] != GROUND else 0.0
        n_slider = _rotation(slider_angle).T @ _rotation(guide_angle) @ n_guide
        model.prismatic(j.name, marker(*j.guide), marker(*j.slider), axis0=axis, normal1=n_slider)
        built.normals[j.name] = (float(n_guide[0]), float(n_guide[1]))

    for inp in d.inputs.values():
        if inp.point is not None:
            marker(inp.body, inp.point)
    readers = Readers(model, markers, refs)

    def com(body: str) -> int:
        key = (body, "__com__")
        if key not in markers:
            markers[key] = model.marker(body, (0.0, 0.0))
        return markers[key]

    for load in d.loads:
        law = Law(d, subs, load.components)
        built.laws[load.name] = law
        m = com(load.body) if load.point is None else marker(load.body, load.point)
        if law.constant:
            if load.point is None:
                model.torque(m, value=law.values[0])
            else:
                model.force(m, value=tuple(law.values))
            built.evaluation[load.name] = "constant load"
            continue
        if configuration == "tuned" and _symbolic_law(model, law, load.body, load.point, m):
            built.evaluation[load.name] = "symbolic user function"
            continue
        model_load = _user_function(law, readers.reader(law), torque=load.point is None)
        (model.torque if load.point is None else model.force)(m, user=model_load)
        built.evaluation[load.name] = "Python user function"

    for pot in d.potentials:
        built.potentials[pot.name] = Law(d, subs, [pot.energy])
        groups: dict[tuple[str, str | None], list] = {}
        for sym in sorted(pot.energy.free_symbols & set(d.inputs), key=str):
            inp = d.inputs[sym]
            if inp.kind not in ("x", "y", "angle"):
                raise ValueError(f"potential {pot.name!r}: energy depends on {inp.kind} of {inp.body!r}; only "
                                 f"positions and angles are allowed")
            groups.setdefault((inp.body, inp.point), []).append((inp.kind, sym))
        for (body, point), syms in groups.items():
            if body == GROUND:   # the reaction on a ground point moves nothing (its inputs are read, not loaded)
                continue
            kinds = dict(syms)
            if point is None:
                law = Law(d, subs, [-sp.diff(pot.energy, kinds["angle"])])
                m = com(body)
            else:
                law = Law(d, subs, [-sp.diff(pot.energy, kinds[k]) if k in kinds else sp.Integer(0) for k in ("x", "y")])
                m = marker(body, point)
            key = f"{pot.name} on {body}" + (f".{point}" if point else "")
            if configuration == "tuned" and _symbolic_law(model, law, body, point, m):
                built.evaluation[key] = "symbolic user function"
                continue
            user = _user_function(law, readers.reader(law), torque=point is None)
            (model.torque if point is None else model.force)(m, user=user)
            built.evaluation[key] = "Python user function"

    if friction == "regularized":
        for j in d.contacts():
            if not _active(d, j):
                continue
            obj = model.joints[j.name][0]
            n = built.normals[j.name]
            # N = force on the slider along the normal = -(ForceLocal . n) (= -lam); only |N| enters
            guard = ReactionGuard(lambda mbs, o=obj, n=n: -(lambda f: f[0] * n[0] + f[1] * n[1])(
                mbs.GetObjectOutput(o, OVT.ForceLocal)))
            axis = (val(j.axis[0]), val(j.axis[1]))       # guide frame (= global on a guide fixed in ground)
            moving = j.guide[0] != GROUND
            fric = GuideFriction(model, marker(*j.slider), axis, guard, mu=val(j.friction.mu_kinetic),
                                 resistance=val(j.friction.resistance), eps=eps,
                                 guide=(model.node(j.guide[0]), refs[j.guide[0]], com(j.guide[0])) if moving else None)
            model.force(marker(*j.slider), user=fric)
            if moving:   # the opposite force on the guide at the slider point: at its centre of mass, plus its moment
                model.force(com(j.guide[0]), user=fric.guide_force)
                model.torque(com(j.guide[0]), user=fric.guide_torque)
            built.frictions_by_contact[j.name] = fric
            built.evaluation[f"friction_{j.name}"] = REACTION_LAW_EVALUATION
        delta = tolerance("pin_friction_norm_width")
        for j in d.pins():
            if not _active(d, j):
                continue
            obj = model.joints[j.name][0]
            guard = ReactionGuard(lambda mbs, o=obj: math.hypot(*mbs.GetObjectOutput(o, OVT.Force)[:2]))
            sides = (j.a[0], j.b[0])
            fric = PinFriction(model, tuple(None if b == GROUND else model.node(b) for b in sides), guard,
                               coefficient=val(j.friction.mu_kinetic) * val(j.radius),
                               resistance=val(j.friction.resistance), eps=eps, delta=delta)
            loaded = [(side, body) for side, body in enumerate(sides) if body != GROUND]
            for k, (side, body) in enumerate(loaded):   # the first load records, the other reads the same state
                model.torque(com(body), user=fric.load(side, record=k == 0))
            built.frictions_by_pin[j.name] = fric
            built.evaluation[f"friction_{j.name}"] = REACTION_LAW_EVALUATION
    if configuration == "tuned" and not built.frictions:
        built.loads_jacobian = 0    # no Python load left whose derivative Newton needs
    model.assemble()
    return built


def _symbolic_law(model: Model, law: Law, body: str, point: str | None, marker: int) -> bool:
    """Record ``law`` as an Exudyn symbolic user function if Exudyn has an element whose user function
    sees exactly the law's inputs, and say whether it did.

    * a force at a body point whose law reads only that point's x, y, vx, vy (and t, modes):
      ObjectConnectorCartesianSpringDamper from the ground origin to the point (Model.point_law);
    * a torque on a body whose law reads only that body's angle and rate (and t, modes):
      ObjectConnectorCoordinateSpringDamper on its rotation coordinate (Model.angle_law).

    Any other law (e.g. a spring between two bodies' points) stays a Python load user function.
    """
    if point is not None and all(k.body == body and k.point == point for k in law.kinds):
        f, kinds = law.symbolic(), [k.kind for k in law.kinds]

        def force(t, pos, vel):
            values = {"x": pos[0], "y": pos[1], "vx": vel[0], "vy": vel[1]}
            return f(t, [values[k] for k in kinds])
        model.point_law(marker, force)
        return True
    if point is None and all(k.body == body and k.point is None for k in law.kinds):
        f, kinds = law.symbolic(), [k.kind for k in law.kinds]

        def torque(t, angle, rate):
            return f(t, [angle if k == "angle" else rate for k in kinds])[0]
        model.angle_law(body, torque)
        return True
    return False


def _user_function(law: Law, read, torque: bool):
    f = law

    if torque:
        def user(mbs, t, load_vector):
            return [0.0, 0.0, f(t, read(mbs))[0]]
    else:
        def user(mbs, t, load_vector):
            fx, fy = f(t, read(mbs))
            return [fx, fy, 0.0]
    return user


def run(mechanism: Mechanism | ParameterSet, t_end: float, h: float, solver: str = "index3",
        output_step: float | None = None, friction: str = "regularized", eps: float = settings.DEFAULT_EPS,
        configuration: str = "python", ignore_singular: bool = False, linear_solver: str = "dense",
        newton_tolerance: float = settings.NEWTON_TOLERANCE) -> SimulationResult:
    """Simulate a mechanism in Exudyn from the in-house consistent initial state.

    Parameters
    ----------
    mechanism : study.Mechanism (a description with its parameter set), or a study mechanism's ParameterSet
    t_end : float
        End time [s], a whole number of steps.
    h : float
        Fixed step [s].
    solver : {'index3', 'index2'} (or an explicit name, which Exudyn refuses; see settings.SOLVERS)
    output_step : float, optional
        Sampling of the result, a whole multiple of h; default every step.
    friction : {'regularized', 'none'}
        'none' leaves out the Coulomb friction and resistance of every contact and pin.
    eps : float
        Velocity scale of tanh(v/eps) in the friction and resistance laws [m/s] (settings.DEFAULT_EPS); a pin's
        law reads the same number in rad/s (tanh(omega_rel/eps)), as the in-house friction_eps.
    configuration : {'python', 'tuned'}
        How Exudyn evaluates the load laws and iterates (settings.CONFIGURATIONS); both solve the same
        model, 'tuned' as Exudyn recommends for speed.
    ignore_singular : bool
        Exudyn's option for redundant constraints / singular poses (settings.simulation_settings); dense
        linear solver only.
    linear_solver : {'dense', 'sparse'}
        The linear solver of Newton's iteration (settings.LINEAR_SOLVERS): Exudyn's dense inverse, or Eigen's
        sparse LU, which Exudyn recommends for larger systems (e.g. the N-four-bar at N = 40).
    newton_tolerance : float
        Relative and absolute tolerance of Newton's iteration (default settings.NEWTON_TOLERANCE). A run whose
        residual cannot reach it (a round-off floor at a singular pose) stops with exudyn.SolverError.

    Returns
    -------
    SimulationResult (see the module docstring for the mapping of every quantity)
    """
    return solve.run_model(build, as_mechanism(mechanism), t_end, h, solver, output_step, friction, eps, configuration,
                           ignore_singular, linear_solver, newton_tolerance)


def initial_accelerations(mechanism: Mechanism | ParameterSet, q, qd, friction: str = "regularized",
                          eps: float = settings.DEFAULT_EPS) -> tuple[Array, Array]:
    """Exudyn's accelerations and multipliers at a state (relative coordinates), from its solver
    initialization alone: the initial-acceleration solve SolveDynamic performs at t = 0 (with the seeded
    normal force if friction is on), mapped to the in-house coordinates and multiplier convention.

    Returns
    -------
    qdd : (m,) array
    lam : (r,) array, in ``eom.constraint_names`` order
    """
    return solve.initial_accelerations(build, as_mechanism(mechanism), q, qd, friction, eps)
