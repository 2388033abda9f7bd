"""Running a built Exudyn model (SolveDynamic with its timing and statistics), and the SimulationResult assembled
from its per-step series."""

from __future__ import annotations

import time

import exudyn as exu
import numpy as np

from study.results import SimulationResult, package_versions
from study.exudyn_models.building import Model
from study.exudyn_models.guards import RecordedFriction
from study.exudyn_models.settings import (CONFIGURATION_DESCRIPTIONS, LINEAR_SOLVER_DESCRIPTIONS, NEWTON_TOLERANCE,
                                          SOLVER_DESCRIPTIONS, SOLVER_TYPES, SPECTRAL_RADIUS, RunGrid, exudyn_version)

Array = np.ndarray


# --------------------------------------------------------------------------------------------
# solving and post-processing
# --------------------------------------------------------------------------------------------
def solve(model: Model, settings: exu.SimulationSettings, solver: str) -> dict:
    """Run SolveDynamic; return timing and iteration statistics.

    ``cpu_seconds`` is Exudyn's own solver timer (``timer.total``, the time spent in the solver
    including the Python user functions); ``process_cpu_seconds`` and ``wall_seconds`` are measured
    around the call. Exudyn's exceptions propagate unchanged (explicit solvers raise
    ``exudyn.ModelError``); a failed implicit run (``exudyn.SolverError``) gets a note with the
    solver's error string and the time reached.
    """
    wall0, cpu0 = time.perf_counter(), time.process_time()
    try:
        model.mbs.SolveDynamic(settings, solverType=SOLVER_TYPES[solver], storeSolver=True)
    except exu.SolverError as exc:
        slv = model.mbs.sys.get("dynamicSolver")
        if slv is not None:
            exc.add_note(f"Exudyn: {slv.GetErrorString()!r} at t = {slv.it.currentTime}")
        raise
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    slv = model.mbs.sys["dynamicSolver"]
    return {
        "cpu_seconds": float(slv.timer.total),
        "process_cpu_seconds": cpu,
        "wall_seconds": wall,
        "steps": int(settings.timeIntegration.numberOfSteps),
        "newton_iterations": int(slv.it.newtonStepsCount),
        "jacobian_evaluations": int(slv.it.newtonJacobiCount),
    }


def friction_history(fric: RecordedFriction, grid: RunGrid, stats: dict) -> Array:
    """The friction user function's record at every step (checked), its call counts added to ``stats``."""
    hist = np.asarray(fric.history, dtype=float)
    if hist.shape != (grid.n_steps + 1, fric.width):
        raise RuntimeError(f"friction history has shape {hist.shape}, expected ({grid.n_steps + 1}, {fric.width}): one "
                           f"row per step plus t = 0")
    stats.update(friction_user_function_calls=fric.guard.calls, friction_guard_substitutions=fric.guard.substitutions)
    return hist


def cumulative_trapezoid(y: Array, t: Array) -> Array:
    """Integral of y from t[0] to every t[k] by the trapezoidal rule (same length as t)."""
    out = np.zeros_like(np.asarray(y, dtype=float))
    if len(t) > 1:
        out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))
    return out


WORK_NOTE = ("work_<load> = trapezoidal integral of the load's power sampled at every solver step (then "
             "sampled at the output times): error <= t_end h^2 max|P''| / 12 for smooth power, O(h) "
             "locally at a jump of a discontinuous (on/off) load")


def body_energies(bodies: dict[str, tuple[float, float]], pos: dict[str, Array], vel: dict[str, Array],
                  g: float) -> tuple[Array, Array]:
    """Kinetic and gravity potential energy from body states; ``bodies`` maps name -> (mass, inertia)."""
    kinetic = sum(0.5 * m * (vel[b][:, 0] ** 2 + vel[b][:, 1] ** 2) + 0.5 * J * vel[b][:, 2] ** 2
                  for b, (m, J) in bodies.items())
    potential = g * sum(m * pos[b][:, 1] for b, (m, _) in bodies.items())
    return kinetic, potential


def assemble_result(eom, ps, grid: RunGrid, solver: str, eps: float, friction: str, *, t: Array, q: Array,
                    qd: Array, qdd: Array, lam: Array, kinetic: Array, potential: Array,
                    works: dict[str, Array], forces: dict[str, Array], stats: dict, meta: dict):
    """The study's SimulationResult from per-step Exudyn series, sampled at the output times.

    Phi and Phidot are the in-house ones evaluated on Exudyn's q; work is integrated from the
    loads' power (see ``WORK_NOTE``). ``meta`` adds the mechanism-specific entries.
    """
    energies = {"kinetic": kinetic, "potential": potential}
    for name, power in works.items():
        energies[f"work_{name}"] = cumulative_trapezoid(power, t)
    idx = grid.output_indices
    phi = np.array([eom.phi(qi) for qi in q[idx]])
    phidot = np.array([eom.phi_q(qi) @ qdi for qi, qdi in zip(q[idx], qd[idx])])
    common_meta = {
        "engine": "exudyn",
        "exudyn_version": exudyn_version(),
        "method": f"exudyn_{solver}",
        "solver": solver,
        "solver_description": SOLVER_DESCRIPTIONS[solver],
        "configuration": stats.get("configuration", "python"),
        "configuration_description": CONFIGURATION_DESCRIPTIONS[stats.get("configuration", "python")],
        "linear_solver": stats.get("linear_solver", "dense"),
        "linear_solver_description": LINEAR_SOLVER_DESCRIPTIONS[stats.get("linear_solver", "dense")],
        "h": grid.h,
        "t_end": grid.t_end,
        "output_step": grid.h * grid.stride,
        "eps": eps,
        "friction": friction,
        "mechanism": ps.mechanism,
        "variant": ps.variant,
        "parameter_hash": ps.sha256,
        "coordinate_names": list(eom.coordinate_names),
        "constraint_names": list(eom.constraint_names),
        "newton_tolerance": stats.get("newton_tolerance", NEWTON_TOLERANCE),
        "spectral_radius": SPECTRAL_RADIUS if solver == "index3" else None,
        "qdd_source": "Exudyn node accelerations (Coordinates_tt sensors), not finite differences",
        "work_integration": WORK_NOTE,
        "versions": package_versions(),
    }
    return SimulationResult(
        t=t[idx], q=q[idx], qd=qd[idx], qdd=qdd[idx], lam=lam[idx], phi=phi, phidot=phidot,
        energies={k: val[idx] for k, val in energies.items()},
        forces={k: np.asarray(val, dtype=float)[idx] for k, val in forces.items()},
        stats=stats, meta={**common_meta, **meta},
    )
