"""The handlers of the description's friction: sliding contacts (a prismatic joint with friction) and pins (a
revolute joint with friction), one function each, and whether a model needs its loads' Jacobian.

* A prismatic joint with :class:`~study.model.joints.Friction` data whose kinetic coefficient or resistance is > 0
  gets the regularized Coulomb law of :class:`~study.exudyn_models.guards.GuideFriction` along the guide's axis,
  with N read from the joint through a :class:`~study.exudyn_models.guards.ReactionGuard`; ``friction='none'``
  leaves it out. On a moving guide the axis turns with the guide, the sliding velocity is relative to the guide's
  point under the slider, and the guide carries the opposite force (a force at its centre of mass and the torque of
  its lever: the same load as the force at the slider point).
* A revolute joint with friction data (a pin, ``friction=Friction(mu_s, mu_k, T0), radius=r``) whose mu_k or T0 is
  > 0 gets the regularized law of :class:`~study.exudyn_models.guards.PinFrictionTorque`: the torque
  tau = -(mu_k r sqrt(|R|^2 + delta^2) + T0) tanh(omega_rel/eps) on its body a and -tau on its body b
  (LoadTorqueVector user functions; nothing on ground), omega_rel = theta_a' - theta_b' from the nodes, |R| the
  magnitude of the RevoluteJoint2D's 'Force' (its multipliers, a global vector; only the magnitude enters) through
  a ReactionGuard, delta = ``pin_friction_norm_width`` (reference/tolerances.toml, the in-house value), eps read in
  rad/s. Exudyn has only this regularized law: friction='exact' and 'sign' are not run modes
  (settings.FRICTION_MODES), for pins as for guides.
"""

from __future__ import annotations

import sympy as sp

from study.exudyn_models.assembly import Assembly
from study.exudyn_models.building import OVT
from study.exudyn_models.guards import GuideFriction, PinFrictionTorque, ReactionGuard, reaction_norm
from study.model.joints import GROUND, Description, Prismatic, Revolute

_FORCE_LOCAL = OVT.ForceLocal   # the reaction the guide's friction reads, looked up once

#: How a friction law that reads a joint reaction (a guide's normal force, a pin's |R|) is evaluated.
REACTION_LAW_EVALUATION = ("Python user function (reads the joint reaction through mbs.GetObjectOutput; no Exudyn "
                           "element or symbolic user function has access to it)")


def active(d: Description, j: Prismatic | Revolute) -> bool:
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
    return 2 if has_friction(d) else 0


def has_friction(d: Description) -> bool:
    """Whether the description has an active friction contact or pin (:func:`active`)."""
    return any(active(d, j) for j in [*d.contacts(), *d.pins()])


def add_contact_friction(a: Assembly, j: Prismatic) -> None:
    """The regularized friction of a sliding contact: on the slider at its point and, on a moving guide, the
    opposite load on the guide."""
    model, built, eps = a.model, a.built, a.built.eps
    obj = model.joints[j.name][0]
    n = built.normals[j.name]
    guard = ReactionGuard(_normal_force(obj, n))
    axis = (a.val(j.axis[0]), a.val(j.axis[1]))       # guide frame (= global on a guide fixed in ground)
    moving = j.guide[0] != GROUND
    fric = GuideFriction(model, a.marker(*j.slider), axis, guard, mu=a.val(j.friction.mu_kinetic),
                         resistance=a.val(j.friction.resistance), eps=eps,
                         guide=(model.node(j.guide[0]), a.refs[j.guide[0]], a.com(j.guide[0])) if moving else None)
    model.force(a.marker(*j.slider), user=fric)
    if moving:   # the opposite force on the guide at the slider point: at its centre of mass, plus its moment
        model.force(a.com(j.guide[0]), user=fric.guide_force)
        model.torque(a.com(j.guide[0]), user=fric.guide_torque)
    built.frictions_by_contact[j.name] = fric
    built.evaluation[f"friction_{j.name}"] = REACTION_LAW_EVALUATION


def _normal_force(obj: int, normal: tuple[float, float]):
    """The reader of a contact's normal force N = force on the slider along the normal = -(ForceLocal . n) (= -lam)
    of the joint ``obj``; only |N| enters. Called at every friction evaluation: Python floats, no allocation
    beyond Exudyn's output."""
    n0, n1 = normal

    def read(mbs) -> float:
        f = mbs.GetObjectOutput(obj, _FORCE_LOCAL).tolist()
        return -(f[0] * n0 + f[1] * n1)
    return read


def add_pin_friction(a: Assembly, j: Revolute, delta: float) -> None:
    """The regularized friction torque of a pin on its bodies (its opposite on the second; nothing on ground)."""
    model, built = a.model, a.built
    obj = model.joints[j.name][0]
    guard = ReactionGuard(reaction_norm(obj))
    sides = (j.a[0], j.b[0])
    fric = PinFrictionTorque(model, tuple(None if b == GROUND else model.node(b) for b in sides), guard,
                       coefficient=a.val(j.friction.mu_kinetic) * a.val(j.radius),
                       resistance=a.val(j.friction.resistance), eps=built.eps, delta=delta)
    loaded = [(side, body) for side, body in enumerate(sides) if body != GROUND]
    for k, (side, body) in enumerate(loaded):   # the first load records, the other reads the same state
        model.torque(a.com(body), user=fric.load(side, record=k == 0))
    built.frictions_by_pin[j.name] = fric
    built.evaluation[f"friction_{j.name}"] = REACTION_LAW_EVALUATION
