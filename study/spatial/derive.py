"""Symbolic equations of a spatial description in the redundant coordinates of Nikravesh and Haug.

Body i has q_i = (r_i, p_i): the centre of mass r (3) and the Euler parameters p (4). With G = G(p), G_dot =
G(p_dot) (:mod:`study.spatial.rotations`) and J' the inertia tensor at the centre of mass in the body frame, the
kinetic energy T = 1/2 m r_dot^2 + 2 p_dot^T G^T J' G p_dot gives, by Lagrange's equations (G p_dot = -G_dot p and
G_dot p_dot = 0, both exact for any p and p_dot):

    m r_ddot = f,     4 G^T J' G p_ddot = 8 G_dot^T J' G_dot p + Q_p

(Nikravesh 1988, eq. 11.35; Haug 1989, eq. 11.2.31). 4 G^T J' G is singular: G p = 0. The row p^T p - 1 = 0 of each
body has the Jacobian 2 p^T, so any multiple of p added to the p-equation is taken up by that row's multiplier and
leaves every acceleration unchanged. The mass matrix used is therefore

    M_p = 4 G^T J' G + c p p^T,   c = 4 trace(J') / 3,

positive definite (the solver needs that), with the same motion; only the norm row's multiplier (no physical
reaction) differs. c makes M_p = 4 c' I for a body with equal moments c' and unit p, so the scale is kept. The
velocity terms (moved to the left as in :mod:`study.model.derive`) are C qd = -8 G_dot^T J' G_dot p.

Loads: gravity g is the potential V = -sum m g . r; a force f at body point s' has the generalized force
(d(r + A s')/dq)^T f; a torque n in the global frame 2 E^T n, in the body frame 2 G^T n' (on the p block).
Constraints: the joints' rows (:mod:`study.spatial.joints`) and one norm row per body; gamma = -(Phi_q qd)_q qd.
A joint with friction has its relative rate P qd and Pdot qd (:mod:`study.spatial.friction`).
:func:`spatial_system` hands them to the code generator (:mod:`study.model.codegen`) of both backends.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from study.model.codegen import SymbolicSystem
from study.spatial.description import SpatialDescription, spatial_only
from study.spatial.elements import PointLoad, SpatialDescriptionError
from study.spatial.friction import friction_rates
from study.spatial.joints import BodyFrames, joint_rows
from study.spatial.rotations import e_matrix, g_matrix

COORDINATES = ("x", "y", "z", "e0", "e1", "e2", "e3")


@dataclass(frozen=True)
class SpatialSymbolic:
    """Sympy matrices of one spatial mechanism (symbols: q, qd and the time t)."""

    q: sp.Matrix
    qd: sp.Matrix
    t: sp.Symbol
    coordinate_names: tuple[str, ...]
    mass: sp.Matrix            # (m, m)
    velocity_terms: sp.Matrix  # (m, 1)  C(q, qd) qd
    potential: sp.Expr
    phi: sp.Matrix             # (r, 1)
    phi_q: sp.Matrix           # (r, m)
    gamma: sp.Matrix           # (r, 1)
    constraint_names: tuple[str, ...]
    loads: dict[str, sp.Matrix]   # (m, 1) generalized force of every applied load
    points: dict[str, sp.Matrix]  # (3, 1) global position of every named body point, '<body>.<point>'
    rates: dict[str, tuple[sp.Matrix, sp.Expr]]   # (1, m) P and Pdot qd of every joint with friction


def _coordinates(d: SpatialDescription) -> tuple[sp.Matrix, sp.Matrix, tuple[str, ...]]:
    names = tuple(f"{b}_{c}" for b in d.bodies for c in COORDINATES)
    return (sp.Matrix(sp.symbols([f"q_{n}" for n in names], real=True)),
            sp.Matrix(sp.symbols([f"qd_{n}" for n in names], real=True)), names)


def rotational_mass(inertia: sp.Matrix, p: sp.Matrix) -> sp.Matrix:
    """M_p = 4 G^T J' G + c p p^T, c = 4 trace(J') / 3 (the module docstring)."""
    g = g_matrix(p)
    return 4 * g.T * inertia * g + sp.Rational(4, 3) * inertia.trace() * p * p.T


def rotational_velocity_terms(inertia: sp.Matrix, p: sp.Matrix, pd: sp.Matrix) -> sp.Matrix:
    """C qd of the p block: -8 G_dot^T J' G_dot p."""
    gd = g_matrix(pd)
    return -8 * gd.T * inertia * gd * p


def derive_spatial(d: SpatialDescription) -> SpatialSymbolic:
    """The symbolic equations of a spatial description (a planar one is refused by name)."""
    d = spatial_only(d)
    if not d.bodies:
        raise SpatialDescriptionError(f"mechanism {d.name!r} has no bodies")
    q, qd, names = _coordinates(d)
    frames = BodyFrames(d, q)
    m = len(q)
    mass, vel, potential = sp.zeros(m, m), sp.zeros(m, 1), sp.Integer(0)
    for i, body in enumerate(d.bodies.values()):
        k = 7 * i
        inertia = sp.Matrix(body.inertia.tolist())
        p, pd = q[k + 3:k + 7, 0], qd[k + 3:k + 7, 0]
        mass[k:k + 3, k:k + 3] = body.mass * sp.eye(3)
        mass[k + 3:k + 7, k + 3:k + 7] = rotational_mass(inertia, p)
        vel[k + 3:k + 7, 0] = rotational_velocity_terms(inertia, p, pd)
        potential -= body.mass * sum(g * r for g, r in zip(d.gravity_vector.tolist(), q[k:k + 3]))
    rows, constraint_names = joint_rows(d, frames)
    for i, body in enumerate(d.bodies):
        p = q[7 * i + 3:7 * i + 7, 0]
        rows.append((p.T * p)[0] - 1)
        constraint_names.append(f"{body}_norm")
    phi = sp.Matrix(rows)
    phi_q = phi.jacobian(q)
    gamma = -(phi_q * qd).jacobian(q) * qd
    points = {f"{b}.{k}": frames.point(b, k) for b, body in d.bodies.items() for k in body.points}
    return SpatialSymbolic(q=q, qd=qd, t=d.t, coordinate_names=names, mass=mass, velocity_terms=vel,
                           potential=potential, phi=phi, phi_q=phi_q, gamma=gamma,
                           constraint_names=tuple(constraint_names), loads=_loads(d, q, frames), points=points,
                           rates=friction_rates(d, frames, q, qd))


def _loads(d: SpatialDescription, q: sp.Matrix, frames: BodyFrames) -> dict[str, sp.Matrix]:
    loads = {}
    for load in d.loads:
        f = sp.Matrix(load.components)
        if isinstance(load, PointLoad):
            loads[load.name] = frames.point(load.body, load.point).jacobian(q).T * f
            continue
        k = 7 * list(d.bodies).index(load.body)
        p = q[k + 3:k + 7, 0]
        generalized = sp.zeros(len(q), 1)
        generalized[k + 3:k + 7, 0] = 2 * (e_matrix(p) if load.frame == "global" else g_matrix(p)).T * f
        loads[load.name] = generalized
    return loads


def spatial_system(name: str, s: SpatialSymbolic) -> SymbolicSystem:
    """The code generator's view of the equations ``s`` of mechanism ``name``: no parameters (the description's
    numbers are in the expressions), switches or sliding contacts; the joints with friction are pins (their rates
    P, Pdot qd; :mod:`study.spatial.friction`). Its kinematic functions are the points' positions
    ``pos__<body>.<point>`` (q) -> (3,) and each joint with friction's ``friction_jac__<J>`` (q) -> (m,) and
    ``friction_bias__<J>`` (q, qd) -> ()."""
    m = len(s.q)
    kinematics = [(f"pos__{point}", "q", x, (3,)) for point, x in s.points.items()]
    for joint, (jac, bias) in s.rates.items():
        kinematics += [(f"friction_jac__{joint}", "q", jac, (m,)),
                       (f"friction_bias__{joint}", "q, qd", sp.Matrix([bias]), ())]
    return SymbolicSystem(
        name=name, q=tuple(s.q), qd=tuple(s.qd), parameters=(), modes=(), mass=s.mass,
        velocity_terms=s.velocity_terms, potential=s.potential,
        potential_gradient=sp.Matrix([s.potential]).jacobian(s.q).T, phi=s.phi, phi_q=s.phi_q, gamma=s.gamma,
        loads=s.loads, indicators=sp.zeros(0, 1), rates=tuple(s.rates.values()), kinematics=tuple(kinematics))
