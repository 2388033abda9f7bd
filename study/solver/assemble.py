"""A run's samples -> SimulationResult: accelerations, multipliers, residuals, energies (both backends)."""

from __future__ import annotations

import numpy as np

from study.errors import SimulationError
from study.results import SimulationResult
from study.solver.checks import diagnose_dynamics
from study.solver.dynamics import Dynamics, output_error
from study.solver.friction import FrictionDynamics


def assemble_result(dyn: Dynamics, t: np.ndarray, y: np.ndarray, modes: list) -> SimulationResult:
    """Post-process samples: accelerations, multipliers, residuals and energies at every sample.

    With friction (a FrictionDynamics) also the contacts' normal and tangential forces, stick flags
    and the work of each contact's tangential force. A user's callable that raises here, or returns what
    cannot be stored (a wrong shape, complex values; potential_energy: a real scalar), fails the run with
    its name and the sample's time (``study.solver.checks.diagnose_equations``).
    """
    eom = dyn.eom
    m, r = eom.n_coordinates, eom.n_constraints
    n = len(t)
    qdd, lam = np.zeros((n, m)), np.zeros((n, r))
    phi, phidot = np.zeros((n, r)), np.zeros((n, r))
    kinetic, potential = np.zeros(n), np.zeros(n)
    with_friction = isinstance(dyn, FrictionDynamics)
    nc = dyn.n_contacts if with_friction else 0
    normal, tangential, stick = np.zeros((n, nc)), np.zeros((n, nc)), np.zeros((n, nc))
    for k in range(n):
        q, qd = y[k, :m], y[k, m:2 * m]
        try:
            if with_friction:
                sol = dyn.contact_solution(t[k], q, qd, modes[k])
                qdd[k], lam[k] = sol.qdd, sol.lam
                normal[k], tangential[k], stick[k] = sol.normal, sol.friction, dyn.stick_flags(sol)
            else:
                qdd[k], lam[k] = dyn.evaluate(t[k], q, qd, modes[k])
            phi[k] = eom.phi(q)
            phidot[k] = eom.phi_q(q) @ qd
            kinetic[k] = eom.kinetic_energy(q, qd)
            if eom.potential_energy:
                value = eom.potential_energy(q)
                if np.iscomplexobj(value):  # storing it would drop the imaginary part without a word
                    raise output_error(eom, "potential_energy(q)", value, (), float(t[k]), q)
                potential[k] = value
        except SimulationError:
            raise
        except Exception as exc:  # noqa: BLE001 - a user's callable raised, or returned what cannot be stored
            error = diagnose_dynamics(dyn, float(t[k]), q, qd, modes[k], potential=True)
            if error is None:
                raise
            raise error from exc
    energies = {"kinetic": kinetic, "potential": potential}
    for i, name in enumerate(dyn.work_names):
        energies[f"work_{name}"] = y[:, 2 * m + i]
    forces = {}
    for j, name in enumerate(dyn.contact_names if with_friction else ()):
        energies[f"work_friction_{name}"] = y[:, 2 * m + len(dyn.work_names) + j]
        forces[f"normal_{name}"] = normal[:, j]
        forces[f"friction_{name}"] = tangential[:, j]
        forces[f"stick_{name}"] = stick[:, j]
    meta = {"coordinate_names": list(eom.coordinate_names), "constraint_names": list(eom.constraint_names),
            "has_potential": eom.potential_energy is not None}
    result = SimulationResult(t, y[:, :m], y[:, m:2 * m], qdd, lam, phi, phidot, energies, forces, {}, meta)
    result.check_finite()  # every saved sample: a NaN is a failed run, never a result
    return result
