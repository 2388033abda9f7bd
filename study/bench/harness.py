"""The timing harness: a run as a case of the pipeline, medians of repeated timings, the error measure.

Every run of the benchmark is a case (``reference/cases/bench.toml``, or one built by
:func:`inhouse_case` / :func:`at_setting` for a setting the list cannot hold in advance) run
through the pipeline's store (:func:`execute`: cached, checked on every read, in this process, one at
a time); its k-th timing is the case with option ``repeat = k`` (:func:`repeat_of`). CPU times are
``time.process_time`` of the integration only (in-house: ``stats['cpu_seconds']``; Exudyn: the process
time around its ``SolveDynamic``), medians of :data:`~study.bench.settings.REPEATS` runs; runs longer than :data:`~study.bench.settings.LONG_RUN` s are repeated fewer times
(:func:`repeats_for`, at least once); every table row records its repeats.
"""

from __future__ import annotations

import os
import platform
import sys
import time
from dataclasses import replace

import numpy as np

from study.bench.settings import CASE_LIST, LONG_RUN, LONG_RUN_TOTAL, OUTPUT_STEPS, STORE_FOLDER, repeats
from study.compare import max_deviation
from study.model.compile import cache_dir
from study.pipeline import Case, InlineExecutor, Store, run_cases
from study.results import SimulationResult, package_versions


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
    """Timings of a run that took ``cpu`` seconds once: :func:`~study.bench.settings.repeats`, fewer (>= 1)
    for long runs.

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


def inhouse_case(mech: str, variant: str, t_end: float, extra: dict, backend: str, integrator: str, setting: float,
                 group: str) -> Case:
    """An in-house run of the benchmark as a case: rtol ``setting`` (atol = rtol/100), or RK4's step."""
    options = dict(integrator=integrator, backend=backend, output_step=OUTPUT_STEPS[mech], **extra)
    if integrator == "RK4":
        options["step"] = setting
    else:
        options.update(rtol=setting, atol=setting * 1e-2)
    return Case(CASE_LIST.study, group, "inhouse", mech, variant, float(t_end), tuple(sorted(options.items())),
                (("setting", f"{setting:g}"),))


def _with(case: Case, options: dict, labels: dict) -> Case:
    return replace(case, options=tuple(sorted({**case.kwargs, **options}.items())),
                   labels=tuple({**dict(case.labels), **labels}.items()))


def at_setting(case: Case, value: float) -> Case:
    """The case at another value of what its sweep varies (see :func:`setting`; atol follows rtol / 100)."""
    options = case.kwargs
    if case.engine == "exudyn":
        new = {"h": value}
    elif "step" in options:
        new = {"step": value}
    else:
        new = {"rtol": value, "atol": value * 1e-2}
    return _with(case, new, {"setting": f"{value:g}"})


def with_labels(case: Case, **labels: str) -> Case:
    """The case with labels added (what the benchmark ran it for, e.g. ``stage``): the same key."""
    return _with(case, {}, labels)


def repeat_of(case: Case, k: int) -> Case:
    """The k-th timing of a case (k = 0: the case itself): option ``repeat = k``, the same result."""
    return case if k == 0 else _with(case, {"repeat": k}, {"repeat": str(k)})


def setting(case: Case) -> float:
    """The value a sweep varies: Exudyn's step h, RK4's step or rtol."""
    options = case.kwargs
    return float(options["h"] if case.engine == "exudyn" else options.get("step", options.get("rtol")))


def bench_store() -> Store:
    """The benchmark's saved runs: folder :data:`~study.bench.settings.STORE_FOLDER` of the cache root."""
    return Store(cache_dir() / STORE_FOLDER)


def execute(case: Case) -> SimulationResult:
    """Run a case through the pipeline's store in this process (reused if saved); its saved result.

    Raises :class:`study.pipeline.MissingResult` naming the error if the run failed.
    """
    store = bench_store()
    run_cases([case], store, InlineExecutor(), title=case.name)
    return store.load(case)


def cpu_seconds(case: Case, result: SimulationResult) -> float:
    """CPU of a run's integration: in-house ``stats['cpu_seconds']``; Exudyn the process time around
    ``SolveDynamic`` (its own ``timer.total`` is wall-clock time, measured 1.5-2x the process time on
    the shared, loaded machine), user functions included."""
    return float(result.stats["process_cpu_seconds" if case.engine == "exudyn" else "cpu_seconds"])


def timed(case: Case, n: int) -> tuple[float, SimulationResult]:
    """Median CPU of ``n`` timings of a case (repeats 0 ... n-1, each a saved run), and the last result."""
    results = [execute(repeat_of(case, k)) for k in range(n)]
    return float(np.median([cpu_seconds(case, r) for r in results])), results[-1]


def max_dq(result, ref) -> float:
    """max over the output samples and coordinates of |q - q_ref| [rad]; both must share every sample."""
    if len(result.t) != len(ref.t):
        raise ValueError(f"run has {len(result.t)} samples, reference {len(ref.t)}: not comparable")
    return max_deviation(result, ref, "q")
