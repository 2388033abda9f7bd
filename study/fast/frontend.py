"""Python side of the compiled path: what it supports, packing of options, segments and events, result.

An in-house run on backend 'compiled' (``study.engines.inhouse_run.run_inhouse``) calls :func:`simulate_compiled`. It supports the described
mechanisms (kernels generated from their description) and a user's EquationsOfMotion whose callables
numba compiles (:mod:`study.fast.user`, which names what it cannot compile), the ``multiplier`` acceleration solver,
every stabilization (none, baumgarte, sliding_mode with every sgn approximation, projection),
friction None / 'regularized' / 'sign' / 'exact' in sliding contacts and revolute joints, and the integrators RK23,
RK45, DOP853 (scipy's error control) and RK4. Anything else raises a ValueError naming the option: there is no silent
fallback. Switches are located in the compiled loop; the new mode is set here by the reference loop's rule
(``study.laws.modes.switch``: loads: the crossing entry flips; exact friction:
``study.solver.friction.StickSlipSwitching.on_event``), then the next segment starts. Samples are post-processed by the reference
``study.solver.assemble.assemble_result``, so a result has exactly the reference's fields.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from types import ModuleType, SimpleNamespace

import numpy as np
from numba import types
from numba.core.types.function_type import WrapperAddressProtocol
from numba.core.typing.typeof import typeof_impl
from numba.experimental.function_type import _get_wrapper_address

from study.errors import NonFiniteError, RunBoundError
from study.kernels.cache import check, compile_lock
from study.fast.codegen import generated_module

from study.fast.dynamics import (ACCELERATIONS_ENTRY, CI_PROJECTS, PIN_NOT_CONVERGED, RHS_ENTRY, accelerations_entry,
                                 no_phases, rhs_entry, work_arrays)
from study.fast.loop import (DONE, FAIL_EVALUATIONS, FAIL_LOCATE, FAIL_NONFINITE, FAIL_PROJECTION, FAIL_RHS, FAIL_STALL,
                             FAIL_STEP, integrate_segment, segment_arrays, segment_signature)
from study.kernels.signatures import BIAS, EVALUATE, INDICATORS, KINEMATICS, PHASES
from study.laws.modes import as_mode, initial_mode, switch
from study.fast.steppers import tableau
from study.fast.support import METHOD_IDS, check_supported
from study.model import Mechanism
from study.model.eom import EquationsOfMotion
from study.model.coordinates import lower
from study.reference_data import tolerance
from study.results import SimulationResult
from study.solver.assemble import assemble_result
from study.solver.dynamics import Dynamics
from study.solver.friction import FrictionDynamics, StickSlipSwitching
from study.solver.run import build_dynamics, output_times, run_bounds, run_metadata
from study.solver.stabilization import Stabilization

_FAILURES = {FAIL_STEP: "the step size fell below the round-off limit",
             FAIL_RHS: "the acceleration problem failed (singular saddle-point system or a Painleve case of "
                       "the friction solve)",
             FAIL_PROJECTION: "the projection failed (singular system or no convergence)"}


def entry(dispatcher, signature):
    """An entry kernel (the loop, ``rhs_entry``, ``accelerations_entry``), compiled or loaded for its declared
    signature on first use, under the compile lock: a run pays only for the entries it calls (the compiled loop;
    scipy's integrators on compiled evaluations call ``rhs_entry`` alone)."""
    if signature.args not in dispatcher.overloads:
        with compile_lock(f"{_qualified(dispatcher)} {signature}"):
            dispatcher.disable_compile(False)
            dispatcher.compile(signature)
            dispatcher.disable_compile()
    return dispatcher


@dataclass(frozen=True)
class CompiledModel:
    """Generated numba functions of one parameter set, with the numbers they read.

    Attributes
    ----------
    module : the generated module (``evaluate``, ``indicators``, ``kinematics``), or the same three
        kernels of a user's equations (:func:`study.fast.user.user_kernels`)
    p : (k,) parameter vector in ``module.PARAMETERS`` order (empty for a user's equations)
    lp : load parameters (empty: the laws' numbers are parameters in ``p``)
    n_load_indicators : switching functions of the loads
    """

    module: ModuleType | SimpleNamespace
    p: np.ndarray
    lp: np.ndarray
    n_load_indicators: int
    work_names: tuple[str, ...]


_MODELS: dict[Mechanism, CompiledModel] = {}
_USER_MODELS: dict[int, tuple[EquationsOfMotion, CompiledModel]] = {}   # id -> (the equations, kept alive; model)


def user_model(eom: EquationsOfMotion) -> CompiledModel:
    """The compiled model of equations without a planar description (generated ones' module, or a user's callables
    compiled; once per object)."""
    if id(eom) not in _USER_MODELS:
        from study.fast.user import user_kernels

        k = user_kernels(eom)   # no symbolic parameters (study.fast.user)
        _USER_MODELS[id(eom)] = (eom, CompiledModel(k, np.zeros(0), np.zeros(0), k.N_LOAD_INDICATORS,
                                                    tuple(k.WORK_NAMES)))
    return _USER_MODELS[id(eom)][1]


def compiled_model(mechanism: Mechanism) -> CompiledModel:
    """The compiled model of a mechanism's description in relative coordinates (generated once, then from disk)."""
    if mechanism not in _MODELS:
        b = lower(mechanism.description, "relative")
        b.validate()
        mod = generated_module(b)
        p = np.array([float(b.values[k]) for k in mod.PARAMETERS])
        _MODELS[mechanism] = CompiledModel(mod, p, np.zeros(0), mod.N_LOAD_INDICATORS, tuple(mod.WORK_NAMES))
    return _MODELS[mechanism]


def compiled_bias(stabilization: Stabilization):
    """The compiled counterpart of a stabilization's bias: its class's own ``compiled_bias``.

    A class that does not define one itself (e.g. a user's subclass that changes ``bias`` only) is
    refused by name: the inherited compiled form would not be its bias.
    """
    cls = type(stabilization)
    if cls.__dict__.get("compiled_bias") is None:
        raise ValueError(f"backend='compiled': the stabilization {cls.__name__} (name {stabilization.name!r}) does "
                         f"not define its own compiled_bias (the compiled form of its bias, signature "
                         f"study.kernels.signatures.BIAS) and compiled_parameters; define them in the class, or use "
                         f"backend='reference'")
    return cls.compiled_bias


def compiled_phases(dyn: Dynamics):
    """The compiled form of the run's friction treatment: its class's ``compiled_phases`` (``no_phases`` without
    friction)."""
    law = getattr(dyn, "law", None)
    return no_phases if law is None else law.compiled_phases


def pin_numbers(dyn: Dynamics) -> tuple[float, float]:
    """(delta [N] of |R|_delta, relative tolerance of the torques' Newton solve) of the run's pins: the reference
    dynamics' own values (``FrictionDynamics``; zeros without friction or pins, where the kernels read neither)."""
    return getattr(dyn, "pin_numbers", (0.0, 0.0))


def pack_options(eom: EquationsOfMotion, stabilization: Stabilization, law, n_work: int,
                 n_load_modes: int, pin_numbers: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """The option arrays (ci, cf) in the layout of ``study.fast.dynamics``; ``pin_numbers``: see :func:`pin_numbers`."""
    r, nc = eom.n_constraints, len(eom.contacts)
    pins = tuple(eom.pin_frictions)
    s = stabilization
    cf = [getattr(s, "tol", 0.0)]
    cf += [c.mu_kinetic for c in eom.contacts] + [c.mu_static for c in eom.contacts]
    cf += [c.resistance for c in eom.contacts]
    cf += [p.mu_static * p.radius for p in pins] + [p.mu_kinetic * p.radius for p in pins] + [p.torque for p in pins]
    cf += [float(x) for x in pin_numbers]
    bias_offset = len(cf)
    cf += [float(x) for x in s.compiled_parameters(r)]
    ci = [int(s.projects), bias_offset, int(law is not None), int(law is not None and law.switched), len(cf),
          int(getattr(s, "weighting", "") == "mass"), int(getattr(s, "max_iter", 0)), n_load_modes]
    ci += [c.constraint_index for c in eom.contacts] + [k for p in pins for k in p.rows]
    ci += [len(pins), n_work, nc, r, eom.n_coordinates]
    if law is not None:
        cf += [float(x) for x in law.compiled_parameters()]
    return np.array(ci, dtype=np.int64), np.array(cf, dtype=float)


@dataclass
class Setup:
    """Everything one compiled run needs (reference dynamics for modes, switching and post-processing)."""

    model: CompiledModel
    dyn: Dynamics
    ci: np.ndarray
    cf: np.ndarray
    y0: np.ndarray
    switching: StickSlipSwitching | None
    n_load_modes: int
    bias: object     # the stabilization's compiled_bias
    phases: object   # the friction treatment's compiled_phases (no_phases without friction)


def setup(eom: EquationsOfMotion, mechanism: Mechanism | None, q0, qd0, method: str, friction, friction_eps, friction_sgn,
          acceleration_solver: str = "multiplier", **method_options) -> Setup:
    """Build the reference dynamics (``study.solver.run.build_dynamics``) and the compiled option arrays.

    ``mechanism`` None: a user's equations, whose callables are compiled as they are (:func:`user_model`)."""
    dyn, y0, switching = build_dynamics(eom, q0, qd0, method=method, acceleration_solver=acceleration_solver,
                                        friction=friction, friction_eps=friction_eps, friction_sgn=friction_sgn,
                                        **method_options)
    model, ci, cf = _pack(eom, mechanism, dyn)
    return Setup(model, dyn, ci, cf, y0, switching, model.n_load_indicators, compiled_bias(dyn.stabilization),
                 compiled_phases(dyn))


def _pack(eom: EquationsOfMotion, mechanism: Mechanism | None,
          dyn: Dynamics) -> tuple[CompiledModel, np.ndarray, np.ndarray]:
    """The compiled model of the equations (of ``mechanism``'s description, else of ``eom``'s callables) and the
    option arrays of the reference dynamics ``dyn``. The cache folders are checked first (``study.kernels.cache.check``):
    a run whose compiled code could not be saved is refused before anything is written."""
    check()
    planar = mechanism is not None and mechanism.kind == "planar"   # a spatial mechanism's equations are generated
    model = compiled_model(mechanism) if planar else user_model(eom)
    n_load = model.n_load_indicators
    if dyn.work_names != model.work_names:
        raise ValueError(f"backend='compiled': the loads {dyn.work_names} of the equations differ from the compiled "
                         f"description's {model.work_names}; the equations must come from the parameter set")
    law = getattr(dyn, "law", None)
    if law is not None and dyn.n_load_modes != n_load:
        raise ValueError(f"backend='compiled': {dyn.n_load_modes} load switching functions in the equations, "
                         f"{n_load} in the compiled description")
    return (model, *pack_options(eom, dyn.stabilization, law, len(dyn.work_names), n_load, pin_numbers(dyn)))


class FunctionAddress(WrapperAddressProtocol):
    """A compiled function passed from Python as a first-class function, at the cost of a pointer.

    Passing the numba dispatcher itself makes every call look its signature up again (~100 us); this holds
    the address of its compiled wrapper and its numba type (registered with ``typeof`` below). numba's
    ``_get_wrapper_address`` is not public API: requirements.lock pins the numba it is written for, and
    tests/test_fast.py runs Radau and LSODA through it against the reference path."""

    def __init__(self, dispatcher, signature):
        self._signature, self.numba_type = signature, types.FunctionType(signature)
        self._address = _get_wrapper_address(dispatcher, signature)

    def __wrapper_address__(self) -> int:
        return self._address

    def signature(self):
        return self._signature


@typeof_impl.register(FunctionAddress)
def _typeof_function_address(value: FunctionAddress, context):
    return value.numba_type


def compiled_rhs(eom: EquationsOfMotion, mechanism, dyn: Dynamics):
    """``dyn.rhs`` evaluated by the compiled kernels, for scipy's integrators (Radau, LSODA) on the reference loop.

    Same signature (t, y, mode) and the same count of evaluations in ``dyn.nfev``. Where the compiled solve fails,
    the reference ``dyn.rhs`` is evaluated at that state so that its error (singular system, Painleve case) is
    the one raised; if the reference succeeds there, the disagreement itself is raised."""
    model, ci, cf = _pack(eom, mechanism, dyn)
    evaluate, bias = FunctionAddress(model.module.evaluate, EVALUATE), FunctionAddress(compiled_bias(dyn.stabilization), BIAS)
    phases = FunctionAddress(compiled_phases(dyn), PHASES)
    p, lp = model.p, model.lp
    no_mode = np.zeros(0, dtype=np.int64)
    rhs_kernel = entry(rhs_entry, RHS_ENTRY)

    def rhs(t: float, y: np.ndarray, mode=None) -> np.ndarray:
        dyn.nfev += 1
        dy = np.empty(y.size)
        status = rhs_kernel(evaluate, bias, phases, float(t), np.ascontiguousarray(y, dtype=float),
                           no_mode if mode is None else np.asarray(mode, dtype=np.int64), p, lp, ci, cf, dy,
                           work_arrays(ci))
        if status != 0:
            dyn.rhs(t, y, mode)
            raise RuntimeError(f"compiled acceleration solve failed at t = {t:.9g} s ({_FAILURES[FAIL_RHS]}) "
                               f"where the reference solve succeeds; rerun with backend='reference'")
        return dy

    return rhs


def accelerations(s: Setup, t: float, q, qd, mode=(), repeat: int = 1) -> np.ndarray:
    """[qdd, lambda, N, f] at one state from the compiled kernels (``repeat`` times, for timing); N and f list the
    sliding contacts, then the revolute joints with friction (|R| [N], the torque [N m])."""
    eom = s.dyn.eom
    m, r = eom.n_coordinates, eom.n_constraints
    nt = len(eom.contacts) + len(eom.pin_frictions)
    out = np.zeros(m + r + 2 * nt)
    status = entry(accelerations_entry, ACCELERATIONS_ENTRY)(s.model.module.evaluate, s.bias, s.phases, float(t),
                                 np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float),
                                 np.asarray(mode, dtype=np.int64), s.model.p, s.model.lp, s.ci, s.cf, out, int(repeat),
                                 work_arrays(s.ci))
    if status == PIN_NOT_CONVERGED:
        _pin_failure(s.dyn, t, q, qd, mode)
    if status != 0:
        raise RuntimeError(f"compiled acceleration solve failed at t = {t}: {_FAILURES[FAIL_RHS]}")
    return out


def _pin_failure(dyn: Dynamics, t: float, q, qd, mode) -> None:
    """Raise the reference's PinFrictionError of a state where the compiled Newton solve of the pins' torques did not
    converge (the reference solve at that state raises it, with its iterations in the message); if the reference
    converges there, the disagreement is raised."""
    dyn.contact_solution(float(t), np.asarray(q, dtype=float), np.asarray(qd, dtype=float), tuple(mode) or None)
    raise RuntimeError(f"compiled solve of the revolute joints' friction torques did not converge at t = {t:.9g} s "
                       f"where the reference solve converges; rerun with backend='reference'")


def _raise_failure(outcome: int, integrator: str, t_reached: float, i_event: int, counters: np.ndarray,
                   y_end: np.ndarray, mode: tuple, s: Setup, max_evaluations: float, min_step: float) -> None:
    """The error of a compiled segment that ended with a failure code (``outcome < 0``), with its counts."""
    m = s.dyn.eom.n_coordinates
    if outcome == FAIL_EVALUATIONS:
        raise RunBoundError(f"{integrator} (compiled) stopped at t = {t_reached:.9g} s: {counters[2]} evaluations "
                            f"reached max_evaluations = {max_evaluations:g} (a stalled or far too long run; "
                            f"max_evaluations= raises the bound)", t=float(t_reached), quantity="evaluations",
                            evaluations=int(counters[2]))
    if outcome == FAIL_STALL:
        raise RunBoundError(f"{integrator} (compiled) stopped at t = {t_reached:.9g} s: {counters[5]} steps in a "
                            f"row below min_step = {min_step:.3g} s (a stall: the solution is near a singularity "
                            f"or a discontinuity; min_step= overrides)", t=float(t_reached), quantity="step",
                            steps=int(counters[1]))
    if outcome == FAIL_LOCATE:
        raise RunBoundError(f"{integrator} (compiled) stopped at t = {t_reached:.9g} s: the switch of switching "
                            f"function {i_event} cannot be located within the step from there (its interpolant "
                            f"returns to the side it started on and stays there, or shows no sign change): the step is too large for the "
                            f"solution (use a smaller rtol)", t=float(t_reached), quantity="step")
    if outcome == FAIL_NONFINITE:
        raise NonFiniteError(f"{integrator} (compiled) failed at t = {t_reached:.9g} s: a non-finite value in the "
                             f"right-hand side (accelerations, multipliers or load powers) of the step ending "
                             f"there; likely causes: a step too large for the solution (RK4), non-finite "
                             f"forces, or a singular configuration", t=float(t_reached),
                             quantity="rhs")
    if outcome == FAIL_RHS and counters[6] == PIN_NOT_CONVERGED:
        _pin_failure(s.dyn, t_reached, y_end[:m], y_end[m:2 * m], mode)
    if outcome < 0:
        raise RuntimeError(f"{integrator} (compiled) failed at t = {t_reached:.9g}: {_FAILURES[outcome]}; "
                           f"rerun with backend='reference' for a diagnosis")


def loop_kernels(s: Setup) -> tuple:
    """(phases, kinematics) as the loop receives them: None where a run does not call them (no friction, no
    post-step projection), so the loop is compiled without them (``study.fast.loop.segment_signature``)."""
    friction, projects = s.phases is not no_phases, bool(s.ci[CI_PROJECTS])
    return (s.phases if friction else None), (s.model.module.kinematics if projects else None)


def compile_kernels(s: Setup) -> None:
    """Compile (or load) the kernels with declared signatures that the run passes to the loop, each under its
    compile lock and before the run's CPU time is taken: they compile on first use (``study.kernels.cache.kernel``),
    which would otherwise be in the run's first segment."""
    phases, kinematics = loop_kernels(s)
    module = s.model.module
    kernels = [(k, signature) for k, signature in ((module.evaluate, EVALUATE), (module.indicators, INDICATORS),
                                                    (s.bias, BIAS), (phases, PHASES), (kinematics, KINEMATICS))
               if k is not None]
    for kernel, signature in kernels:
        with compile_lock(f"{_qualified(kernel)} {signature}"):
            kernel.get_compile_result(signature)


def _qualified(kernel) -> str:
    """A kernel's module and qualified name: the same in every process (the name of its compile lock)."""
    f = getattr(kernel, "py_func", kernel)
    return f"{getattr(f, '__module__', '')}.{getattr(f, '__qualname__', type(f).__name__)}"


def run(s: Setup, t_end: float, t_out: np.ndarray, integrator: str, rtol: float, atol: float, step,
        max_evaluations: float | None = None, min_step: float | None = None):
    """Integrate with the compiled loop; returns (t, y, modes, stats) of the samples.

    The run is bounded as on the reference path: RunBoundError once its evaluations reach
    ``max_evaluations``, or after ``min_step_run`` (reference/tolerances.toml) adaptive steps in a row
    shorter than ``min_step``; both default as on the reference path (``study.solver.run.run_bounds``).
    """
    max_evaluations, min_step = run_bounds(t_end, max_evaluations, min_step)
    eom, model = s.dyn.eom, s.model
    m = eom.n_coordinates
    tab = tableau(integrator)
    arrays, (n_stages, order, n_rows) = tab[:7], tab[7:]
    if s.switching is not None:
        mode = as_mode(s.switching.initial_mode(0.0, s.y0.copy()))
    elif s.n_load_modes:
        def indicators(t, y):
            return eom.indicators(t, y[:m], y[m:2 * m])
        mode = initial_mode(indicators, 0.0, s.y0, s.dyn.rhs)
    else:
        mode = ()
    n_mode = len(mode)
    y_out = np.zeros((len(t_out), len(s.y0)))
    mode_out = np.zeros((len(t_out), max(n_mode, 1)), dtype=np.int64)
    counters = np.array([0, 0, 0, 0, 1, 0, 0], dtype=np.int64)
    bounds = np.array([float(max_evaluations), float(min_step), float(tolerance("min_step_run"))])
    y, t, y_end = s.y0.copy(), 0.0, np.zeros(len(s.y0))
    events, restarts = [], 0
    first = float(step) if step is not None else 0.0
    phases, kinematics = loop_kernels(s)
    segment = entry(integrate_segment, segment_signature(phases is not None, kinematics is not None))
    while True:
        outcome, t_reached, i_event = segment(
            model.module.evaluate, s.bias, phases, model.module.indicators, kinematics,
            METHOD_IDS[integrator], arrays, n_stages, order, n_rows, t, y, float(t_end), first, float(rtol), float(atol),
            np.asarray(mode if n_mode else (0,), dtype=np.int64)[:n_mode], model.p, model.lp, s.ci, t_out, s.cf,
            y_out, mode_out, counters, y_end, bounds, work_arrays(s.ci),
            segment_arrays(METHOD_IDS[integrator], arrays, n_stages, n_rows, len(s.y0), s.ci))
        restarts += 1
        if outcome < 0:
            _raise_failure(outcome, integrator, t_reached, i_event, counters, y_end, mode, s, max_evaluations, min_step)
        if outcome == DONE:
            break
        t, y = float(t_reached), y_end.copy()
        mode = switch(s.switching, t, y, mode, int(i_event), events)
    k = int(counters[0])
    modes = [tuple(int(v) for v in row[:n_mode]) if n_mode else None for row in mode_out[:k]]
    stats = {"steps": int(counters[1]), "nfev": int(counters[2]), "projections": int(counters[3]),
             "restarts": restarts, "events": len(events), "event_times": [e["t"] for e in events]}
    return t_out[:k].copy(), y_out[:k].copy(), modes, stats


def simulate_compiled(eom: EquationsOfMotion, mechanism, q0, qd0, t_end: float, *, method: str,
                      integrator: str, rtol: float, atol: float, step, output_step: float,
                      acceleration_solver: str, progress, friction, friction_eps: float, friction_sgn: str,
                      max_evaluations: float, min_step: float, **method_options) -> SimulationResult:
    """The compiled backend of an in-house run (arguments already checked by its ``InHouse`` specification; what
    the compiled backend supports checked again here, for a direct call)."""
    check_supported(integrator, acceleration_solver, progress)
    s = setup(eom, mechanism, q0, qd0, method, friction, friction_eps, friction_sgn, acceleration_solver, **method_options)
    t_out = output_times(float(t_end), output_step)
    compile_kernels(s)
    cpu0 = time.process_time()
    t, y, modes, stats = run(s, float(t_end), t_out, integrator, rtol, atol, step, max_evaluations, min_step)
    cpu = time.process_time() - cpu0
    result = assemble_result(s.dyn, t, y, modes)
    result.stats.update({**stats, "cpu_seconds": cpu})
    if s.switching is not None:
        result.stats["friction_transitions"] = s.switching.transitions
    law = s.dyn.law if isinstance(s.dyn, FrictionDynamics) else None
    ps = None if mechanism is None else mechanism.parameters
    result.meta.update(run_metadata(eom, ps, integrator=integrator, rtol=rtol, atol=atol, step=step,
                                    acceleration_solver=acceleration_solver, output_step=output_step, t_end=t_end,
                                    stabilization=s.dyn.stabilization, law=law, backend="compiled"))
    return result
