"""Time to the first result of each path, from a fresh process, with a cold and a warm cache.

One measurement is one child process that produces one short result of one mechanism (:data:`MECHANISMS`: the
planar quick-return mechanism and two spatial ones, the heavy top and the spatial slider-crank): the command line's
``simulate <mechanism> --t-end 1`` on the reference path or the compiled path, or one Exudyn run of the same
mechanism (``study.run`` with ``study.Exudyn(h=1e-3)``). Cold: the child's cache folder (``STUDY_CACHE_DIR``) is empty, so it generates and compiles everything
it needs (sympy derivation, numba kernels); warm: a second child on the same folder. The numbers are the child's
wall time seen from here and its CPU time (user + system, from its resource usage): on a shared machine the wall
time varies with the load, the CPU time much less. Each is repeated (``repeats``, a fresh cold folder each time)
and every repeat is a row, so the spread shows. These are benchmark numbers, never a test's bound.

A host's speed is read from its pace, the µs of one compiled quick-return evaluation that ``make reproduce`` prints
(:func:`study.bench.evaluations.pace_us`): every row carries the pace of the host it was measured on and its CPU
seconds scaled to a host of pace 1 µs (``cpu_s / pace_us``), so that numbers from hosts of different speed compare
(a host 1.5 times slower per evaluation is taken as 1.5 times slower to start).
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

from study.bench.harness import log

T_END = 1.0   # [s] simulated: the run itself takes a few milliseconds; the rest is start-up and compilation
#: the mechanisms measured: a planar one, a spatial one of one body and one of three bodies and four joint kinds
MECHANISMS = ("quick_return", "heavy_top", "spatial_slider_crank")


def commands(out: Path, t_end: float = T_END, mechanism: str = "quick_return") -> dict[str, list[str]]:
    """The child process of each path (arguments after the interpreter), ``t_end`` [s] simulated."""
    cli = ["-m", "study", "simulate", mechanism, "--t-end", str(t_end), "--out", str(out)]
    exudyn = f"import study; study.run({mechanism!r}, study.Exudyn(h=1e-3), {t_end})"
    return {"reference": [*cli, "--backend", "reference"], "compiled": [*cli, "--backend", "compiled"],
            "exudyn": ["-c", exudyn]}


def child(argv: list[str], cache: Path) -> tuple[float, float]:
    """(wall [s], CPU [s]) of ``python argv`` with ``cache`` as its cache folder (numba's too)."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "STUDY_TRACEBACK")}
    env["STUDY_CACHE_DIR"] = str(cache)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, *argv], env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def compile_time(repeats: int = 2, paths: tuple[str, ...] = ("reference", "compiled", "exudyn"),
                 pace: float | None = None, t_end: float = T_END,
                 mechanisms: tuple[str, ...] = MECHANISMS) -> pd.DataFrame:
    """One row per mechanism, path, cache state (cold, warm) and repeat: the first result's wall and CPU seconds, this host's
    pace [µs per evaluation] (``pace``, else measured here by :func:`study.bench.evaluations.pace_us`) and the CPU
    scaled to a pace of 1 µs."""
    if pace is None:
        from study.bench.evaluations import pace_us

        pace = pace_us()
    rows = []
    for repeat in range(repeats):
        for mechanism in mechanisms:
            with tempfile.TemporaryDirectory(prefix="study_compile_time_") as tmp:
                for path in paths:
                    argv = commands(Path(tmp) / f"{path}_result", t_end, mechanism)[path]
                    cache = Path(tmp) / f"{path}_cache"
                    for state in ("cold", "warm"):
                        wall, cpu = child(argv, cache)
                        rows.append({"path": path, "cache": state, "mechanism": mechanism, "repeat": repeat,
                                     "first_call_wall_s": wall, "cpu_s": cpu, "pace_us": pace,
                                     "cpu_s_at_pace_1us": cpu / pace})
                        log(f"compile: {mechanism}, {path} path, {state} cache, repeat {repeat}: {wall:.1f} s wall, "
                            f"{cpu:.1f} s CPU ({cpu / pace:.1f} s at a pace of 1 µs; this host's: {pace:.3g} µs)")
    return pd.DataFrame(rows)
