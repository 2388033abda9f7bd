"""Mechanism A in Exudyn: slider-crank with regularized Coulomb friction in the slider guide.

Bodies (NodeRigidBody2D at the centre of mass, global frame = the study's: O at the origin,
gravity -y): crank (COM at O, angle q1), rod (COM C2, angle phi = q1 + q2, body x axis from B to A),
slider (at B, rotation locked). Joints: revolute 'O' (ground-crank), 'A' (crank-rod), 'B'
(rod-slider); prismatic 'guide' (ground marker at O, axis global x, marker 1 = slider), which
keeps y_B = 0.

Loads: gravity on every body; constant drive torque M on the crank; the alpha term (torsion spring
-alpha q1 or damper -alpha q1dot, per ``alpha_law``) as a user-function torque; on the slider one
user-function force along x,

    coulomb = -mu |N| tanh(v_B / eps),    resistance = -F tanh(v_B / eps),

with N the guide's normal reaction read from the PrismaticJoint2D inside the user function through
the 'hybrid' :class:`~study.exudyn_models.common.ReactionGuard` (live Newton iterate, last accepted
value while the live one is the zero of the first iteration).

Mapping to the in-house result (``study.mechanisms.slider_crank``):

* q1 = crank node angle, q2 = rod node angle - crank node angle (the node angles are Exudyn's
  rotation coordinates, continuous, never wrapped); qd, qdd likewise from the node velocity and
  acceleration coordinates (Exudyn's accelerations, not finite differences).
* The in-house constraint row is y_B (unit normal (0, 1)); with M qdd + Phi_q^T lam = Q the guide
  pushes the slider with -lam along +y. Exudyn's ForceLocal of the guide is the force on the
  marker-0 body (ground) in the ground frame, so the force on the slider is -ForceLocal and
  ``lam = ForceLocal_y``; ``forces['normal_guide'] = N = -lam`` (positive: guide pushes up).
* ``forces['friction_guide']`` (Coulomb part) and ``forces['resistance_guide']`` (the F part) are
  the values of the last user-function call of each step, i.e. the forces in the converged
  residual (the t = 0 sample: the initial-acceleration solve).
* ``forces['joint_<J>_x/_y']`` (J in O, A, B): global components of the force the revolute joint
  exerts on its distal body (crank at O, rod at A, slider at B) = -Exudyn 'Force' (which is the
  force on the marker-0 body).
"""

from __future__ import annotations

import sys
import numpy as np

from study.exudyn_models import common
from study.exudyn_models.common import OVT, BodyState, GuideFriction, Model, ReactionGuard, unit, unit_normal
from study.params import ParameterSet
from study.results import SimulationResult

MECHANISM = "slider_crank"
BODIES = ("crank", "rod", "slider")
REVOLUTE_JOINTS = {"O": "crank", "A": "rod", "B": "slider"}   # joint -> distal body


def body_states(ps: ParameterSet, q, qd) -> dict[str, BodyState]:
    """COM position, angle and velocities of every body from (q1, q2) and their rates."""
    v = ps.values
    q1, q2 = float(q[0]), float(q[1])
    w1, w2 = float(qd[0]), float(qd[1])
    phi, wphi = q1 + q2, w1 + w2
    a, va = v.l1 * unit(q1), v.l1 * w1 * unit_normal(q1)
    c2 = a - v.c2 * unit(phi)
    vc2 = va - v.c2 * wphi * unit_normal(phi)
    b = a - v.l2 * unit(phi)
    vb = va - v.l2 * wphi * unit_normal(phi)
    return {
        "crank": BodyState((0.0, 0.0), q1, (0.0, 0.0), w1),
        "rod": BodyState(tuple(c2), phi, tuple(vc2), wphi),
        "slider": BodyState(tuple(b), 0.0, tuple(vb), 0.0),
    }


def build(ps: ParameterSet, q0, qd0, friction: str = "regularized", eps: float = common.DEFAULT_EPS):
    """Assemble the Exudyn model for the consistent initial state (q0, qd0).

    Returns
    -------
    model : common.Model
    loads : dict with 'friction' (GuideFriction or None)
    """
    if ps.mechanism != MECHANISM:
        raise ValueError(f"parameter set is for {ps.mechanism!r}, not {MECHANISM!r}")
    v = ps.values
    model = Model()
    states = body_states(ps, q0, qd0)
    model.body("crank", v.m1, v.J1, states["crank"], v.g)     # J1 is about O = the COM
    model.body("rod", v.m2, v.J2, states["rod"], v.g)
    model.body("slider", v.m3, v.J3, states["slider"], v.g)

    ground_o = model.marker("ground", (0.0, 0.0))
    crank_o = model.marker("crank", (0.0, 0.0))
    model.revolute("O", ground_o, crank_o)
    model.revolute("A", model.marker("crank", (v.l1, 0.0)), model.marker("rod", (v.c2, 0.0)))
    slider = model.marker("slider", (0.0, 0.0))
    model.revolute("B", model.marker("rod", (v.c2 - v.l2, 0.0)), slider)
    model.prismatic("guide", ground_o, slider)

    model.torque(crank_o, value=v.M)
    crank_node = model.node("crank")
    alpha = v.alpha
    if v.alpha_law == "spring":
        def alpha_torque(mbs, t, load_vector):
            return [0.0, 0.0, -alpha * mbs.GetNodeOutput(crank_node, OVT.Rotation)[2]]
    else:
        def alpha_torque(mbs, t, load_vector):
            return [0.0, 0.0, -alpha * mbs.GetNodeOutput(crank_node, OVT.AngularVelocity)[2]]
    model.torque(crank_o, user=alpha_torque)

    fric = None
    if friction == "regularized":
        guide = model.joints["guide"][0]
        # N on the slider along +y = -(force on the ground), ForceLocal in the ground (= global) frame
        guard = ReactionGuard(lambda mbs: -mbs.GetObjectOutput(guide, OVT.ForceLocal)[1])
        fric = GuideFriction(model, "slider", guard, mu=v.mu, resistance=v.F, eps=eps)
        model.force(slider, fric)
    model.assemble()
    return model, {"friction": fric}


def loads_jacobian(ps: ParameterSet, friction: str) -> int:
    """2, always: the regularized friction and resistance tanh(v/eps) need their derivative in the Newton
    matrix (without it Newton diverges, see common.simulation_settings); the frictionless runs keep the
    same setting, so the two differ only by the friction itself."""
    return 2


def run(ps: ParameterSet, t_end: float, h: float, solver: str = "index3", output_step: float | None = None,
        friction: str = "regularized", eps: float = common.DEFAULT_EPS) -> SimulationResult:
    """Simulate the slider-crank in Exudyn from the in-house consistent initial state.

    Parameters
    ----------
    ps : ParameterSet
        A slider-crank parameter set (``study.params.load_parameters('slider_crank', variant)``).
    t_end : float
        End time [s], a whole number of steps.
    h : float
        Fixed step [s].
    solver : {'index3', 'index2'} (or an explicit name, which Exudyn refuses; see common.SOLVERS)
    output_step : float, optional
        Sampling of the result, a whole multiple of h; default every step.
    friction : {'regularized', 'none'}
        'none' leaves out Coulomb friction and the resistance F.
    eps : float
        Velocity scale of tanh(v/eps) in the friction and resistance laws [m/s] (default 1e-3,
        see common.DEFAULT_EPS).

    Returns
    -------
    SimulationResult
        See the module docstring for the mapping of every quantity.
    """
    return common.run_model(sys.modules[__name__], ps, t_end, h, solver, output_step, friction, eps)


def initial_values(model) -> tuple[np.ndarray, np.ndarray]:
    acc = {b: model.node_output(b, OVT.Coordinates_tt)[2] for b in ("crank", "rod")}
    qdd = np.array([acc["crank"], acc["rod"] - acc["crank"]])
    return qdd, np.array([model.joint_output("guide")[1]])


def initial_accelerations(ps: ParameterSet, q, qd, friction: str = "regularized",
                          eps: float = common.DEFAULT_EPS) -> tuple[np.ndarray, np.ndarray]:
    """Exudyn's accelerations and multipliers at a consistent state, from its solver initialization.

    No time step is taken: this is the initial-acceleration solve SolveDynamic performs at t = 0
    (with the seeded normal force if friction is on), mapped to the in-house coordinates and
    multiplier convention (see the module docstring).

    Returns
    -------
    qdd : (m,) array
    lam : (r,) array
    """
    return common.initial_accelerations(sys.modules[__name__], ps, q, qd, friction, eps)


def result(ps, eom, model, loads, grid, solver, friction, eps, stats) -> SimulationResult:
    v = ps.values
    t = grid.h * np.arange(grid.n_steps + 1)
    pos, vel, acc = {}, {}, {}
    for name in BODIES:
        pos[name], vel[name], acc[name] = model.body_series(name, grid)
    q = np.column_stack([pos["crank"][:, 2], pos["rod"][:, 2] - pos["crank"][:, 2]])
    qd = np.column_stack([vel["crank"][:, 2], vel["rod"][:, 2] - vel["crank"][:, 2]])
    qdd = np.column_stack([acc["crank"][:, 2], acc["rod"][:, 2] - acc["crank"][:, 2]])
    guide_local = model.series(("guide", "force"), grid)
    lam = guide_local[:, [1]]

    forces = {"normal_guide": -lam[:, 0]}
    fric = loads["friction"]
    if fric is not None:
        hist = common.friction_history(fric, grid, stats)
        coulomb, resistance = hist[:, 2], hist[:, 3]
    else:
        coulomb = resistance = np.zeros_like(t)
    forces["friction_guide"] = coulomb
    forces["resistance_guide"] = resistance
    forces.update(common.joint_forces(model, grid, REVOLUTE_JOINTS))

    bodies = {"crank": (v.m1, v.J1), "rod": (v.m2, v.J2), "slider": (v.m3, v.J3)}
    kinetic, potential = common.body_energies(bodies, pos, vel, v.g)
    w1 = vel["crank"][:, 2]
    works = {"drive": v.M * w1}
    if v.alpha_law == "spring":
        potential = potential + 0.5 * v.alpha * q[:, 0] ** 2
    else:
        works["alpha_damper"] = -v.alpha * w1 ** 2
    works["friction_guide"] = (coulomb + resistance) * vel["slider"][:, 0]
    meta = {
        "lam_mapping": "lam1 = ForceLocal_y of the PrismaticJoint2D 'guide' (force on the ground, global frame) "
                       "= -(normal force on the slider along +y)",
        "reaction_reading": "hybrid guard: live Newton iterate of the guide reaction, last accepted value "
                            "while the live one is the zero of the first Newton iteration; initial "
                            "accelerations use the fixed-point seeded reaction",
        "force_conventions": {
            "normal_guide": "N on the slider along +y (positive: guide pushes up) = -lam1",
            "friction_guide": "Coulomb force on the slider along +x, -mu |N| tanh(v_B/eps)",
            "resistance_guide": "resistance on the slider along +x, -F tanh(v_B/eps)",
            "joint_<J>_x/_y": "global force of revolute joint J on its distal body (O: crank, A: rod, B: slider)",
        },
        "work_friction_guide": "Coulomb plus resistance (the whole tangential guide force)",
    }
    return common.assemble_result(eom, ps, grid, solver, eps, friction, t=t, q=q, qd=qd, qdd=qdd, lam=lam,
                                  kinetic=kinetic, potential=potential, works=works, forces=forces,
                                  stats=stats, meta=meta)
