"""The setup of an in-house run, shared by both backends: its dynamics, output grid and recorded settings.

``study.simulate.simulate`` (the reference backend) and ``study.fast.frontend`` (the compiled one)
build a run's dynamics and initial state with :func:`build_dynamics`, sample it on
:func:`output_times` and record its settings with :func:`run_metadata`; the samples become a result
in ``study.solver.assemble``.
"""

from __future__ import annotations

import numpy as np

from study.model.eom import EquationsOfMotion
from study.reference_data import tolerance
from study.results import package_versions
from study.solver.accelerations import make_acceleration_solver
from study.solver.dynamics import Dynamics
from study.solver.friction import FrictionDynamics, StickSlipSwitching, make_friction
from study.solver.stabilization import Stabilization, make_stabilization


def build_dynamics(eom: EquationsOfMotion, q0: np.ndarray, qd0: np.ndarray, *, method: str | Stabilization,
                   acceleration_solver: str, friction: str | None, friction_eps: float, friction_sgn: str,
                   resistance_reading: str = "holds", **method_options) -> tuple[Dynamics, np.ndarray, StickSlipSwitching | None]:
    """A run's dynamics (with friction: a FrictionDynamics), its initial state y0 and its stick/slip rule.

    y0 = [q0, qd0, 0 for the work of every applied load (and of every contact's friction)].
    """
    stabilization = make_stabilization(method, **method_options)
    law = None if friction is None else make_friction(friction, eps=friction_eps, sgn=friction_sgn,
                                                      resistance_reading=resistance_reading)
    work_names = tuple(eom.applied_forces(0.0, q0, qd0))
    solver = make_acceleration_solver(acceleration_solver)
    if law is None:
        dyn = Dynamics(eom, solver, stabilization, work_names)
        return dyn, np.concatenate([q0, qd0, np.zeros(len(work_names))]), None
    n_load = len(np.atleast_1d(eom.indicators(0.0, q0, qd0))) if eom.indicators is not None else 0
    dyn = FrictionDynamics(eom, solver, stabilization, work_names, law=law, n_load_modes=n_load)
    y0 = np.concatenate([q0, qd0, np.zeros(len(work_names) + dyn.n_contacts)])
    return dyn, y0, StickSlipSwitching(dyn) if law.switched else None


def run_bounds(t_end: float, max_evaluations: float | None = None,
               min_step: float | None = None) -> tuple[float, float]:
    """A run's (max_evaluations, min_step), the defaults of reference/tolerances.toml where not given: the
    bounds both backends apply (evaluation limit; min_step_run steps in a row below min_step is a stall)."""
    max_evaluations = tolerance("max_evaluations") if max_evaluations is None else max_evaluations
    min_step = tolerance("min_step_fraction") * float(t_end) if min_step is None else min_step
    return max_evaluations, min_step


def output_times(t_end: float, output_step: float) -> np.ndarray:
    """The sampling grid of a run: k * output_step up to t_end, plus t_end itself."""
    n_out = int(np.floor(t_end / output_step + 1e-9))
    t_out = np.append(np.arange(n_out + 1) * output_step, [] if np.isclose(n_out * output_step, t_end) else [t_end])
    t_out[-1] = min(t_out[-1], t_end)
    return t_out


def run_metadata(eom: EquationsOfMotion, ps, *, integrator: str, rtol: float, atol: float, step: float | None,
                 acceleration_solver: str, output_step: float, t_end: float, stabilization, law,
                 backend: str = "reference") -> dict:
    """The settings of an in-house run, as stored in ``SimulationResult.meta`` (both backends)."""
    return {
        "engine": "in-house",
        "backend": backend,
        "mechanism": ps.mechanism if ps else eom.name,
        "variant": ps.variant if ps else None,
        "parameter_hash": ps.sha256 if ps else eom.parameter_hash,
        "integrator": integrator,
        "rtol": rtol if integrator != "RK4" else None,
        "atol": atol if integrator != "RK4" else None,
        "step": step,
        "acceleration_solver": acceleration_solver,
        "output_step": output_step,
        "t_end": float(t_end),
        **stabilization.settings(),
        **(law.settings() if law is not None else {"friction": None}),
        **eom.redundancy_note(),
        "versions": package_versions(),
    }
