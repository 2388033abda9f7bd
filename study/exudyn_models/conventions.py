"""The texts a result's meta carries about its mapping: which Exudyn output each multiplier row is read from, what
each force series is, how the laws and the friction's reaction are evaluated."""

from __future__ import annotations

from study.exudyn_models.assembly import Built
from study.exudyn_models.friction import has_friction

REACTION_READING = ("hybrid guard: live Newton iterate of the guide's or pin's reaction, last accepted value while "
                    "the live one is the zero of the first Newton iteration; initial accelerations use the "
                    "fixed-point seeded reaction")
LOAD_EVALUATION = ("laws lambdified with the parameter values bound, evaluated in Exudyn user functions from marker "
                   "positions/velocities and node angles/rates; a mode is the sign of its switching function at the "
                   "current state (no event location); the recorded '<load>' series are the laws evaluated on the "
                   "converged states")
WORK_FRICTION = ("work_friction_<c>: Coulomb plus resistance (the whole tangential guide force); work_friction_<p>: "
                 "the pin's torque tau times omega_rel (Coulomb plus T0)")


def meta(built: Built, rows: list[str], sources: list[tuple[str, int | None]], forces: dict) -> dict:
    """The mechanism-specific meta entries of a result; ``sources``: the rows' (joint, component)
    (:func:`study.exudyn_models.mapping.row_sources`)."""
    out = {
        "description": built.d.name,
        "loads_jacobian": built.loads_jacobian,
        "law_evaluation": dict(built.evaluation),
        "lam_mapping": lam_mapping(built, rows, sources),
        "reaction_reading": REACTION_READING if built.frictions else "not used",
        "force_conventions": force_conventions(built, forces),
        "load_evaluation": LOAD_EVALUATION,
    }
    if has_friction(built.d):
        out["work_friction"] = WORK_FRICTION
    return out


def lam_mapping(built: Built, rows, sources: list[tuple[str, int | None]]) -> str:
    """Where each multiplier row is read from."""
    parts = []
    for row, (joint, k) in zip(rows, sources):
        if k is not None:
            parts.append(f"{row} = -Force_{'xy'[k]} of RevoluteJoint2D '{joint}' (force on its second body, "
                         f"global)")
        elif joint not in built.normals:
            parts.append(f"{row} = Force of DistanceConstraint '{joint}' (its multiplier: the rod's tension)")
        else:
            n = built.normals[joint]
            parts.append(f"{row} = ForceLocal . ({n[0]:g}, {n[1]:g}) of PrismaticJoint2D '{joint}' (force on "
                         f"the guide body in the guide's body frame, along the joint normal)")
    return "; ".join(parts)


def force_conventions(built: Built, forces) -> dict[str, str]:
    """What each force series of the result is."""
    out = {}
    pins = {j.name for j in built.d.pins()}
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
