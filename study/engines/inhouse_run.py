"""An in-house run of an :class:`~study.engines.inhouse.InHouse` specification: the checks that need the equations
(the friction the run takes, the initial state, the run's size, a singular start, the equations themselves), then
the compiled loop (``study.fast``), scipy's loop (on the reference or the compiled evaluations) or ALI3P."""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from study import arguments
from study.fast.support import SCIPY_STEPS_ONLY
from study.friction_default import friction_entries, treatment
from study.model.eom import EquationsOfMotion
from study.reference_data import tolerance
from study.results import SimulationResult
from study.run_arguments import DEFAULT_ATOL, DEFAULT_FRICTION, DEFAULT_RTOL, FIXED_STEP, check_run_size
from study.solver.accelerations import make_acceleration_solver
from study.solver.assemble import assemble_result
from study.solver.checks import RunGuard, SingularityMonitor, validate_equations
from study.solver.friction import DEFAULT_EPS
from study.solver.index3 import ALI3P, NAME as INDEX3, integrate_index3
from study.solver.integrate import integrate
from study.solver.run import build_dynamics, output_times, run_bounds, run_metadata


def run_inhouse(eom: EquationsOfMotion, mech, spec, t_end, q0, qd0, progress) -> SimulationResult:
    """Run ``spec`` (an InHouse) on ``eom`` (of ``mech``, or None for a user's equations) over [0, t_end]."""
    given = spec.checked(t_end, progress)
    s = {**spec.arguments(), "acceleration_solver": spec.solver(), "progress": progress}
    s.update({k: given[k] for k in ("t_end", "step", "rtol", "atol") if given[k] is not None})
    for key, default in (("rtol", DEFAULT_RTOL), ("atol", DEFAULT_ATOL)):   # as every run had them (fixed-step: unused)
        s[key] = default if s[key] is None else s[key]
    ps = None if mech is None else mech.parameters
    arguments.per_constraint(spec.method.name, _options_of(spec.method), eom)
    s["friction"], s["friction_eps"], s["friction_sgn"], stated = _friction(eom, ps, given, s)
    integrator, index3 = s["integrator"], s["integrator"] == INDEX3
    if index3 and eom.indicators is not None:
        raise ValueError(f"integrator 'ALI3P' does not locate the switches of {eom.name}'s discontinuous loads "
                         f"({', '.join(eom.indicator_names) or 'its indicators'}): use an ODE integrator (e.g. 'RK45')")
    min_rtol = tolerance("integrator_min_rtol")
    scipy_steps = spec.backend == "reference" or integrator in SCIPY_STEPS_ONLY
    if scipy_steps and integrator not in FIXED_STEP and s["rtol"] < min_rtol:
        loop = "" if integrator in SCIPY_STEPS_ONLY else " (or backend='compiled', whose loop takes its own steps)"
        raise ValueError(f"rtol = {s['rtol']!r} is below what scipy's {integrator} honours ({min_rtol:.3g} = 100 "
                         f"machine epsilons; it would silently raise it): use rtol >= {min_rtol:.3g}{loop}")
    s["max_evaluations"], s["min_step"] = run_bounds(s["t_end"], given["max_evaluations"], given["min_step"])
    max_output_bytes = tolerance("max_output_bytes") if spec.max_output_bytes is None else given["max_output_bytes"]
    q0, qd0 = _initial_state(eom, mech, q0, qd0)
    check_run_size(eom, q0, qd0, float(s["t_end"]), integrator, s["step"], s["output_step"], s["friction"],
                   s["max_evaluations"], max_output_bytes)
    monitor = None if make_acceleration_solver(s["acceleration_solver"]).passes_singular else SingularityMonitor(eom, q0)
    if monitor is not None:  # a singular start is refused even with check=False: nothing is determined there
        monitor.check(0.0, q0)
    if spec.check:
        validate_equations(eom, q0, qd0)
    reading = spec.resistance_reading
    if reading is None:
        reading = getattr(ps.values, "resistance_reading", "holds") if ps is not None else "holds"
    if spec.backend == "compiled" and s["friction"] == "exact" and reading != "holds":
        raise ValueError(f"backend 'compiled' implements resistance_reading 'holds' only, got {reading!r}: use "
                         f"backend='reference'")
    if not scipy_steps:
        from study.fast import simulate_compiled

        result = simulate_compiled(eom, mech, q0, qd0, **{k: s[k] for k in _COMPILED})
        result.meta.update(stated)
        return result
    return _scipy_loop(eom, mech, spec, s, q0, qd0, reading, monitor, stated)


_COMPILED = ("t_end", "method", "integrator", "rtol", "atol", "step", "output_step", "acceleration_solver", "progress",
             "friction", "friction_eps", "friction_sgn", "max_evaluations", "min_step")


def _scipy_loop(eom, mech, spec, s: dict, q0, qd0, reading: str, monitor, stated: dict) -> SimulationResult:
    """scipy's integrators (on the reference or the compiled evaluations) or ALI3P: the run of ``s`` (checked)."""
    dyn, y0, switching = build_dynamics(eom, q0, qd0, method=s["method"], acceleration_solver=s["acceleration_solver"],
                                        friction=s["friction"], friction_eps=s["friction_eps"],
                                        friction_sgn=s["friction_sgn"], resistance_reading=reading)
    ps = None if mech is None else mech.parameters
    t_end, integrator, step, m = float(s["t_end"]), s["integrator"], s["step"], eom.n_coordinates
    settings = {"integrator": integrator, "rtol": s["rtol"], "atol": s["atol"], "step": step,
                "acceleration_solver": s["acceleration_solver"], "output_step": s["output_step"], "t_end": s["t_end"],
                "stabilization": dyn.stabilization, "law": getattr(dyn, "law", None)}
    indicators = None
    if eom.indicators is not None and switching is None:
        def indicators(t, y):
            return eom.indicators(t, y[:m], y[m:2 * m])

    t_out = output_times(t_end, s["output_step"])
    if integrator == INDEX3:
        cpu0 = time.process_time()
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # non-finite states are diagnosed
            traj, stats = integrate_index3(dyn, y0, t_end, t_out, step, ALI3P(), s["progress"])
        return _result(dyn, traj, stats, time.process_time() - cpu0, eom, ps, stated, **settings | {"rtol": None,
                                                                                                      "atol": None})

    post_step = None
    if dyn.stabilization.projects:
        def post_step(y):
            q, qd, changed = dyn.stabilization.project(eom, y[:m], y[m:2 * m])
            return (np.concatenate([q, qd, y[2 * m:]]) if changed else y), changed

    rhs = None
    if spec.backend == "compiled":
        from study.fast import compiled_rhs

        rhs = compiled_rhs(eom, mech, dyn)
    guard = RunGuard(dyn, monitor, s["max_evaluations"], step if integrator in FIXED_STEP else None, t_end, rhs)
    cpu0 = time.process_time()
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # the guard reports non-finite values
        traj = integrate(guard, 0.0, y0, t_end, t_out, method=integrator, rtol=s["rtol"], atol=s["atol"],
                         step=step, indicators=indicators, post_step=post_step, progress=s["progress"],
                         switching=switching, min_step=s["min_step"],
                         monitor=None if monitor is None else (lambda t, y: monitor.check(t, y[:m])),
                         describe=guard.describe)
    stats = {"steps": traj.steps, "projections": traj.projections, "restarts": traj.restarts,
             "events": len(traj.events), "event_times": [e["t"] for e in traj.events],
             **dyn.accelerations.statistics()}
    if switching is not None:
        stats["friction_transitions"] = switching.transitions
    return _result(dyn, traj, stats, time.process_time() - cpu0, eom, ps, stated, **settings, backend=spec.backend)


def _friction(eom: EquationsOfMotion, ps, given: dict, s: dict):
    """The friction a run takes (:func:`study.friction_default.treatment`), its width and sgn form with their
    defaults, and what the result states about it (whether it was the default, the entries left out)."""
    by_default = s["friction"] == DEFAULT_FRICTION
    friction = treatment(eom, ps, s["friction"], given, integrator=s["integrator"], friction_eps=s["friction_eps"],
                         friction_sgn=s["friction_sgn"], backend=s["backend"])
    eps = DEFAULT_EPS if s["friction_eps"] is None else given["friction_eps"]
    sgn = "tanh" if s["friction_sgn"] is None else s["friction_sgn"]
    return friction, eps, sgn, {"friction_default": by_default,
                                "friction_left_out": [] if friction else friction_entries(eom)}


def _initial_state(eom: EquationsOfMotion, mech, q0, qd0) -> tuple[np.ndarray, np.ndarray]:
    """q0, qd0 as given, or the mechanism's consistent initial state where not given; checked against eom."""
    if q0 is None or qd0 is None:
        if mech is None:
            raise ValueError("q0 and qd0 are required for a user's EquationsOfMotion")
        state = mech.initial_state()
        q0 = state.q if q0 is None else q0
        qd0 = state.qd if qd0 is None else qd0
    names = eom.coordinate_names
    q0, qd0 = (arguments.state(k, v, eom.n_coordinates, names) for k, v in (("q0", q0), ("qd0", qd0)))
    eom.check_shapes(q0, qd0)
    return q0, qd0


def _options_of(method) -> dict:
    """A method's options: the fields of its object (none for a user's Stabilization that is not a dataclass)."""
    if dataclasses.is_dataclass(method):
        return {f.name: getattr(method, f.name) for f in dataclasses.fields(method)}
    return {}


def _result(dyn, traj, stats: dict, cpu: float, eom: EquationsOfMotion, ps, stated: dict, **settings):
    """The samples of a run as a SimulationResult, with its statistics, settings and what ``stated`` adds."""
    nfev = dyn.nfev  # the evaluations of the run, before the samples' post-processing adds its own
    result = assemble_result(dyn, traj.t, traj.y, traj.modes)
    result.stats.update({"nfev": nfev, **stats, "cpu_seconds": cpu})
    result.meta.update(run_metadata(eom, ps, **settings), **stated)
    return result
