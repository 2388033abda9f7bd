"""Running cases: one case in a worker, and every case not stored yet, saved as each arrives.

:func:`run_cases` runs whatever is not stored yet on an executor (:mod:`study.pipeline.executors`),
saves each result as it arrives (atomically: an interrupted run leaves no half-written result and
resumes where it stopped) and records failed cases with their error without stopping the others.
"""

from __future__ import annotations

import math
import sys
import time
import traceback
from concurrent.futures import Executor, Future, as_completed
from dataclasses import dataclass, field
from typing import Callable, Iterable, Iterator, Mapping

import numpy as np
from threadpoolctl import threadpool_limits

from study.pipeline.cases import Case
from study.pipeline.executors import InlineExecutor
from study.pipeline.keys import code_version, mechanism_of
from study.pipeline.store import Store
from study.results import SimulationResult

Announce = Callable[[Case], "Callable[[float], None] | None"]   # a case about to run -> its progress callback


def run_case(case: Case, progress: Callable[[float], None] | None = None) -> SimulationResult:
    """Compute one case (in whatever process the executor chose): its options are a serialized run specification
    (:func:`study.engines.spec_from_dict`, engine ``case.engine``), run by :func:`study.engines.run`; ``progress``
    (an in-house run): called with the time reached."""
    from study.engines.runner import run, spec_from_dict

    mech = mechanism_of(case.mechanism, case.variant)
    options = case.kwargs
    options.pop("repeat", None)  # the k-th timing of the same run (a key of its own, the same result)
    q0 = qd0 = None
    if case.engine == "inhouse":
        q0, qd0 = initial_state(case, mech, options)
    return run(mech, spec_from_dict({"engine": case.engine, **options}), case.t_end, q0=q0, qd0=qd0, progress=progress)


def initial_state(case: Case, mech, options: dict) -> tuple:
    """An in-house case's initial state (None: the mechanism's consistent one), from its options ``initial``,
    ``perturb_ulps``, ``q0`` and ``qd0`` (consumed; 'printed' also sets ``check`` False)."""
    initial = options.pop("initial", "consistent")
    ulps = options.pop("perturb_ulps", 0)  # conditioning check (study.verify): q0, qd0 moved by ulps
    q0, qd0 = options.pop("q0", None), options.pop("qd0", None)
    if initial == "printed":  # the paper's printed state, used as is (see the parameter file)
        ic = mech.parameters.initial
        # off the constraints on purpose (the study shows what that does): the check would refuse it
        q0, qd0, options["check"] = list(ic.printed_q), list(ic.printed_qd), False
    elif initial != "consistent":
        raise ValueError(f"case {case.name}: initial = {initial!r} must be 'consistent' or 'printed'")
    if ulps:
        if q0 is None:
            state = mech.initial_state()
            q0, qd0 = state.q, state.qd
        q0, qd0 = (np.add(x, ulps * np.spacing(np.asarray(x, float))) for x in (q0, qd0))
    return q0, qd0


def _run_case_timed(case: Case, progress: Callable[[float], None] | None = None) -> tuple[SimulationResult, float, str]:
    """Run a case; also returns the wall time and the code version of the process that ran it."""
    t0 = time.perf_counter()
    # One BLAS thread, so that a result does not depend on the host's core count (OpenBLAS's threaded kernels round
    # differently: they moved Radau's step sequence on Andrews' squeezer), and so that a worker, which has a core,
    # does not oversubscribe the cores and count its BLAS threads' waiting as the case's process time.
    with threadpool_limits(limits=1, user_api="blas"):
        result = run_case(case, progress)
    return result, time.perf_counter() - t0, code_version(case.engine)


class Progress:
    """One status line on stderr: done / remaining / failed (redrawn on a terminal, else every ~5 %)."""

    def __init__(self, total: int, title: str, stream=None):
        self.total, self.title = total, title
        self.done = self.failed = 0
        self.stream = stream or sys.stderr
        self.start = time.perf_counter()
        self._tty = getattr(self.stream, "isatty", lambda: False)()
        self._last_printed = -1

    def update(self, failed: bool = False) -> None:
        self.done += 1
        self.failed += int(failed)
        step = max(self.total // 20, 1)
        if self._tty or self.done == self.total or self.done // step != self._last_printed // step:
            self._last_printed = self.done
            self._draw()

    def _draw(self) -> None:
        width = 24
        filled = int(width * self.done / max(self.total, 1))
        line = (f"{self.title}: [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} done, "
                f"{self.total - self.done} remaining, {self.failed} failed, "
                f"{time.perf_counter() - self.start:.0f} s")
        end = "" if self._tty and self.done < self.total else "\n"
        print(("\r" if self._tty else "") + line, end=end, file=self.stream, flush=True)


@dataclass
class RunSummary:
    """What :func:`run_cases` did: counts, failed cases with their errors, wall time per case."""

    cached: int = 0
    computed: int = 0
    failed: dict[str, str] = field(default_factory=dict)
    expected: dict[str, str] = field(default_factory=dict)  # stopped with the error their case list expects
    rejected: dict[str, str] = field(default_factory=dict)  # saved results that failed their check
    wall_seconds: dict[str, float] = field(default_factory=dict)


def compiled(case: Case) -> bool:
    """Whether a case runs on the compiled path (study.fast)."""
    return case.engine == "inhouse" and case.kwargs.get("backend") == "compiled"


def warm_compiled(case: Case) -> None:
    """Compile the compiled path for ``case``'s mechanism in this worker, or load it from numba's disk cache.

    The compiled loop takes ~40 s to compile once; numba keeps it on disk, but two workers that start
    compiled cases at the same time both compile it. :func:`run_cases` therefore gives this short run
    to the first worker and the reference-path and Exudyn cases to the others first, so they find it
    on disk when their turn comes to a compiled case.
    """
    from study.simulate import simulate

    simulate(mechanism_of(case.mechanism, case.variant), t_end=1e-3, output_step=1e-3, backend="compiled",
             friction="none")


def _outcomes(executor: Executor, todo: list[Case], seconds: Mapping[str, float],
              announce: Announce | None) -> Iterator[tuple[Case, Future]]:
    """(case, finished future) pairs as they complete; pending ones are cancelled if the caller stops.

    The reference-path cases go first (a worker compiles the compiled path meanwhile), each group longest first
    by the wall ``seconds`` a case took when it last ran (cases not in it first of all): a long case submitted
    last would keep one worker busy after the others ran out of work."""
    if isinstance(executor, InlineExecutor):  # one at a time, in list order, so each is saved before the next starts
        for case in todo:
            yield case, executor.submit(_run_case_timed, *((case,) if announce is None else (case, announce(case))))
        return
    if announce is not None:
        raise ValueError("run_cases: announce (progress within a run) needs the cases run in this process "
                         "(InlineExecutor, workers = 1)")
    first = next((c for c in todo if compiled(c)), None)
    if first is not None:   # its errors, if any, are those of the compiled cases, reported with them
        executor.submit(warm_compiled, first)
    order = sorted(todo, key=lambda c: (compiled(c), -seconds.get(c.name, math.inf)))
    futures = {executor.submit(_run_case_timed, case): case for case in order}
    try:
        for future in as_completed(futures):
            yield futures[future], future
    finally:  # KeyboardInterrupt or an error while saving: do not leave work queued
        for future in futures:
            future.cancel()


def _expected_failure(store: Store, case: Case) -> str | None:
    """The recorded error of ``case`` if it is the one its case list expects (``expect_error``), else None."""
    failure = store.failure(case) if case.expect_error else None
    if failure is None or failure.get("key") != case.key():
        return None
    error = str(failure.get("error", ""))
    return error if error.split(":", 1)[0] == case.expect_error else None


def run_cases(cases: Iterable[Case], store: Store, executor: Executor, title: str = "cases",
              stream=None, seconds: Mapping[str, float] | None = None, announce: Announce | None = None) -> RunSummary:
    """Run every case without a saved result on ``executor``; save each as it completes.

    ``seconds``: the wall seconds each case (by name) took when it last ran, to start the longest first.
    ``announce``: called with each case just before it runs (an InlineExecutor's cases only: they run here, in
    list order); it returns the run's progress callback (the time reached) or None.

    Identical cases (same key) run once. A case that raises is recorded (``Store.record_failure``)
    and the others go on. A case whose case list expects it to stop with an error, and whose failure with that
    error is recorded under its key (the same code and inputs: the run is deterministic, its bounds are counts),
    is not run again: the record is its result. On KeyboardInterrupt the pending cases are cancelled; finished
    results stay saved, so a rerun resumes.
    """
    unique: dict[str, Case] = {}
    for case in cases:
        unique.setdefault(case.key(), case)
    summary = RunSummary()
    stream = stream or sys.stderr
    todo = []
    for c in unique.values():
        why = store.problem(c)
        if why is None:
            continue
        recorded = _expected_failure(store, c) if why == "not saved" else None
        if recorded is not None:
            summary.expected[c.name] = recorded
            continue
        if why != "not saved":  # a damaged result is reported and recomputed, never reused
            print(f"{c.name}: saved result rejected, recomputing: {why}", file=stream)
            summary.rejected[c.name] = why
            store.discard(c)
        todo.append(c)
    summary.cached = len(unique) - len(todo)
    if not todo:
        return summary
    progress = Progress(len(todo), f"{title} ({summary.cached} cached)", stream)
    for case, future in _outcomes(executor, todo, seconds or {}, announce):
        try:
            result, wall, worker_code = future.result()
            if worker_code != code_version(case.engine):  # e.g. a Dask worker with another installed copy
                raise RuntimeError(f"the worker runs code version {worker_code}, this process "
                                   f"{code_version(case.engine)}: its result would be saved under a wrong key")
            result.check_finite()  # a NaN anywhere is a failed run, never cached as a success
        except Exception as exc:  # noqa: BLE001 - recorded, the other cases go on
            error = f"{type(exc).__name__}: {exc}"
            store.record_failure(case, error, "".join(traceback.format_exception(exc)))
            expected = type(exc).__name__ == case.expect_error
            (summary.expected if expected else summary.failed)[case.name] = error
            progress.update(failed=not expected)
            continue
        if case.expect_error:  # saved (its summary shows it), but a case list's claim turned out false
            summary.failed[case.name] = f"expected to stop with {case.expect_error}, but the run finished"
        store.save(case, result)
        summary.computed += 1
        summary.wall_seconds[case.name] = wall
        progress.update()
    return summary
