"""A run's arguments before any work: the settings a run takes unless told otherwise, :func:`check_arguments` (types,
ranges, choices and the combinations that would be silently ignored) and :func:`check_run_size` (the output and the
fixed-step cost against their bounds), with the estimates they share with the case lists and ``study validate``.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from study import arguments
from study.errors import RunTooLargeError
from study.model.eom import EquationsOfMotion
from study.reference_data import tolerance
from study.solver.index3 import NAME as INDEX3
from study.solver.integrate import INTEGRATORS
from study.solver.stabilization import Stabilization

# friction= unless told otherwise: the parameter set's treatment of every friction entry (sliding contacts and pins,
# study.friction_default).
DEFAULT_FRICTION = "default"
# Default output spacing [s]: 100 samples per second resolve the quick-return's crank period
# (1 s) with 100 points and the slider-crank's slow motion with room to spare.
DEFAULT_OUTPUT_STEP = 0.01
# Tolerances of the adaptive integrators unless given: the study's working accuracy (reference/tolerances.toml
# keeps the reference runs' own).
DEFAULT_RTOL, DEFAULT_ATOL = 1e-8, 1e-10
# 'reference': Python + scipy (the default); 'compiled': study.fast (numba).
BACKENDS = ("reference", "compiled")
# scipy's OdeSolvers and RK4 integrate the index-1 ODE; ALI3P (study.solver.index3) is its own index-3 formulation.
INTEGRATOR_NAMES = (*INTEGRATORS, INDEX3)
FIXED_STEP = ("RK4", INDEX3)
# Right-hand-side evaluations a fixed step takes, at least: RK4's four stages; ALI3P's Newton iterations
# (two where the step converges at once; more at singular positions).
EVALUATIONS_PER_STEP = {"RK4": 4, INDEX3: 2}


def check_arguments(*, t_end, method, integrator, rtol, atol, step, output_step, acceleration_solver, variant,
                    progress, friction, friction_eps, friction_sgn, resistance_reading, backend, check,
                    max_evaluations, min_step, max_output_bytes, names: Mapping[str, str] | None = None) -> dict:
    """:func:`simulate`'s arguments checked before any work: types, ranges, choices, and the combinations
    that would be silently ignored (a step for an adaptive integrator, a width or sgn the friction treatment
    does not use, a step or output step longer than the horizon ``t_end``; None: a run specification's checks,
    without its horizon). Returns the numbers converted.

    ``names`` maps an argument to the way the user gave it (the command line passes its flags)."""
    from study.solver.accelerations import ACCELERATION_SOLVERS
    from study.solver.friction import FRICTION_TREATMENTS, RESISTANCE_READINGS
    from study.solver.stabilization import SIGN_FUNCTIONS, STABILIZATIONS

    names = names or {}

    def w(key: str) -> str:
        return names.get(key, key)

    def n(key, value, **kw):
        return arguments.number(w(key), value, **kw)

    given = {"t_end": n("t_end", t_end, optional=True), "output_step": n("output_step", output_step),
             "rtol": n("rtol", rtol, optional=True), "atol": n("atol", atol, optional=True),
             "step": n("step", step, optional=True), "friction_eps": n("friction_eps", friction_eps, optional=True),
             "max_evaluations": n("max_evaluations", max_evaluations, whole=True, optional=True),
             "min_step": n("min_step", min_step, optional=True),
             "max_output_bytes": n("max_output_bytes", max_output_bytes, optional=True)}
    if not isinstance(method, Stabilization):
        arguments.choice(w("method"), method, STABILIZATIONS)
    arguments.choice(w("integrator"), integrator, INTEGRATOR_NAMES)
    arguments.choice(w("acceleration_solver"), acceleration_solver, ACCELERATION_SOLVERS, optional=True)
    arguments.choice(w("backend"), backend, BACKENDS)
    arguments.choice(w("friction"), friction, [*FRICTION_TREATMENTS, "none", DEFAULT_FRICTION], optional=True)
    friction = None if friction == "none" else friction
    if friction_sgn == "sign":
        raise ValueError(f"{w('friction_sgn')} = 'sign' is not a smooth sgn (the plain sgn is {w('friction')}='sign'); "
                         f"valid choices: {', '.join(k for k in SIGN_FUNCTIONS if k != 'sign')}")
    arguments.choice(w("friction_sgn"), friction_sgn, [k for k in SIGN_FUNCTIONS if k != "sign"], optional=True)
    arguments.choice(w("resistance_reading"), resistance_reading, RESISTANCE_READINGS, optional=True)
    arguments.text(w("variant"), variant, optional=True)
    arguments.function(w("progress"), progress)
    arguments.flag(w("check"), check)
    t_end = given["t_end"]
    if integrator in FIXED_STEP:
        if step is None:
            raise ValueError(f"{w('integrator')} {integrator} is fixed-step: give {w('step')} (the step size h > 0)")
        if rtol is not None or atol is not None:
            raise ValueError(f"{w('rtol')}/{w('atol')} do not apply to {w('integrator')} {integrator} (fixed step)")
        if t_end is not None and given["step"] > t_end:
            raise ValueError(f"{w('step')} = {step:g} s is longer than {w('t_end')} = {t_end:g} s: {integrator} would "
                             f"take one shortened step")
    elif step is not None:
        raise ValueError(f"{w('step')} = {step!r} applies to the fixed-step integrators ({', '.join(FIXED_STEP)}); "
                         f"{integrator} is adaptive (its accuracy is set by {w('rtol')} and {w('atol')})")
    if integrator == INDEX3:
        not_for_index3 = [(w("method"), method, "it holds the position constraints itself",
                           getattr(method, "name", method) != "none"),
                          (w("acceleration_solver"), acceleration_solver, "it is its own augmented Lagrangian",
                           acceleration_solver is not None),
                          (w("friction"), friction, f"its steps do not locate stick/slip switches; run it with {w('friction')} none",
                           friction not in (None, DEFAULT_FRICTION)),   # the default: checked once it is known
                          (w("backend"), backend, "it runs on the reference backend", backend != "reference")]
        for name, value, why, given_here in not_for_index3:
            if given_here:
                raise ValueError(f"{name} = {value!r} does not apply to {w('integrator')} ALI3P: {why}")
    if t_end is not None and given["output_step"] > t_end:
        raise ValueError(f"{w('output_step')} = {output_step:g} s is longer than {w('t_end')} = {t_end:g} s (the result "
                         f"would hold only t = 0 and t_end)")
    if friction == DEFAULT_FRICTION:   # the parameter set's treatment: its combinations are checked once it is known
        return given
    if friction_eps is not None and friction not in ("regularized", "sign"):
        raise ValueError(f"{w('friction_eps')} = {friction_eps!r} applies to friction 'regularized' (its width) and "
                         f"'sign' (its stick band); {w('friction')} = {friction or 'none'} has no width")
    if friction_sgn is not None and friction != "regularized":
        raise ValueError(f"{w('friction_sgn')} = {friction_sgn!r} applies to friction 'regularized' only; "
                         f"{w('friction')} = {friction or 'none'} does not use it")
    return given


def check_run_size(eom: EquationsOfMotion, q0: np.ndarray, qd0: np.ndarray, t_end: float, integrator: str,
                   step: float | None, output_step: float, friction: str | None, max_evaluations: float,
                   max_output_bytes: float) -> None:
    """Refuse, before anything is allocated, a run whose output or fixed-step cost exceeds its bounds.

    The output holds ~t_end / output_step samples of 1 + 3m + 3r + 2 + (loads) + 4 (contacts) columns at
    ``output_bytes_per_value`` each; a fixed-step run takes ``EVALUATIONS_PER_STEP`` evaluations per step. The message gives
    the estimate and the argument that raises the bound (the user's confirmation).
    """
    samples, columns, nbytes = output_size(eom, q0, qd0, t_end, output_step, friction)
    if not nbytes <= max_output_bytes:
        raise RunTooLargeError(
            f"t_end = {t_end:g} s at output_step = {output_step:g} s asks for {samples:.3g} samples of {columns} "
            f"values, about {format_bytes(nbytes)} of memory, above max_output_bytes = {format_bytes(max_output_bytes)}: use a "
            f"larger output_step or a shorter t_end, or pass max_output_bytes= to confirm")
    if integrator in FIXED_STEP:
        per_step = EVALUATIONS_PER_STEP[integrator]
        evaluations = fixed_step_evaluations(integrator, t_end, step)
        if not evaluations <= max_evaluations:
            cpu = evaluations * tolerance("seconds_per_evaluation")
            raise RunTooLargeError(
                f"{integrator} with step = {step:g} s over t_end = {t_end:g} s takes {evaluations / per_step:.3g} steps "
                f"= {evaluations:.3g} evaluations (at least {_duration(cpu)} of CPU, ~{format_bytes(nbytes)} of output), "
                f"above max_evaluations = {max_evaluations:g}: pass max_evaluations={evaluations:.0f} "
                f"(--max-evaluations) to confirm, or use a larger step")


def fixed_step_evaluations(integrator: str, t_end: float, step: float) -> float:
    """The evaluations of a fixed-step run (known before it starts): EVALUATIONS_PER_STEP per step, and the first."""
    return EVALUATIONS_PER_STEP[integrator] * np.ceil(t_end / step) + 1


def output_size(eom: EquationsOfMotion, q0: np.ndarray, qd0: np.ndarray, t_end: float, output_step: float,
                friction: str | None) -> tuple[float, int, float]:
    """A run's output: (samples, columns, estimated bytes); see :func:`check_run_size`."""
    m, r = eom.n_coordinates, eom.n_constraints
    n_contacts = len(eom.contacts) + len(getattr(eom, "pin_frictions", ())) if friction is not None else 0
    columns = 1 + 3 * m + 3 * r + 2 + len(eom.applied_forces(0.0, q0, qd0)) + 4 * n_contacts
    samples = t_end / output_step + 2
    return samples, columns, samples * columns * tolerance("output_bytes_per_value")


def format_bytes(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} PiB"  # pragma: no cover


def _duration(seconds: float) -> str:
    for unit, size in (("years", 3.15e7), ("days", 86400.0), ("hours", 3600.0), ("minutes", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"
