"""Coulomb friction in spatial joints (:class:`~study.spatial.elements.JointFriction`) as the planar pins' friction.

A joint with friction becomes one :class:`study.model.eom.FrictionalPin` of the spatial equations, so the one friction
machinery of both backends runs it with every treatment (exact stick/slip with its mode switch and event location,
regularized, sign; ``study.solver.friction``, ``study.laws.contact``, ``study.laws.friction``): the torque (force)
tau solves tau + (mu_k r |R(tau)|_delta + T0) s = 0, R the multipliers of the pin's two rows, its generalized force
P^T tau with P = d(rate)/d(qd), the relative rate P qd, its acceleration P qdd + Pdot qd.

* revolute (rows ``<J>_tx``, ``<J>_ty``: d in body b's joint frame, :mod:`study.spatial.joints`): R = R_t, the
  transverse reaction (the rows' gradients in r_a are the unit vectors A_b f_b, A_b g_b, so the multipliers are the
  force components across the axis; the axial reaction, row ``_tz``, carries no friction), the rate
  omega_rel = (A_b h_b)^T (omega_a - omega_b), omega_i = 2 E(p_i) p_dot_i the global angular velocity (ground: 0).
  P^T tau = (2 E_a^T h tau, -2 E_b^T h tau) on the p blocks: the torque tau h on body a, -tau h on body b (a
  torque's generalized force, :mod:`study.spatial.derive`); r = the pin radius, T0 = ``resistance`` [N m].
* prismatic (rows ``<J>_tx``, ``<J>_ty``, the same unit gradients): R = N, the normal reaction, a 2-vector; the rate
  v_rel = (A_b h_b)^T d_dot, d the gap between point a and point b. P^T f = (dd/dq)^T h f: the force f h at point a
  of body a and -f h at point b of body b. On the constraint manifold d is parallel to h, so v_rel is the velocity of
  point a relative to body b's material point under it along the axis (the omega_b x d term is across h) and the
  force's moment arm between b's two points vanishes; r = 1 (the friction force is mu_k |N|_delta + T0),
  T0 = ``resistance`` [N].

The friction's work (tau * rate, ``work_friction_<J>``) enters the energy balance as the planar pins' does. The
outputs name the joint: ``normal_<J>`` = |R| [N], ``friction_<J>`` = tau on body a ([N m] for a revolute, [N] for a
prismatic joint), ``v_t`` = the rate ([rad/s], [m/s]).
"""

from __future__ import annotations

import sympy as sp

from study.model.eom import FrictionalPin
from study.spatial.description import SpatialDescription
from study.spatial.elements import GROUND, Revolute
from study.spatial.joints import BodyFrames, frame_vectors, gap
from study.spatial.rotations import e_matrix

#: the two rows whose multipliers are the reaction R of a joint with friction (suffixes of its constraint names)
REACTION_ROWS = ("tx", "ty")


def _angular_velocity(d: SpatialDescription, q: sp.Matrix, qd: sp.Matrix, body: str) -> sp.Matrix:
    """omega = 2 E(p) p_dot of ``body`` in the global frame (ground: 0)."""
    if body == GROUND:
        return sp.zeros(3, 1)
    k = 7 * list(d.bodies).index(body)
    return 2 * e_matrix(list(q[k + 3:k + 7, 0])) * qd[k + 3:k + 7, 0]


def _rate(d: SpatialDescription, frames: BodyFrames, q: sp.Matrix, qd: sp.Matrix, j) -> sp.Expr:
    """The relative rate of joint ``j`` along its axis A_b h_b (module docstring)."""
    axis = frame_vectors(d, frames, j)[1][2]
    if isinstance(j, Revolute):
        relative = _angular_velocity(d, q, qd, j.body_a) - _angular_velocity(d, q, qd, j.body_b)
    else:
        relative = gap(frames, j).jacobian(q) * qd
    return (axis.T * relative)[0]


def friction_rates(d: SpatialDescription, frames: BodyFrames, q: sp.Matrix,
                   qd: sp.Matrix) -> dict[str, tuple[sp.Matrix, sp.Expr]]:
    """(P (1, m), Pdot qd) of every joint with friction, in the order of ``d.frictions``."""
    joints = {j.name: j for j in d.joints}
    rates = {}
    for name in d.frictions:
        jac = sp.Matrix([_rate(d, frames, q, qd, joints[name])]).jacobian(qd)
        rates[name] = (jac, ((jac * qd).jacobian(q) * qd)[0])
    return rates


def joint_pins(d: SpatialDescription, constraint_names: tuple[str, ...], f: dict) -> tuple[FrictionalPin, ...]:
    """The joints with friction as FrictionalPins, their rate Jacobians and biases the generated functions
    ``friction_jac__<J>``, ``friction_bias__<J>`` of ``f`` (:func:`study.spatial.derive.spatial_system`)."""
    pins = []
    for name, law in d.frictions.items():
        bias = f[f"friction_bias__{name}"]
        pins.append(FrictionalPin(
            name=name, rows=tuple(constraint_names.index(f"{name}_{row}") for row in REACTION_ROWS),
            rate_jacobian=f[f"friction_jac__{name}"],
            rate_bias=lambda q, qd, bias=bias: float(bias(q, qd)),
            mu_static=law.mu_static, mu_kinetic=law.mu_kinetic,
            radius=1.0 if law.radius is None else law.radius, torque=law.resistance))
    return tuple(pins)

