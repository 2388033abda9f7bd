"""Joint reactions of every joint from a solution in the description's relative coordinates.

Relative coordinates eliminate the tree joints, so their reactions are not multipliers. The
absolute-coordinate equations of the same description have one constraint block per joint, and
their multipliers are the reactions: with the solution mapped to absolute coordinates (every body's
x, y, theta and their rates and accelerations, through the generated kinematics), the bodies'
Newton-Euler equations

    M_abs xdd + Phi_abs,x^T lambda = Q_abs(t, x, xd) + Jt^T F_t

(F_t: the contacts' tangential forces of the solution) are solved for lambda by least squares
(the minimum-norm reactions where the constraints are redundant).

Sign convention (one for every joint, both engines):

* revolute joint J between (A, a) and (B, b): ``joint_<J>_x``, ``joint_<J>_y`` = the global force of
  the joint on its second body B (= lambda of rows ``<J>_x``, ``<J>_y``); the force on A is the
  opposite;
* prismatic joint J: ``joint_<J>_n`` = the force on the slider along the joint's normal (= -lambda of
  the gap row ``<J>``); the guide body carries the opposite. ``joint_<J>_moment`` = the torque of the
  rotation lock on the slider (= -lambda of ``<J>_angle``), about the slider's centre of mass.
"""

from __future__ import annotations

import numpy as np

from study.mechanisms import as_mechanism
from study.model import Mechanism
from study.model.joints import Distance, Prismatic, Revolute
from study.params import ParameterSet
from study.results import SimulationResult

Array = np.ndarray


def _absolute(bodies, f, q: Array, qd: Array, qdd: Array) -> tuple[Array, Array, Array]:
    """(x, xd, xdd) of ``bodies`` from relative coordinates, with the generated kinematics ``f``."""
    x, xd, xdd = [], [], []
    for b in bodies:
        jac, ja = f[f"jac__{b}.com"](q), f[f"angle_jac__{b}"](q)
        x += list(f[f"pos__{b}.com"](q)) + [f[f"angle__{b}"](q)]
        xd += list(jac @ qd) + [ja @ qd]
        xdd += list(jac @ qdd + f[f"bias__{b}.com"](q, qd)) + [ja @ qdd + f[f"angle_bias__{b}"](q, qd)]
    return np.array(x, dtype=float), np.array(xd, dtype=float), np.array(xdd, dtype=float)


def absolute_state(mechanism: Mechanism | ParameterSet, q: Array, qd: Array, qdd: Array) -> tuple[Array, Array, Array]:
    """(x, xd, xdd) of every body (x, y, theta per body, description order) from relative coordinates."""
    mech = as_mechanism(mechanism)
    return _absolute(mech.description.bodies, mech.equations().kinematics, q, qd, qdd)


def joint_reactions(mechanism: Mechanism | ParameterSet, result: SimulationResult) -> dict[str, Array]:
    """Reactions of every joint at every sample of an in-house result (see the module docstring).

    Parameters
    ----------
    mechanism : the result's Mechanism (a description with its parameter set), or a study mechanism's
        parameter set
    result : SimulationResult in the description's relative coordinates (q, qd, qdd; the contacts'
        ``friction_<name>`` forces when friction was on)

    Returns
    -------
    dict name -> (N,) array
    """
    mech = as_mechanism(mechanism)
    d = mech.description
    eom = mech.equations("absolute")
    kinematics = mech.equations().kinematics
    rows = {name: i for i, name in enumerate(eom.constraint_names)}
    contacts = {c.name: c for c in eom.contacts}
    n = len(result.t)
    lam = np.zeros((n, eom.n_constraints))
    for k in range(n):
        x, xd, xdd = _absolute(d.bodies, kinematics, result.q[k], result.qd[k], result.qdd[k])
        rhs = eom.forces(result.t[k], x, xd) - eom.mass(x) @ xdd
        for name, c in contacts.items():
            tangential = result.forces.get(f"friction_{name}")
            if tangential is not None:
                rhs = rhs + c.tangent_jacobian(x) * tangential[k]
        lam[k] = np.linalg.lstsq(eom.phi_q(x).T, rhs, rcond=None)[0]
    out = {}
    for j in d.joints:
        if isinstance(j, Revolute):
            out[f"joint_{j.name}_x"], out[f"joint_{j.name}_y"] = lam[:, rows[f"{j.name}_x"]], lam[:, rows[f"{j.name}_y"]]
        elif isinstance(j, Distance):
            out[f"joint_{j.name}_tension"] = lam[:, rows[j.name]]
        elif isinstance(j, Prismatic):
            out[f"joint_{j.name}_n"] = -lam[:, rows[j.name]]
            if f"{j.name}_angle" in rows:
                out[f"joint_{j.name}_moment"] = -lam[:, rows[f"{j.name}_angle"]]
    return out

