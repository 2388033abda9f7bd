"""The timing harness: one timed run (in-house or Exudyn), medians of repeated timings, the error measure.

CPU times are ``time.process_time`` of the integration only (in-house: ``stats['cpu_seconds']``;
Exudyn: the process time around its ``SolveDynamic``), medians of :data:`~study.bench.settings.REPEATS`
runs; runs longer than :data:`~study.bench.settings.LONG_RUN` s are repeated fewer times
(:func:`repeats_for`, at least once); every table row records its repeats.
"""

from __future__ import annotations

import os
import platform
import sys
import time

import numpy as np

from study.bench.settings import EPS, EXUDYN_ENGINES, LONG_RUN, LONG_RUN_TOTAL, OUTPUT_STEP, repeats
from study.compare import max_deviation
from study.results import package_versions
from study.simulate import simulate


def log(msg: str) -> None:
    """Progress line on stderr."""
    print(f"[bench {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def machine() -> dict:
    """Platform, CPU count and package versions."""
    import numba

    return {"platform": platform.platform(), "processor": platform.processor() or platform.machine(),
            "cpu_count": os.cpu_count(), "python": sys.version.split()[0],
            **{k: v for k, v in package_versions().items() if k != "platform"}, "numba": numba.__version__}


def repeats_for(cpu: float, quick: bool = False) -> int:
    """Timings of a run that took ``cpu`` seconds once: :func:`~study.bench.settings.repeats`, fewer (>= 1) for long runs.

    Parameters
    ----------
    cpu : float
        CPU seconds of one run.
    quick : bool
        A ``--quick`` smoke run (fewer repeats).

    Returns
    -------
    int
        ``repeats(quick)`` below :data:`LONG_RUN` s, else ``LONG_RUN_TOTAL // cpu`` clipped to 1 ... repeats(quick).
    """
    if not np.isfinite(cpu) or cpu < LONG_RUN:
        return repeats(quick)
    return int(max(1, min(repeats(quick), LONG_RUN_TOTAL // cpu)))


def median_cpu(fn, repeats: int) -> tuple[float, object]:
    """Median of fn()'s returned CPU seconds over ``repeats`` calls, and the last result."""
    values, last = [], None
    for _ in range(repeats):
        cpu, last = fn()
        values.append(cpu)
    return float(np.median(values)), last


def inhouse_timer(mech, variant, t_end, extra, backend, integrator, setting):
    """A timing closure: one in-house run -> (CPU seconds of the integration, result)."""
    kw = dict(eom_or_mechanism=mech, variant=variant, t_end=t_end, integrator=integrator, backend=backend,
              output_step=OUTPUT_STEP, **extra)
    if integrator == "RK4":
        kw["step"] = setting
    else:
        kw.update(rtol=setting, atol=setting * 1e-2)

    def fn():
        r = simulate(**kw)
        return r.stats["cpu_seconds"], r
    return fn


def exudyn_timer(mech, variant, t_end, solver, h, configuration="tuned"):
    """A timing closure: one Exudyn run at fixed step h -> (process CPU seconds of SolveDynamic, result).

    The process CPU time around ``SolveDynamic`` (Exudyn's initialization and time loop, user functions
    included), like the in-house ``process_time`` of the integration; Exudyn's own ``timer.total`` is
    wall-clock time (measured: 1.5-2x the process time on the shared, loaded machine).
    """
    from study import exudyn_models
    from study.params import load_parameters

    ps = load_parameters(mech, variant)

    def fn():
        r = exudyn_models.run(ps, t_end, h, solver=solver, output_step=OUTPUT_STEP, friction="regularized", eps=EPS,
                              configuration=configuration)
        return r.stats["process_cpu_seconds"], r
    return fn


def max_dq(result, ref) -> float:
    """max over the output samples and coordinates of |q - q_ref| [rad]; both must share every sample."""
    if len(result.t) != len(ref.t):
        raise ValueError(f"run has {len(result.t)} samples, reference {len(ref.t)}: not comparable")
    return max_deviation(result, ref, "q")


def timer(mech, variant, t_end, extra, engine, method, setting):
    if engine in EXUDYN_ENGINES:
        return exudyn_timer(mech, variant, t_end, method, setting, EXUDYN_ENGINES[engine])
    return inhouse_timer(mech, variant, t_end, extra, "compiled" if "compiled" in engine else "reference", method, setting)
