"""``simulate``: one call from equations (or a built-in mechanism) to a SimulationResult."""

from __future__ import annotations

import dataclasses
import functools
import time
from typing import Callable

import numpy as np
from threadpoolctl import threadpool_limits

from study import arguments
from study.model.eom import EquationsOfMotion
from study.fast.support import SCIPY_STEPS_ONLY, check_supported
from study.friction_default import default_friction, friction_entries, treatment
from study.reference_data import tolerance
from study.results import SimulationResult
from study.solver.accelerations import make_acceleration_solver
from study.solver.assemble import assemble_result
from study.solver.checks import RunGuard, SingularityMonitor, validate_equations
from study.solver.friction import DEFAULT_EPS
from study.run_arguments import (BACKENDS, DEFAULT_ATOL, DEFAULT_FRICTION,  # noqa: F401 (re-exported)
                                 DEFAULT_OUTPUT_STEP, DEFAULT_RTOL, EVALUATIONS_PER_STEP, FIXED_STEP, INTEGRATOR_NAMES, check_arguments,
                                 check_run_size, fixed_step_evaluations, format_bytes, output_size)
from study.solver.index3 import ALI3P, NAME as INDEX3, integrate_index3
from study.solver.integrate import integrate
from study.solver.run import build_dynamics, output_times, run_bounds, run_metadata
from study.solver.stabilization import Stabilization, check_options

__all__ = ["BACKENDS", "DEFAULT_FRICTION", "DEFAULT_OUTPUT_STEP", "FIXED_STEP", "INTEGRATOR_NAMES", "build_dynamics",
           "check_run_size", "default_friction", "friction_entries", "resolve", "simulate", "simulate_methods"]



def resolve(eom_or_mechanism, variant: str | None):
    """An EquationsOfMotion, a Mechanism (a description with its parameter set) or a built-in mechanism name (with
    its variant) -> (eom, mechanism or None)."""
    from study.mechanisms import mechanism
    from study.model import Mechanism
    from study.params import load_parameters

    if isinstance(eom_or_mechanism, (EquationsOfMotion, Mechanism)) and variant is not None:
        raise ValueError(f"variant= applies to built-in mechanism names, not to a {type(eom_or_mechanism).__name__} "
                         f"(its parameter set is its own)")
    if isinstance(eom_or_mechanism, EquationsOfMotion):
        return eom_or_mechanism, None
    if isinstance(eom_or_mechanism, Mechanism):
        return eom_or_mechanism.equations(), eom_or_mechanism
    if isinstance(eom_or_mechanism, str):
        m = mechanism(load_parameters(eom_or_mechanism, variant or "seed"))
        return m.equations(), m
    raise ValueError(f"eom_or_mechanism = {eom_or_mechanism!r} must be an EquationsOfMotion, a Mechanism or a "
                     f"mechanism name")


def one_blas_thread(fn):
    """Run ``fn`` with one BLAS thread. The study's matrices are small (Phi_q of the 40-window four-bar is 80 x 81):
    from about that size on OpenBLAS splits a product over threads, which on a busy host wait for a core (and the
    waiting counts as process time), and whose order of summation depends on the thread count. The pipeline's
    workers run with one thread for the same reasons."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)
    return wrapper


@one_blas_thread
def simulate(
    eom_or_mechanism,
    q0=None,
    qd0=None,
    t_end: float = 1.0,
    *,
    method: str | Stabilization = "none",
    integrator: str = "RK45",
    rtol: float | None = None,
    atol: float | None = None,
    step: float | None = None,
    output_step: float = DEFAULT_OUTPUT_STEP,
    acceleration_solver: str | None = None,
    variant: str | None = None,
    progress: Callable[[float], None] | None = None,
    friction: str | None = DEFAULT_FRICTION,
    friction_eps: float | None = None,
    friction_sgn: str | None = None,
    resistance_reading: str | None = None,
    backend: str = "reference",
    check: bool = True,
    max_evaluations: float | None = None,
    min_step: float | None = None,
    max_output_bytes: float | None = None,
    **method_options,
) -> SimulationResult:
    """Simulate a constrained mechanism.

    Parameters
    ----------
    eom_or_mechanism : EquationsOfMotion, Mechanism or str
        A user's equations; a :class:`study.Mechanism` (a description with its parameter set: q0, qd0 default
        to its consistent initial state); or a study mechanism's name, e.g. 'slider_crank' (then ``variant``
        selects the parameter set, default 'seed', and q0, qd0 default to its consistent initial state).
    q0, qd0 : (m,) array_like
        Initial state; it should satisfy the constraints (see ``study.model.initial_state``).
    t_end : float
        End time [s], > 0.
    method : str or Stabilization
        Stabilization: 'none', 'baumgarte', 'sliding_mode', 'projection'; options go in
        ``method_options`` (d, omega or alpha, beta; Lambda, K, k, sgn, width; weighting). Or a
        ``study.solver.stabilization.Stabilization`` object (e.g. ``Baumgarte(d=1, omega=10)``, or a
        user's subclass on the reference backend), whose fields are its options.
    integrator : str
        'RK45', 'DOP853', 'RK23', 'Radau', 'LSODA' (scipy, adaptive: ``rtol``, default 1e-8, and ``atol``,
        default 1e-10) or 'RK4' (fixed ``step``, no longer than ``t_end``): these integrate the
        accelerations of ``acceleration_solver`` stabilized by ``method``. Or 'ALI3P' (fixed ``step``): the
        index-3 augmented Lagrangian with mass-orthogonal projections of Bayo and Ledesma on the trapezoidal
        rule (``study.solver.index3``), which holds the position constraints itself and passes singular
        positions; it takes no ``method`` but 'none', no ``acceleration_solver``, no friction, no switching
        loads, and runs on the reference backend. An argument the chosen integrator would ignore (``step``
        for an adaptive one, ``rtol``/``atol`` for a fixed-step one) is refused.
    acceleration_solver : str, optional
        'multiplier' (the default), 'partitioned' (R/D matrix) or 'orthonormal' (these need a full-rank
        Phi_q: a run stops at a singular pose with a SingularConfigurationError naming the time, pose and
        rank), or 'augmented_lagrangian' (passes singular poses and redundant constraints; no singularity
        monitor).
    output_step : float
        Spacing of the saved samples [s].
    friction : {'default', 'none', 'exact', 'regularized', 'sign'}
        Coulomb friction at the sliding contacts and pins (``study.solver.friction``). 'default': the parameter
        set's treatment of every entry with friction (``study.friction_default``); 'none' (or None) leaves them
        out, named in ``meta['friction_left_out']``. 'exact': event-located stick/slip; 'regularized': sgn replaced
        by ``friction_sgn`` ('tanh', 'sat', 'arctan', 'sqrt'; default 'tanh') of width ``friction_eps``
        [m/s] (default 1e-3); 'sign': paper 000's plain sgn (use with integrator='RK4'). ``friction_eps``
        also sets the band |v_t| <= eps reported as apparent stick by 'regularized' and 'sign'. A
        width or sgn the chosen treatment does not use is refused. The result gains
        forces ``normal_<c>``, ``friction_<c>``, ``stick_<c>`` and energies ``work_friction_<c>``.
        Revolute joints with friction (``Description.revolute(..., friction=, radius=)``) follow the contacts in
        these outputs (``normal_<pin>`` = |R| [N], ``friction_<pin>`` = the torque on the joint's first body
        [N m], ``friction_eps`` read in rad/s), with every treatment on both backends.
    resistance_reading : {None, 'holds', 'sliding_only'}
        Whether a contact's constant resistance counts in the static limit of the 'exact' treatment
        (``study.solver.friction.RESISTANCE_READINGS``). None: the parameter set's
        ``resistance_reading`` if it has one, else 'holds' (``study.model.SlidingContact.resistance``).
    backend : {'reference', 'compiled'}
        'reference': the Python solver with scipy's integrators. 'compiled': generated numba code and a
        compiled integration loop (``study.fast``; multiplier solver, RK23/RK45/DOP853/RK4; Radau and
        LSODA take scipy's steps on the compiled evaluations); an unsupported combination raises a
        ValueError naming the option.
    check : bool
        Validate the equations and the initial state once before the run (``study.solver.checks``:
        symmetric positive-definite M(q0), phi_q and gamma against finite differences of phi and
        phi_q, q0 and qd0 on the constraints); False skips it. A singular pose is refused either way.
    max_evaluations : float, optional
        Bound on right-hand-side evaluations (default ``max_evaluations`` in reference/tolerances.toml).
        A fixed-step run that needs more is refused before it starts, with its estimate.
    min_step : float, optional
        Smallest step of an adaptive integrator [s] (default ``min_step_fraction`` * t_end).
    max_output_bytes : float, optional
        Bound on the estimated memory of the output (default ``max_output_bytes``).

    Raises
    ------
    ValueError
        A bad argument (named); ``study.errors.EquationsError`` for equations or a state that fail
        the checks; ``study.errors.RunTooLargeError`` for a run refused by its estimate.
    study.errors.SimulationError
        The run failed: non-finite values, a singular configuration, a bound reached (time, quantity
        and likely cause in the message).

    Returns
    -------
    SimulationResult
    """
    given = check_arguments(t_end=t_end, method=method, integrator=integrator, rtol=rtol, atol=atol, step=step,
                            output_step=output_step, acceleration_solver=acceleration_solver, variant=variant,
                            progress=progress, friction=friction, friction_eps=friction_eps,
                            friction_sgn=friction_sgn, resistance_reading=resistance_reading, backend=backend,
                            check=check, max_evaluations=max_evaluations, min_step=min_step,
                            max_output_bytes=max_output_bytes)
    t_end, step, max_evaluations = given["t_end"], given["step"], given["max_evaluations"]
    rtol = DEFAULT_RTOL if rtol is None else given["rtol"]
    atol = DEFAULT_ATOL if atol is None else given["atol"]
    if not isinstance(method, Stabilization):
        method_options = check_options(method, method_options)
    eom, mech = resolve(eom_or_mechanism, variant)
    ps = None if mech is None else mech.parameters
    arguments.per_constraint(getattr(method, "name", method), _options_of(method, method_options), eom)
    friction, friction_eps, friction_sgn, stated = _friction(eom, ps, friction, given, integrator=integrator,
                                                             friction_eps=friction_eps, friction_sgn=friction_sgn,
                                                             backend=backend)
    index3 = integrator == INDEX3
    if index3 and eom.indicators is not None:
        raise ValueError(f"integrator 'ALI3P' does not locate the switches of {eom.name}'s discontinuous loads "
                         f"({', '.join(eom.indicator_names) or 'its indicators'}): use an ODE integrator (e.g. 'RK45')")
    acceleration_solver = ("augmented_lagrangian" if index3 else "multiplier") if acceleration_solver is None \
        else acceleration_solver
    if backend == "compiled":   # before anything compiles: importing the compiled path compiles its kernels
        check_supported(integrator, acceleration_solver, progress)
    min_rtol = tolerance("integrator_min_rtol")
    scipy_steps = backend == "reference" or integrator in SCIPY_STEPS_ONLY
    if scipy_steps and integrator not in FIXED_STEP and rtol < min_rtol:
        loop = "" if integrator in SCIPY_STEPS_ONLY else " (or backend='compiled', whose loop takes its own steps)"
        raise ValueError(f"rtol = {rtol!r} is below what scipy's {integrator} honours ({min_rtol:.3g} = 100 machine "
                         f"epsilons; it would silently raise it): use rtol >= {min_rtol:.3g}{loop}")
    max_evaluations, min_step = run_bounds(t_end, max_evaluations, min_step)
    max_output_bytes = tolerance("max_output_bytes") if max_output_bytes is None else max_output_bytes
    q0, qd0 = _initial_state(eom, mech, q0, qd0)
    check_run_size(eom, q0, qd0, float(t_end), integrator, step, output_step, friction, max_evaluations,
                   max_output_bytes)
    rank_tolerant = make_acceleration_solver(acceleration_solver).passes_singular
    monitor = None if rank_tolerant else SingularityMonitor(eom, q0)
    if monitor is not None:  # a singular start is refused even with check=False: nothing is determined there
        monitor.check(0.0, q0)
    if check:
        validate_equations(eom, q0, qd0)
    if resistance_reading is None:
        resistance_reading = getattr(ps.values, "resistance_reading", "holds") if ps is not None else "holds"
    if backend == "compiled":
        if friction == "exact" and resistance_reading != "holds":
            raise ValueError(f"backend 'compiled' implements resistance_reading 'holds' only, got "
                             f"{resistance_reading!r}: use backend='reference'")
    if not scipy_steps:
        from study.fast import simulate_compiled

        result = simulate_compiled(eom, mech, q0, qd0, t_end, method=method, integrator=integrator, rtol=rtol, atol=atol,
                                   step=step, output_step=output_step, acceleration_solver=acceleration_solver,
                                   progress=progress, friction=friction, friction_eps=friction_eps,
                                   friction_sgn=friction_sgn, max_evaluations=max_evaluations, min_step=min_step,
                                   **method_options)
        result.meta.update(stated)
        return result

    dyn, y0, switching = build_dynamics(eom, q0, qd0, method=method, acceleration_solver=acceleration_solver,
                                        friction=friction, friction_eps=friction_eps, friction_sgn=friction_sgn,
                                        resistance_reading=resistance_reading, **method_options)
    stabilization, law = dyn.stabilization, getattr(dyn, "law", None)
    m = eom.n_coordinates
    indicators = None
    if eom.indicators is not None and switching is None:
        def indicators(t, y):
            return eom.indicators(t, y[:m], y[m:2 * m])

    t_out = output_times(float(t_end), output_step)
    if index3:
        cpu0 = time.process_time()
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # non-finite states are diagnosed
            traj, stats = integrate_index3(dyn, y0, float(t_end), t_out, step, ALI3P(), progress)
        return _result(dyn, traj, stats, time.process_time() - cpu0, eom, ps, stated, integrator=integrator, rtol=None,
                       atol=None, step=step, acceleration_solver=acceleration_solver, output_step=output_step,
                       t_end=t_end, stabilization=stabilization, law=law)

    post_step = None
    if stabilization.projects:
        def post_step(y):
            q, qd, changed = stabilization.project(eom, y[:m], y[m:2 * m])
            return (np.concatenate([q, qd, y[2 * m:]]) if changed else y), changed

    rhs = None
    if backend == "compiled":
        from study.fast import compiled_rhs

        rhs = compiled_rhs(eom, mech, dyn)
    guard = RunGuard(dyn, monitor, max_evaluations, step if integrator in FIXED_STEP else None, float(t_end), rhs)
    cpu0 = time.process_time()
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # the guard reports non-finite values
        traj = integrate(guard, 0.0, y0, float(t_end), t_out, method=integrator, rtol=rtol, atol=atol,
                         step=step, indicators=indicators, post_step=post_step, progress=progress,
                         switching=switching, min_step=min_step,
                         monitor=None if monitor is None else (lambda t, y: monitor.check(t, y[:m])),
                         describe=guard.describe)
    stats = {"steps": traj.steps, "projections": traj.projections, "restarts": traj.restarts,
             "events": len(traj.events), "event_times": [e["t"] for e in traj.events],
             **dyn.accelerations.statistics()}
    if switching is not None:
        stats["friction_transitions"] = switching.transitions
    return _result(dyn, traj, stats, time.process_time() - cpu0, eom, ps, stated, integrator=integrator, rtol=rtol,
                   atol=atol, step=step, acceleration_solver=acceleration_solver, output_step=output_step, t_end=t_end,
                   stabilization=stabilization, law=law, backend=backend)


def _friction(eom: EquationsOfMotion, ps, friction, given: dict, friction_eps, friction_sgn, **run):
    """The friction a run takes (:func:`study.friction_default.treatment`), its width and sgn form with their
    defaults, and what the result states about it (whether it was the default, the entries left out)."""
    by_default = friction == DEFAULT_FRICTION
    friction = treatment(eom, ps, friction, given, friction_eps=friction_eps, friction_sgn=friction_sgn, **run)
    eps = DEFAULT_EPS if friction_eps is None else given["friction_eps"]
    sgn = "tanh" if friction_sgn is None else friction_sgn
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


def _options_of(method, options: dict) -> dict:
    """A method's options: those given with its name, or the fields of a Stabilization object."""
    if isinstance(method, Stabilization) and dataclasses.is_dataclass(method):
        return {f.name: getattr(method, f.name) for f in dataclasses.fields(method)}
    return {} if isinstance(method, Stabilization) else options


def simulate_methods(eom_or_mechanism: EquationsOfMotion | str, q0=None, qd0=None, t_end: float = 1.0, *,
                     methods=("none", "baumgarte", "sliding_mode", "projection"), **options) -> dict[str, SimulationResult]:
    """:func:`simulate` with each stabilization method in turn (default options), the other arguments the same."""
    return {method: simulate(eom_or_mechanism, q0, qd0, t_end, method=method, **options) for method in methods}


def _result(dyn, traj, stats: dict, cpu: float, eom: EquationsOfMotion, ps, stated: dict, **settings):
    """The samples of a run as a SimulationResult, with its statistics, settings and what ``stated`` adds."""
    nfev = dyn.nfev  # the evaluations of the run, before the samples' post-processing adds its own
    result = assemble_result(dyn, traj.t, traj.y, traj.modes)
    result.stats.update({"nfev": nfev, **stats, "cpu_seconds": cpu})
    result.meta.update(run_metadata(eom, ps, **settings), **stated)
    return result
