"""Mechanism B in Exudyn: the quick-return (shaper) mechanism of paper 001 (Haug's shaper).

Bodies (NodeRigidBody2D at the centre of mass, global frame = the study's: rocker pivot P at the
origin, crank pivot O = (0, h1), gravity -y): crank (COM at O + a1 e(q1), angle q1), rocker (COM
a2 e(q2), angle q2), connecting rod (COM E + a3 e(q3), angle q3, E = l2 e(q2)), block (at A =
O + l1 e(q1), turning with the rocker), ram (at D = E + l3 e(q3), rotation locked).

Joints: revolute 'O' (ground-crank), 'P' (ground-rocker), 'A' (crank-block), 'E' (rocker-rod),
'D' (rod-ram); prismatic 'block_on_rocker' (marker 0 at the rocker's COM, axis along the rocker,
marker 1 = block: A stays on the rocker line, block angle = rocker angle) and prismatic
'ram_guide' (marker 0 on the ground at (0, h2), axis global x, marker 1 = ram: y_D = h2).

Loads: gravity on every body; constant drive torque M on the crank; the cutting force on the ram
along x as a user-function load evaluating ``study.mechanisms.quick_return.cutting_law(ps)`` with
``mode=None`` on the current ram state (x_D, v_D); for ``mu_guide > 0`` (variant 'guide_friction')
regularized Coulomb friction -mu_guide |N| tanh(v_D/eps) at the ram guide, N read from the
PrismaticJoint2D with the 'hybrid' guard (see common.ReactionGuard).

Mapping to the in-house result (``study.mechanisms.quick_return``), M qdd + Phi_q^T lam = Q:

* q = node angles of crank, rocker, rod (Exudyn's rotation coordinates, continuous); qd, qdd
  from the node velocity and acceleration coordinates (Exudyn's accelerations).
* lam1 (f1 = normal gap of A from the rocker line, gradient n = (-sin q2, cos q2)): the rocker
  pushes the block with -lam1 n. Exudyn's ForceLocal of 'block_on_rocker' is the force on the
  marker-0 body (rocker) in the rocker's body frame, whose y axis is n, so ``lam1 = ForceLocal_y``.
* lam2 (f2 = h2 - y_D, gradient (0, -1)): the guide pushes the ram with (0, lam2). ForceLocal of
  'ram_guide' is the force on the ground (global frame), so ``lam2 = -ForceLocal_y``.
* ``forces['normal_block_on_rocker'] = -lam1`` (force on the block along n),
  ``forces['normal_ram_guide'] = -lam2`` (force on the ram along the in-house contact normal
  (0, -1), i.e. positive when the guide pushes the ram down), ``forces['cutting']`` (x force on the
  ram), ``forces['friction_ram_guide']`` (only with guide friction), ``forces['joint_<J>_x/_y']``
  (J in O, P, A, E, D: global force of the revolute joint on its distal body: crank, rocker, block,
  rod, ram).
"""

from __future__ import annotations

import sys
import numpy as np

from study.exudyn_models import common
from study.exudyn_models.common import OVT, BodyState, GuideFriction, Model, ReactionGuard, unit, unit_normal
from study.mechanisms.quick_return import cutting_law
from study.params import ParameterSet
from study.results import SimulationResult

MECHANISM = "quick_return"
BODIES = ("crank", "rocker", "rod", "block", "ram")
REVOLUTE_JOINTS = {"O": "crank", "P": "rocker", "A": "block", "E": "rod", "D": "ram"}   # joint -> distal body


def body_states(ps: ParameterSet, q, qd) -> dict[str, BodyState]:
    """COM position, angle and velocities of every body from (q1, q2, q3) and their rates."""
    v = ps.values
    q1, q2, q3 = (float(x) for x in q)
    w1, w2, w3 = (float(x) for x in qd)
    o = np.array([0.0, v.h1])
    a, va = o + v.l1 * unit(q1), v.l1 * w1 * unit_normal(q1)
    e, ve = v.l2 * unit(q2), v.l2 * w2 * unit_normal(q2)
    d, vd = e + v.l3 * unit(q3), ve + v.l3 * w3 * unit_normal(q3)
    return {
        "crank": BodyState(tuple(o + v.a1 * unit(q1)), q1, tuple(v.a1 * w1 * unit_normal(q1)), w1),
        "rocker": BodyState(tuple(v.a2 * unit(q2)), q2, tuple(v.a2 * w2 * unit_normal(q2)), w2),
        "rod": BodyState(tuple(e + v.a3 * unit(q3)), q3, tuple(ve + v.a3 * w3 * unit_normal(q3)), w3),
        "block": BodyState(tuple(a), q2, tuple(va), w2),
        "ram": BodyState(tuple(d), 0.0, tuple(vd), 0.0),
    }


def has_guide_friction(ps: ParameterSet, friction: str) -> bool:
    return friction == "regularized" and ps.values.mu_guide > 0


def build(ps: ParameterSet, q0, qd0, friction: str = "regularized", eps: float = common.DEFAULT_EPS):
    """Assemble the Exudyn model for the consistent initial state (q0, qd0).

    Returns
    -------
    model : common.Model
    loads : dict with 'friction' (GuideFriction or None) and 'cutting' (the CuttingLaw)
    """
    if ps.mechanism != MECHANISM:
        raise ValueError(f"parameter set is for {ps.mechanism!r}, not {MECHANISM!r}")
    v = ps.values
    model = Model()
    states = body_states(ps, q0, qd0)
    for name, m, J in (("crank", v.m1, v.J1), ("rocker", v.m2, v.J2), ("rod", v.m3, v.J3),
                       ("block", v.m4, v.J4), ("ram", v.m5, v.J5)):
        model.body(name, m, J, states[name], v.g)

    crank_o = model.marker("crank", (-v.a1, 0.0))
    model.revolute("O", model.marker("ground", (0.0, v.h1)), crank_o)
    model.revolute("P", model.marker("ground", (0.0, 0.0)), model.marker("rocker", (-v.a2, 0.0)))
    block = model.marker("block", (0.0, 0.0))
    model.revolute("A", model.marker("crank", (v.l1 - v.a1, 0.0)), block)
    model.prismatic("block_on_rocker", model.marker("rocker", (0.0, 0.0)), block)
    model.revolute("E", model.marker("rocker", (v.l2 - v.a2, 0.0)), model.marker("rod", (-v.a3, 0.0)))
    ram = model.marker("ram", (0.0, 0.0))
    model.revolute("D", model.marker("rod", (v.l3 - v.a3, 0.0)), ram)
    model.prismatic("ram_guide", model.marker("ground", (0.0, v.h2)), ram)

    model.torque(crank_o, value=v.M)
    law = cutting_law(ps)
    ram_node = model.node("ram")

    def cutting(mbs, t, load_vector):
        r = mbs.GetNodeOutput(ram_node, OVT.Position)
        vel = mbs.GetNodeOutput(ram_node, OVT.Velocity)
        fx, fy = law(t, r, vel, None)
        return [fx, fy, 0.0]
    model.force(ram, cutting)

    fric = None
    if has_guide_friction(ps, friction):
        guide = model.joints["ram_guide"][0]
        # normal force on the ram along +y = -(force on the ground); sign irrelevant for |N|
        guard = ReactionGuard(lambda mbs: -mbs.GetObjectOutput(guide, OVT.ForceLocal)[1])
        fric = GuideFriction(model, "ram", guard, mu=v.mu_guide, resistance=0.0, eps=eps)
        model.force(ram, fric)
    model.assemble()
    return model, {"friction": fric, "cutting": law}


def loads_jacobian(ps: ParameterSet, friction: str) -> int:
    """2 (numerical load Jacobian incl. velocities) with ram-guide friction, else 0.

    The regularized friction tanh(v_D/eps) needs its derivative in the Newton matrix (without it
    Newton diverges, see common.simulation_settings). The cutting law does not: for the smooth law
    the Newton iteration counts with and without the load Jacobian agree within 0.5 % (20 s,
    h = 1e-3: 55 962 vs 55 735) while the 7 extra user-function calls per iteration double the CPU
    time; the on/off law is piecewise constant, its numerical derivative across a switch meaningless.
    """
    return 2 if has_guide_friction(ps, friction) else 0


def run(ps: ParameterSet, t_end: float, h: float, solver: str = "index3", output_step: float | None = None,
        friction: str = "regularized", eps: float = common.DEFAULT_EPS) -> SimulationResult:
    """Simulate the quick-return mechanism in Exudyn from the in-house consistent initial state.

    Parameters
    ----------
    ps : ParameterSet
        A quick-return parameter set (``study.params.load_parameters('quick_return', variant)``).
    t_end : float
        End time [s], a whole number of steps.
    h : float
        Fixed step [s].
    solver : {'index3', 'index2'} (or an explicit name, which Exudyn refuses; see common.SOLVERS)
    output_step : float, optional
        Sampling of the result, a whole multiple of h; default every step.
    friction : {'regularized', 'none'}
        Ram-guide friction (only present when ``mu_guide > 0``); 'none' leaves it out.
    eps : float
        Velocity scale of tanh(v_D/eps) in the friction law [m/s] (default 1e-3).

    Returns
    -------
    SimulationResult
        See the module docstring for the mapping of every quantity.
    """
    return common.run_model(sys.modules[__name__], ps, t_end, h, solver, output_step, friction, eps)


def initial_values(model) -> tuple[np.ndarray, np.ndarray]:
    qdd = np.array([model.node_output(b, OVT.Coordinates_tt)[2] for b in ("crank", "rocker", "rod")])
    return qdd, np.array([model.joint_output("block_on_rocker")[1], -model.joint_output("ram_guide")[1]])


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
    angles = ("crank", "rocker", "rod")
    q = np.column_stack([pos[b][:, 2] for b in angles])
    qd = np.column_stack([vel[b][:, 2] for b in angles])
    qdd = np.column_stack([acc[b][:, 2] for b in angles])
    block_local = model.series(("block_on_rocker", "force"), grid)
    guide_local = model.series(("ram_guide", "force"), grid)
    lam = np.column_stack([block_local[:, 1], -guide_local[:, 1]])

    law = loads["cutting"]
    cut = np.array([law(ti, r, w, None)[0] for ti, r, w in zip(t, pos["ram"][:, :2], vel["ram"][:, :2])])
    forces = {"normal_block_on_rocker": -lam[:, 0], "normal_ram_guide": -lam[:, 1], "cutting": cut}
    works = {"drive": v.M * vel["crank"][:, 2], "cutting": cut * vel["ram"][:, 0]}
    fric = loads["friction"]
    if fric is not None:
        hist = common.friction_history(fric, grid, stats)
        forces["friction_ram_guide"] = hist[:, 2]
        works["friction_ram_guide"] = hist[:, 2] * vel["ram"][:, 0]
    forces.update(common.joint_forces(model, grid, REVOLUTE_JOINTS))

    masses = {"crank": (v.m1, v.J1), "rocker": (v.m2, v.J2), "rod": (v.m3, v.J3), "block": (v.m4, v.J4),
              "ram": (v.m5, v.J5)}
    kinetic, potential = common.body_energies(masses, pos, vel, v.g)
    meta = {
        "loads_jacobian": loads_jacobian(ps, friction),
        "cutting_law": v.cutting_law,
        "lam_mapping": "lam1 = ForceLocal_y of PrismaticJoint2D 'block_on_rocker' (force on the rocker, rocker "
                       "frame, y = rocker normal); lam2 = -ForceLocal_y of 'ram_guide' (force on the ground, "
                       "global frame)",
        "reaction_reading": ("hybrid guard: live Newton iterate of the ram-guide reaction, last accepted value "
                             "while the live one is the zero of the first Newton iteration; initial accelerations "
                             "use the fixed-point seeded reaction") if fric is not None else "not used",
        "force_conventions": {
            "normal_block_on_rocker": "force on the block along n = (-sin q2, cos q2) = -lam1",
            "normal_ram_guide": "force on the ram along (0, -1) (in-house contact normal) = -lam2",
            "cutting": "cutting force on the ram along +x (law evaluated with mode=None on the converged state)",
            "friction_ram_guide": "Coulomb force on the ram along +x, -mu_guide |N| tanh(v_D/eps)",
            "joint_<J>_x/_y": "global force of revolute joint J on its distal body "
                              "(O: crank, P: rocker, A: block, E: rod, D: ram)",
        },
    }
    return common.assemble_result(eom, ps, grid, solver, eps,
                                  friction if v.mu_guide > 0 else "none (mu_guide = 0)", t=t, q=q, qd=qd,
                                  qdd=qdd, lam=lam, kinetic=kinetic, potential=potential, works=works,
                                  forces=forces, stats=stats, meta=meta)
