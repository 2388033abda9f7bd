"""Symbolic derivation: mechanism description -> M(q), velocity terms, potential, Phi, Phi_q, gamma.

Pure functions of a :class:`~study.model.builder.MechanismBuilder` description. For body i with
centre of mass r_i(q) and angle theta_i(q):

    M = sum_i m_i J_i^T J_i + I_i j_i^T j_i              J_i = dr_i/dq,  j_i = dtheta_i/dq
    C(q, qd) qd = sum_i m_i J_i^T (Jdot_i qd) + I_i j_i^T (jdot_i qd)
    V = sum_i m_i g y_i + sum of spring potentials
    gamma = -(Phi_q qd)_q qd

so that M qdd + C qd + dV/dq + Phi_q^T lambda = Q_applied, with Q_applied the sum of the loads'
generalized forces J_p^T f (a force f at point p) and j_i^T tau (a torque on body i).

A sliding contact's tangential velocity is v_t = J_t qd, its rate J_t qdd + b_t with b_t = Jdot_t qd:
J_t = t . J_p on a guide fixed in ground; on a moving guide G, J_t = t(q) . (J_p - J_G*) with
J_G* qd = v_G + omega_G k x (r_p - r_G) the velocity of G's material point at the contact point.

A revolute joint with friction (a pin between bodies a and b, either may be ground) has the relative rate
omega = P qd, P = j_a - j_b (ground: 0), and its rate P qdd + Pdot qd.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from study.model.builder import MechanismBuilder


@dataclass(frozen=True)
class SymbolicEquations:
    """Sympy matrices of one mechanism (symbols: builder.q, builder.qd and builder.p)."""

    mass: sp.Matrix            # (m, m)
    velocity_terms: sp.Matrix  # (m, 1)  C(q, qd) qd
    potential: sp.Expr         # V(q)
    potential_gradient: sp.Matrix  # (m, 1)
    phi: sp.Matrix             # (r, 1)
    phi_q: sp.Matrix           # (r, m)
    gamma: sp.Matrix           # (r, 1)
    point_positions: dict[str, sp.Matrix]       # (2, 1)
    point_jacobians: dict[str, sp.Matrix]       # (2, m)
    point_bias: dict[str, sp.Matrix]            # (2, 1)  Jdot qd
    angle_jacobians: dict[str, sp.Matrix]       # (1, m)  per body
    angle_bias: dict[str, sp.Expr]              # jdot qd  per body
    loads: dict[str, sp.Matrix]                 # (m, 1)  generalized force of every applied load
    indicators: sp.Matrix                       # (k, 1)  switching functions of the loads
    contact_jacobians: dict[str, sp.Matrix] = None   # (1, m)  J_t of every sliding contact
    contact_bias: dict[str, sp.Expr] = None          # Jdot_t qd of every sliding contact
    pin_jacobians: dict[str, sp.Matrix] = None       # (1, m)  P of every revolute joint with friction
    pin_bias: dict[str, sp.Expr] = None              # Pdot qd of every revolute joint with friction


def _bias(jac: sp.Matrix, q: sp.Matrix, qd: sp.Matrix) -> sp.Matrix:
    """Jdot qd = d(J qd)/dq qd."""
    return (jac * qd).jacobian(q) * qd


def derive(b: MechanismBuilder) -> SymbolicEquations:
    q, qd = b.q, b.qd
    m = len(q)
    mass = sp.zeros(m, m)
    vel = sp.zeros(m, 1)
    potential = sp.Integer(0)
    angle_jacobians, angle_bias = {}, {}
    for body in b.bodies:
        r = sp.Matrix([body.x, body.y])
        jr = r.jacobian(q)
        ja = sp.Matrix([body.angle]).jacobian(q)
        jb = _bias(ja, q, qd)
        angle_jacobians[body.name], angle_bias[body.name] = ja, jb[0]
        mass += body.mass * jr.T * jr + body.inertia * ja.T * ja
        vel += body.mass * jr.T * _bias(jr, q, qd) + body.inertia * ja.T * jb
        if b.gravity_g is not None:
            potential += body.mass * b.gravity_g * body.y
    for _, expr in b.potentials:
        potential += expr
    phi = sp.Matrix([expr for _, expr in b.constraints]) if b.constraints else sp.zeros(0, 1)
    phi_q = phi.jacobian(q) if b.constraints else sp.zeros(0, m)
    gamma = -_bias(phi_q, q, qd) if b.constraints else sp.zeros(0, 1)
    positions, jacobians, bias = {}, {}, {}
    for pt in b.points:
        r = sp.Matrix([pt.x, pt.y])
        positions[pt.name] = r
        jacobians[pt.name] = r.jacobian(q)
        bias[pt.name] = _bias(jacobians[pt.name], q, qd)
    loads = {}
    for load in b.point_loads:
        loads[load.name] = jacobians[load.point.name].T * sp.Matrix(load.components)
    for load in b.torque_loads:
        loads[load.name] = angle_jacobians[load.body.name].T * load.torque
    indicators = sp.Matrix([e for _, e, _ in b.switches]) if b.switches else sp.zeros(0, 1)
    contact_jacobians, contact_bias = {}, {}
    for c in b.contacts:
        jac, pb = jacobians[c.point.name], bias[c.point.name]
        if c.guide is None:   # fixed guide: t . J_p and t . Jdot_p qd with the constant tangent
            contact_jacobians[c.name] = sp.Matrix([[c.tangent[0] * jac[0, j] + c.tangent[1] * jac[1, j]
                                                    for j in range(m)]])
            contact_bias[c.name] = c.tangent[0] * pb[0] + c.tangent[1] * pb[1]
            continue
        g = c.guide
        arm = sp.Matrix([c.point.x - g.x, c.point.y - g.y])          # guide's centre of mass -> contact point
        ja = angle_jacobians[g.name]
        coincident = sp.Matrix([g.x, g.y]).jacobian(q) + sp.Matrix([-arm[1], arm[0]]) * ja
        jt = (sp.Matrix([list(c.tangent)]) * (jac - coincident)).applyfunc(sp.expand)
        contact_jacobians[c.name] = jt
        contact_bias[c.name] = sp.expand(_bias(jt, q, qd)[0])
    pin_jacobians, pin_bias = {}, {}
    for pin in b.pin_frictions:
        jac = sp.zeros(1, m)
        for body, sign in ((pin.body_a, 1), (pin.body_b, -1)):
            if body is not None:
                jac += sign * angle_jacobians[body.name]
        pin_jacobians[pin.name] = jac
        pin_bias[pin.name] = _bias(jac, q, qd)[0]
    return SymbolicEquations(
        mass=mass,
        velocity_terms=vel,
        potential=potential,
        potential_gradient=sp.Matrix([potential]).jacobian(q).T,
        phi=phi,
        phi_q=phi_q,
        gamma=gamma,
        point_positions=positions,
        point_jacobians=jacobians,
        point_bias=bias,
        angle_jacobians=angle_jacobians,
        angle_bias=angle_bias,
        loads=loads,
        indicators=indicators,
        contact_jacobians=contact_jacobians,
        contact_bias=contact_bias,
        pin_jacobians=pin_jacobians,
        pin_bias=pin_bias,
    )
