"""The regularized Coulomb friction in a spatial description's revolute and prismatic joints
(:class:`study.spatial.elements.JointFriction`) in its Exudyn model (:mod:`study.exudyn_models.spatial`), the run
options it takes, and what the result reads of it.

The law is the planar models' regularized one (:mod:`study.exudyn_models.friction`), from its one home: the level
:func:`study.laws.friction.friction_level` and the smooth norm :func:`study.laws.friction.pin_norm` (``py_func``) and
the sign ``study.kernels.signs.SIGN_FUNCTIONS['tanh']``, as :mod:`study.exudyn_models.guards` binds them:

* revolute joint: the torque tau = -(mu_k r |R_t|_delta + T0) tanh(omega_rel / eps) about the joint's axis u on
  body a and -tau u on body b;
* prismatic joint: the force f = -(mu_k |N|_delta + F0) tanh(v_rel / eps) along u at point a of body a and -f u at
  point b of body b (the line through point b along u carries point a, by the joint's two transverse rows, so this
  is the same load as at body b's material point under point a, up to the rows' residual);

|x|_delta = sqrt(|x|^2 + delta^2), delta = ``pin_friction_norm_width`` (reference/tolerances.toml); eps [m/s for a
slide, rad/s for a pin]; nothing is applied to ground. Only the regularized law exists here: ``mu_static`` is not
read (the regularized law has no stick), 'exact' and 'sign' are refused by name (:func:`check_options`).

Exudyn's outputs of the joint (an ObjectJointGeneric, marker 0 on body b with the joint frame R_b whose z column is
the axis, :func:`study.spatial.joints.joint_frames`; Exudyn's CObjectJointGeneric::GetOutputVariableConnector, J0 =
marker 0's frame), read through ``mbs.GetObjectOutput`` in the load user functions:

* ForceLocal: the multipliers of the three translation rows in J0 components. A revolute locks all three
  translations, whose rows Exudyn writes in global components: it turns the multipliers into J0 by A_J0^T. A
  prismatic's two transverse rows are written in J0: their own multipliers (the free axis' entry is 0). Either way
  its x and y are the reaction across the axis, the 2-vector R_t (revolute) or N (prismatic); the axial component
  (a revolute's thrust) carries no friction.
* VelocityLocal z = u . (v_a - v_b), the velocities of the two marker points: the sliding velocity (the rate of the
  slide u . (p_a - p_b), as p_a - p_b lies along u on the joint's rows).
* AngularVelocityLocal z = u . (omega_a - omega_b): omega_rel about the axis.

u in global components is A_b R_b e_z, from body b's node (its RotationMatrix output; ground: R_b e_z itself).

What the reaction is (no lag at a converged step): Exudyn's ForceLocal reads the joint's current algebraic
coordinates (GetCurrentAEcoordinate), the current Newton iterate of the multipliers. They are exactly 0 at the first
Newton iteration of every step, in its residual and in the loads' numerical Jacobian (measured on the sliding block
of tests/test_spatial_friction_exudyn.py: 16 of the 33 user-function calls of a step read 0, the others the live
iterate), and during the initial-acceleration solve. A :class:`~study.exudyn_models.guards.ReactionGuard` then
substitutes the value of the last accepted step, and :func:`~study.exudyn_models.guards.seed_reaction_guards`
iterates the initial-acceleration solve to the consistent reaction at t = 0. Every later iteration uses the live
iterate, so a converged step satisfies the law with its own converged reaction. Newton's matrix holds the loads'
numerical derivative with respect to the positions and velocities (``computeLoadsJacobian`` 2, as the planar
friction needs for tanh(v/eps)) but not with respect to the multipliers: the iteration takes one more pass to
settle the reaction (the block: 2 Newton iterations per step, 1 with friction='none').

The result (:func:`friction_results`): ``normal_<joint>`` = |(ForceLocal_x, ForceLocal_y)| of the converged step (a
sensor, with and without the friction), ``friction_<joint>`` = tau or f on body a (the law's value at the recorded
converged evaluation, Coulomb and resistance together), ``work_friction_<joint>`` = the trapezoidal integral of its
power tau omega_rel or f v_rel; zeros for friction='none'. The norm rows' multipliers (in-house convention,
:func:`study.exudyn_models.spatial.norm_multipliers`) add each friction force's part along p: a force F at a body
point P has p . Q_p = 2 (P - r) . F (A(p) is homogeneous quadratic in p), a torque none (E p = G p = 0).
"""

from __future__ import annotations

import numpy as np
from exudyn.itemInterface import LoadForceVector, LoadTorqueVector, MarkerBodyPosition, MarkerBodyRigid

import study.exudyn_models.settings as settings
import study.exudyn_models.solve as solve
from study.exudyn_models.building import OVT
from study.exudyn_models.guards import ReactionGuard, RecordedFriction, joint_friction, reaction_norm
from study.spatial.elements import GROUND, JointFriction, Prismatic
from study.spatial.joints import joint_frames

Array = np.ndarray

#: the Exudyn run's friction options a description without friction takes: the regularized law (the Exudyn
#: specification's default) and none are the same frictionless model
FRICTIONLESS = settings.FRICTION_MODES
FRICTION_LAW = ("regularized Coulomb friction in the joints (study.exudyn_models.spatial_friction): revolute "
                "-(mu_k r |R_t|_delta + T0) tanh(omega_rel/eps) about the axis, prismatic -(mu_k |N|_delta + F0) "
                "tanh(v_rel/eps) along it, R_t and N the joint's ForceLocal across the axis")
REACTION_READING = ("Python load user functions reading the joint's ForceLocal (GetObjectOutput): the current Newton "
                    "iterate, the last accepted step's value at a step's first iteration (where Exudyn's multipliers "
                    "are 0), the initial-acceleration solve seeded to the consistent reaction; no lag at a converged "
                    "step")


def check_options(d, friction: str, eps: float) -> None:
    """Refuse by name the friction options that mean nothing for description ``d``: without friction, any mode but
    FRICTIONLESS and any eps but the default; with friction, 'exact' and 'sign' (Exudyn has the regularized law
    only) and an eps with friction='none' (no law for it to act in). Other values are checked by
    :func:`study.exudyn_models.settings.check_arguments`."""
    if not d.frictions:
        if friction not in FRICTIONLESS:
            raise ValueError(f"friction = {friction!r}: {d.name} is spatial and has no friction entries; "
                             f"valid choices: {', '.join(FRICTIONLESS)}")
        if eps != settings.DEFAULT_EPS:
            raise ValueError(f"eps = {eps!r}: {d.name} is spatial and has no friction entries for a width to "
                             f"apply to; leave eps at its default {settings.DEFAULT_EPS}")
        return
    if friction not in settings.FRICTION_MODES:
        raise ValueError(f"friction = {friction!r}: the Exudyn model of {d.name}'s joint friction (in "
                         f"{sorted(d.frictions)}) has the regularized law only; valid choices: "
                         f"{', '.join(settings.FRICTION_MODES)}")
    if friction == "none" and eps != settings.DEFAULT_EPS:
        raise ValueError(f"eps = {eps!r}: friction = 'none' leaves the friction of {d.name}'s joints out, so no "
                         f"width applies; leave eps at its default {settings.DEFAULT_EPS}")


def active(f: JointFriction) -> bool:
    """A joint friction whose law is not identically zero (kinetic coefficient or resistance > 0)."""
    return f.mu_kinetic > 0 or f.resistance > 0


def loads_jacobian(d) -> int:
    """``computeLoadsJacobian``: 2 when ``d`` has an active joint friction (with either friction option, so that
    'none' differs from 'regularized' by the friction alone, as in the planar models), else 0 (as without friction)."""
    return 2 if any(active(f) for f in d.frictions.values()) else 0


class SpatialJointFriction(RecordedFriction):
    """The regularized friction of one revolute or prismatic joint (module docstring): its value on body a at the
    current state, the global axis, and the load user functions of both bodies. ``history`` rows: [|R_t| or |N|
    used, omega_rel or v_rel, tau or f, u_x, u_y, u_z]."""

    def __init__(self, model, joint: int, prismatic: bool, axis_node: int | None, axis: Array, coefficient: float,
                 resistance: float, eps: float, delta: float):
        guard = ReactionGuard(reaction_norm(joint, OVT.ForceLocal))
        super().__init__(model, guard, 6)
        self.joint, self.axis_node, self.axis = joint, axis_node, tuple(float(c) for c in axis)
        self.rate = OVT.VelocityLocal if prismatic else OVT.AngularVelocityLocal
        self.coefficient, self.resistance = float(coefficient), float(resistance)
        self.eps, self.delta = float(eps), float(delta)

    def global_axis(self, mbs) -> tuple[float, float, float]:
        """u = A_b R_b e_z (ground: R_b e_z); Exudyn's RotationMatrix is row-major."""
        if self.axis_node is None:
            return self.axis
        a, (x, y, z) = mbs.GetNodeOutput(self.axis_node, OVT.RotationMatrix), self.axis
        return a[0] * x + a[1] * y + a[2] * z, a[3] * x + a[4] * y + a[5] * z, a[6] * x + a[7] * y + a[8] * z

    def evaluate(self, mbs, record: bool) -> tuple[float, tuple[float, float, float]]:
        """(tau or f on body a, u) at the current state; ``record``: count the guard's call and keep ``last``."""
        rate = mbs.GetObjectOutput(self.joint, self.rate)[2]
        reaction = self.guard.value(mbs) if record else self.guard.peek(mbs)
        value = joint_friction(self.coefficient, reaction, self.delta, self.resistance, rate, self.eps)
        u = self.global_axis(mbs)
        if record:
            self.last = (reaction, rate, value, *u)
        return value, u

    def load(self, sign: float, record: bool):
        """The load user function of body a (``sign`` 1) or body b (-1): sign * value * u, global components. One
        load of the joint records; the other evaluates the same state and reaction without counting."""
        def user(mbs, t, load_vector):
            value, u = self.evaluate(mbs, record)
            return [sign * value * u[0], sign * value * u[1], sign * value * u[2]]
        return user


def add_joint_friction(b, j, f: JointFriction, eps: float, delta: float) -> SpatialJointFriction:
    """The friction loads of joint ``j`` (revolute or prismatic) in the built model ``b``
    (:class:`study.exudyn_models.spatial.SpatialBuilt`): a torque at the centre of mass of each of its bodies, or a
    force at each body's joint point; nothing on ground."""
    mbs, prismatic = b.model.mbs, isinstance(j, Prismatic)
    _, frame_b = joint_frames(b.d, j)
    fric = SpatialJointFriction(b.model, b.joints[j.name], prismatic, None if j.body_b == GROUND else
                                b.nodes[j.body_b], frame_b[:, 2], f.mu_kinetic * (1.0 if prismatic else f.radius),
                                f.resistance, eps, delta)
    sides = [(body, point, sign) for body, point, sign in ((j.body_a, j.a, 1.0), (j.body_b, j.b, -1.0))
             if body != GROUND]
    for k, (body, point, sign) in enumerate(sides):   # the first load records, the other reads the same state
        user = fric.load(sign, record=k == 0)
        if prismatic:
            local = [float(v) for v in b.d.bodies[body].points[point]]
            marker = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b.objects[body], localPosition=local))
            mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=[0.0, 0.0, 0.0], loadVectorUserFunction=user))
        else:
            marker = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b.objects[body], localPosition=[0.0, 0.0, 0.0]))
            mbs.AddLoad(LoadTorqueVector(markerNumber=marker, loadVector=[0.0, 0.0, 0.0], loadVectorUserFunction=user))
    return fric


def friction_results(b, eom, q: Array, series: dict, grid: settings.RunGrid, stats: dict) -> tuple[dict, dict, dict]:
    """(forces, powers, radial) of the description's joint frictions (module docstring): ``forces`` and ``powers``
    (the friction's power tau omega_rel or f v_rel, whose integral is ``work_friction_<joint>``) at every step,
    ``radial`` (norm-row index -> p . Q_p of the friction forces) at the output steps, whose coordinates are ``q``;
    the friction user functions' call counts summed into ``stats``."""
    joints = {j.name: j for j in b.d.joints}
    names, rows = list(b.d.bodies), list(eom.constraint_names)
    forces, powers, radial = {}, {}, {}
    for name, f in b.d.frictions.items():
        forces[f"normal_{name}"] = np.hypot(*series[(name, "reaction")][:, :2].T)
        if not active(f):
            continue
        hist, calls = np.zeros((grid.n_steps + 1, 6)), {}
        if name in b.frictions:
            hist = solve.friction_history(b.frictions[name], grid, calls)
        for key, count in calls.items():
            stats[key] = stats.get(key, 0) + count
        forces[f"friction_{name}"], powers[f"friction_{name}"] = hist[:, 2], hist[:, 2] * hist[:, 1]
        j = joints[name]
        if not isinstance(j, Prismatic):
            continue
        force = hist[grid.output_indices, 2:3] * hist[grid.output_indices, 3:6]
        for body, point, sign in ((j.body_a, j.a, 2.0), (j.body_b, j.b, -2.0)):
            if body != GROUND:
                i = names.index(body)
                lever = np.array([eom.points[f"{body}.{point}"](x) for x in q]) - q[:, 7 * i:7 * i + 3]
                k = rows.index(f"{body}_norm")
                radial[k] = radial.get(k, 0.0) + sign * np.einsum("ni,ni->n", lever, force)
    return forces, powers, radial
