"""The result mapping: Exudyn's outputs of a built model read back into the study's SimulationResult (in-house
relative coordinates, ``M qdd + Phi_q^T lam = Q``).

* q: where the body angles are linear in q with full rank, theta = A q + c; q = q0 + A^+ (theta - theta0) with
  A^+ the exact pseudo-inverse and theta - theta0 Exudyn's angle displacement (so q(0) = q0 exactly);
  qd, qdd = A^+ times the node angular velocities / accelerations (Exudyn's, not finite differences).
  Otherwise (a translation coordinate) q solves pose(q) = Exudyn's body poses (x, y, theta of every body) by
  Gauss-Newton, and qd, qdd follow through the pose Jacobian (Kinematics.coordinates).
* lam, in ``eom.constraint_names`` order: a revolute row ``<J>_x/_y`` is the row r_a - r_b, so lam =
  the force of joint J on its second body b, global = -Exudyn 'Force' (the force on the marker-0
  body a). A prismatic gap row ``<J>`` = n . (r_s - r_g): the guide pushes the slider with -lam n, so
  lam = ForceLocal . n_local, ForceLocal = Exudyn's force on the marker-0 (guide) body in the
  guide's body frame and n_local the normal in that frame. A distance row: its 'Force' (the rod's tension).
* forces: ``normal_<c>`` = -lam of contact c's row; ``friction_<c>`` (Coulomb part) and
  ``resistance_<c>`` (if the description has a resistance) along the guide axis; after the contacts, every
  pin p: ``normal_<p>`` = |R| (the joint's reaction magnitude) and ``friction_<p>`` = tau, the whole friction
  torque on its body a (Coulomb and T0, as in the in-house result); ``<load>`` = the
  torque, or the force along the guide axis of the loaded body's prismatic joint (else along global
  x); ``joint_<J>_x/_y`` (every revolute joint) = force of J on its second body, global;
  ``joint_<J>_n`` (every prismatic joint) = force on the slider along the joint's normal = -lam.
* energies: kinetic, potential (gravity + springs), ``work_<load>``, ``work_friction_<c>`` and
  ``work_friction_<p>`` (the pair's power tau * omega_rel integrated).

The laws' values in the result are the laws evaluated on Exudyn's converged body series (:mod:`.series`); the
friction's are the friction user functions' own record of each step. The texts of these conventions that a result
carries in its meta are in :mod:`.conventions`.
"""

from __future__ import annotations

import numpy as np

import study.exudyn_models.conventions as conventions
import study.exudyn_models.settings as settings
import study.exudyn_models.solve as solve
from study.exudyn_models.assembly import Built
from study.exudyn_models.building import OVT
from study.exudyn_models.friction import active, has_friction
from study.exudyn_models.series import axis_series, law_series, point_series, series_inputs
from study.model.joints import Distance, Prismatic, Revolute
from study.results import SimulationResult

Array = np.ndarray


# --------------------------------------------------------------------------------------------
# the multipliers
# --------------------------------------------------------------------------------------------
def row_sources(built: Built, names) -> list[tuple[str, int | None]]:
    """(joint, component) of every constraint row: a revolute row's 0 (x) or 1 (y), None for a prismatic gap row
    or a distance row."""
    joints = {j.name: j for j in built.d.joints}
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


def multipliers(built: Built, outputs: dict[str, Array], names, lead: tuple = ()) -> Array:
    """lam (*lead, r) from joint outputs (revolute 'Force', prismatic 'ForceLocal'), in-house convention."""
    if not len(names):
        return np.zeros((*lead, 0))
    cols = []
    for joint, k in row_sources(built, names):
        f = outputs[joint]
        if k is not None:                # revolute: minus the force on the marker-0 body
            cols.append(-f[..., k])
        elif joint in built.normals:     # prismatic: the local force along the normal
            cols.append(f[..., 0] * built.normals[joint][0] + f[..., 1] * built.normals[joint][1])
        else:                            # distance: its force is the multiplier of its row
            cols.append(f[..., 0])
    return np.stack(cols, axis=-1)


def initial_values(built: Built) -> tuple[Array, Array]:
    """(qdd, lam) at the model's current state (after Exudyn's solver initialization)."""
    eom = built.mech.equations()
    acc = np.array([built.model.node_output(b, OVT.Coordinates_tt) for b in built.d.bodies], dtype=float)
    outputs = {j.name: built.model.joint_output(j.name) for j in built.d.joints}
    if built.kin.pinv is not None:
        qdd = built.kin.pinv @ acc[:, 2]
    else:
        vel = np.array([built.model.node_output(b, OVT.Coordinates_t) for b in built.d.bodies], dtype=float)
        qdd = built.kin.rates(built.q0, vel.ravel(), acc.ravel())[1]
    return qdd, multipliers(built, outputs, eom.constraint_names)


# --------------------------------------------------------------------------------------------
# the result
# --------------------------------------------------------------------------------------------
def result(built: Built, eom, grid: settings.RunGrid, solver: str, stats: dict) -> SimulationResult:
    """The SimulationResult of a solved model (see the module docstring for the mapping of every quantity)."""
    d = built.d
    t = grid.h * np.arange(grid.n_steps + 1)
    pos, vel, acc, disp = {}, {}, {}, {}
    for b in d.bodies:
        pos[b], vel[b], acc[b] = built.model.body_series(b, grid)
        disp[b] = built.model.series((b, "coordinates"), grid)   # displacement from the reference
    q, qd, qdd = coordinates(built, pos, vel, acc, disp)
    outputs = {j.name: built.model.series((j.name, "force"), grid) for j in d.joints}
    lam = multipliers(built, outputs, eom.constraint_names, (len(t),))
    rows = list(eom.constraint_names)

    forces, works = load_forces(built, t, pos, vel)
    contact_forces(built, grid, stats, lam, rows, forces, works)
    pin_forces(built, grid, stats, outputs, forces, works)
    forces.update(joint_forces(built, outputs))
    kinetic, potential = energies(built, t, pos, vel)
    meta = conventions.meta(built, rows, row_sources(built, rows), forces)
    friction = built.friction if has_friction(d) else \
        "none (no friction contact or pin with mu_k > 0 or resistance > 0)"
    return solve.assemble_result(eom, built.mech.parameters, grid, solver, built.eps, friction, t=t, q=q, qd=qd,
                                 qdd=qdd, lam=lam, kinetic=kinetic, potential=potential, works=works, forces=forces,
                                 stats=stats, meta=meta)


def coordinates(built: Built, pos: dict, vel: dict, acc: dict, disp: dict) -> tuple[Array, Array, Array]:
    """q, qd, qdd at every step from the bodies' series (angles through A^+, or poses through Gauss-Newton)."""
    bodies, kin = built.d.bodies, built.kin
    if kin.pinv is not None:
        angles = lambda series: np.column_stack([series[b][:, 2] for b in bodies])  # noqa: E731
        q = built.q0 + angles(disp) @ kin.pinv.T      # q(0) = q0 exactly (zero displacement)
        qd = angles(vel) @ kin.pinv.T
        qdd = angles(acc) @ kin.pinv.T
        return q, qd, qdd
    poses_of = lambda series: np.hstack([series[b] for b in bodies])  # noqa: E731
    return kin.coordinates(built.q0, poses_of(pos), poses_of(vel), poses_of(acc))


def load_forces(built: Built, t: Array, pos: dict, vel: dict) -> tuple[dict, dict]:
    """``<load>`` forces (the torque, or the force along the loaded slider's guide axis, else global x) and powers."""
    d, subs = built.d, built.kin.subs
    forces, works = {}, {}
    guides = {j.slider[0]: j for j in d.joints if isinstance(j, Prismatic)}
    for name, law in built.laws.items():
        load = next(ld for ld in d.loads if ld.name == name)
        values = law_series(law, t, series_inputs(law, d, subs, pos, vel))
        if load.point is None:
            forces[name] = values[:, 0]
            works[name] = values[:, 0] * vel[load.body][:, 2]
            continue
        pv = point_series(d, subs, pos, vel, load.body, load.point)
        works[name] = values[:, 0] * pv["vx"] + values[:, 1] * pv["vy"]
        direction = axis_series(guides[load.body], subs, pos) if load.body in guides else \
            np.tile([1.0, 0.0], (len(t), 1))
        forces[name] = values[:, 0] * direction[:, 0] + values[:, 1] * direction[:, 1]
    return forces, works


def contact_forces(built: Built, grid: settings.RunGrid, stats: dict, lam: Array, rows: list, forces: dict,
                   works: dict) -> None:
    """``normal_<c>``, ``friction_<c>``, ``resistance_<c>`` and the friction's power of every contact, into
    ``forces`` and ``works``."""
    d = built.d
    for j in d.contacts():
        if j.name in rows:
            forces[f"normal_{j.name}"] = -lam[:, rows.index(j.name)]
        if not active(d, j):
            continue
        fric = built.frictions_by_contact.get(j.name)
        if fric is not None:
            hist = solve.friction_history(fric, grid, stats)
            coulomb, resistance, v_t = hist[:, 2], hist[:, 3], hist[:, 1]
        else:
            coulomb = resistance = v_t = np.zeros(grid.n_steps + 1)
        forces[f"friction_{j.name}"] = coulomb
        if j.friction.resistance != 0:
            forces[f"resistance_{j.name}"] = resistance
        works[f"friction_{j.name}"] = (coulomb + resistance) * v_t


def pin_forces(built: Built, grid: settings.RunGrid, stats: dict, outputs: dict, forces: dict, works: dict) -> None:
    """``normal_<p>`` (|R|), ``friction_<p>`` (tau on body a) and the pair's power of every pin, into ``forces`` and
    ``works``."""
    d = built.d
    for j in d.pins():
        forces[f"normal_{j.name}"] = np.hypot(outputs[j.name][:, 0], outputs[j.name][:, 1])
        if not active(d, j):
            continue
        fric = built.frictions_by_pin.get(j.name)
        if fric is not None:
            hist = solve.friction_history(fric, grid, stats)
            omega, tau = hist[:, 1], hist[:, 2]
        else:
            omega = tau = np.zeros(grid.n_steps + 1)
        forces[f"friction_{j.name}"] = tau
        works[f"friction_{j.name}"] = tau * omega


def joint_forces(built: Built, outputs: dict) -> dict[str, Array]:
    """``joint_<J>_x/_y`` (revolute, global, on its second body), ``joint_<J>_tension`` (distance), ``joint_<J>_n``
    (prismatic, on the slider along the normal) of every joint."""
    forces = {}
    for j in built.d.joints:
        f = outputs[j.name]
        if isinstance(j, Revolute):
            forces[f"joint_{j.name}_x"], forces[f"joint_{j.name}_y"] = -f[:, 0], -f[:, 1]
        elif isinstance(j, Distance):
            forces[f"joint_{j.name}_tension"] = f[:, 0]
        else:
            n = built.normals[j.name]
            forces[f"joint_{j.name}_n"] = -(f[:, 0] * n[0] + f[:, 1] * n[1])
    return forces


def energies(built: Built, t: Array, pos: dict, vel: dict) -> tuple[Array, Array]:
    """Kinetic and potential energy (gravity and the description's potentials) at every step."""
    d, subs = built.d, built.kin.subs
    bodies = {b: (float(body.mass.xreplace(subs)), float(body.inertia.xreplace(subs)))
              for b, body in d.bodies.items()}
    g = float(d.gravity_g.xreplace(subs)) if d.gravity_g is not None else 0.0
    kinetic, potential = solve.body_energies(bodies, pos, vel, g)
    for law in built.potentials.values():
        potential = potential + law_series(law, t, series_inputs(law, d, subs, pos, vel))[:, 0]
    return kinetic, potential
