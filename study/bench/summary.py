"""The benchmark's summary: its timing tables from the saved runs of the cases it ran.

:func:`summarize` is the case list's summary (``reference/cases/bench.toml``, ``[study] summary``).
Given the cases the benchmark ran (each family's reference and reference checks, the runs it chose,
and their timing repeats, option ``repeat``) and the store's ``load``, it builds the tables those
cases make:

* ``work_precision`` (the sweeps, :mod:`study.bench.sweeps`: runs labelled with their ``stage``): one
  row per run, not per repeat: its setting, max|Δq| against its family's reference over the same
  horizon, the median CPU of the run and its repeats and their number, a failed run's error in ``note``;
* ``quick_return_20s`` (group ``"quick_return 20 s: DOP853"``): the same per run, without the
  evaluation cost and loop overhead (measured outside the runs, :mod:`study.bench.quick_return`);
* ``scaling_simulated_time`` (group ``"scaling: simulated time"``): median CPU per horizon and path;
* ``references``: each reference check against its reference.

A family is what precedes ``": "`` in a group's name (a mechanism, or ``"quick_return 20 s"``); its
reference is the group ``"<family>: reference"`` of the same variant and horizon. A pure function of
the saved results: the benchmark decides which runs to make, this computes the tables.
"""

from __future__ import annotations

from typing import Callable, Iterable

import numpy as np
import pandas as pd

from study.bench.harness import cpu_seconds, max_dq, setting
from study.bench.settings import EPS
from study.pipeline import Case, MissingResult
from study.results import SimulationResult

WORK_PRECISION_COLUMNS = ["mechanism", "variant", "friction", "engine", "method", "setting", "error", "cpu_s",
                          "repeats", "stage", "note", "nfev", "t_end", "reference", "reference_uncertainty"]
QUICK_RETURN_GROUP = "quick_return 20 s: DOP853"
SCALING_GROUP = "scaling: simulated time"


def _family(case: Case) -> str:
    return case.group.split(": ", 1)[0]


def _key(case: Case) -> tuple:
    """The reference a run is measured against: its family, variant and horizon."""
    return (_family(case), case.variant, case.t_end)


def _base(case: Case) -> tuple:
    """What identifies a run whatever its repeat: group, horizon and options without ``repeat``."""
    return (case.group, case.variant, case.t_end, tuple((k, v) for k, v in case.options if k != "repeat"))


def _integrator(case: Case) -> str:
    return f"{case.kwargs['integrator']} ({case.kwargs['backend']})"


def _reference(ref_case: Case, atol: bool) -> str:
    """The reference named in a table: 'compiled DOP853 rtol 5e-15[, atol 5e-17]'."""
    o = ref_case.kwargs
    return f"{o['backend']} {o['integrator']} rtol {o['rtol']:g}" + (f", atol {o['atol']:g}" if atol else "")


def _friction(reference: Case) -> str:
    options = reference.kwargs
    if not options.get("friction"):
        return ""
    return f"{options['friction']} friction, ε = {options.get('friction_eps', EPS):g} m/s"


def summarize(cases: Iterable[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    """The timing tables ``cases`` make, from their saved runs (see the module docstring).

    Raises
    ------
    LookupError
        A run whose family, variant and horizon have no reference among ``cases``.
    """
    cases = list(cases)
    references = {_key(c): c for c in cases if c.group == f"{_family(c)}: reference"}
    loaded = {key: load(c) for key, c in references.items()}

    def reference_of(c: Case) -> tuple[Case, SimulationResult]:
        if _key(c) not in references:
            raise LookupError(f"run {c.name} ({c.t_end:g} s): no reference '{_family(c)}: reference' of variant "
                              f"{c.variant} over {c.t_end:g} s among the cases")
        return references[_key(c)], loaded[_key(c)]

    ref_rows, uncertainty = [], {}
    for c in cases:
        if c.group != f"{_family(c)}: reference check":
            continue
        (ref_case, ref), check = reference_of(c), load(c)
        d = max_dq(check, ref)
        uncertainty[_key(c)] = max(d, uncertainty.get(_key(c), -np.inf))
        ref_rows.append({"mechanism": c.mechanism, "variant": c.variant, "t_end": c.t_end,
                         "integrator": _integrator(ref_case), "reference_rtol": ref_case.kwargs["rtol"],
                         "reference_atol": ref_case.kwargs["atol"], "check_rtol": c.kwargs["rtol"],
                         "check_atol": c.kwargs["atol"], "max_abs_dq_check_vs_reference": d,
                         "reference_steps": ref.stats["steps"], "check_steps": check.stats["steps"]})
    repeats: dict[tuple, dict[int, float]] = {}
    for c in cases:   # the repeats of each run (a repeat listed twice counts once)
        if "repeat" in c.kwargs:
            repeats.setdefault(_base(c), {})[c.kwargs["repeat"]] = cpu_seconds(c, load(c))

    def timing(c: Case, result: SimulationResult) -> tuple[float, int]:
        cpus = [cpu_seconds(c, result), *repeats.get(_base(c), {}).values()]
        return float(np.median(cpus)), len(cpus)

    runs = [c for c in cases if "repeat" not in c.kwargs]
    tables = {}
    swept = [c for c in runs if c.label("stage") is not None]
    if swept:
        tables["work_precision"] = pd.DataFrame([_sweep_row(c, *reference_of(c), uncertainty, load, timing)
                                                 for c in swept], columns=WORK_PRECISION_COLUMNS)
    rows = []
    for c in (c for c in runs if c.group == QUICK_RETURN_GROUP):
        (ref_case, ref), result = reference_of(c), load(c)
        cpu, n = timing(c, result)
        rows.append({"variant": c.variant, "t_end": c.t_end, "integrator": _integrator(c), "rtol": c.kwargs["rtol"],
                     "atol": c.kwargs["atol"], "error": max_dq(result, ref), "cpu_s": cpu, "repeats": n,
                     "steps": result.stats["steps"], "events": result.stats.get("events", 0),
                     "nfev": result.stats["nfev"], "reference": _reference(ref_case, atol=False),
                     "reference_rtol": ref_case.kwargs["rtol"], "reference_uncertainty": uncertainty.get(_key(c))})
    if rows:
        tables["quick_return_20s"] = pd.DataFrame(rows)
    rows = []
    for c in (c for c in runs if c.group == SCALING_GROUP):
        result = load(c)
        cpu, n = timing(c, result)
        rows.append({"backend": c.kwargs["backend"], "t_end": c.t_end, "cpu_s": cpu, "steps": result.stats["steps"],
                     "cpu_per_simulated_s": cpu / c.t_end, "repeats": n})
    if rows:
        tables["scaling_simulated_time"] = pd.DataFrame(rows)
    if ref_rows:
        tables["references"] = pd.DataFrame(ref_rows)
    return tables


def _sweep_row(c: Case, ref_case: Case, ref: SimulationResult, uncertainty: dict, load, timing) -> dict:
    """One row of ``work_precision``: a swept run against its mechanism's reference."""
    engine, method = c.group[len(_family(c)) + 2:].rsplit(", ", 1)
    row = {"mechanism": c.mechanism, "variant": c.variant, "friction": _friction(ref_case), "engine": engine,
           "method": method, "setting": setting(c), "stage": c.label("stage"), "t_end": c.t_end,
           "reference": _reference(ref_case, atol=True),
           "reference_uncertainty": uncertainty.get(_key(c), np.nan)}
    try:
        result = load(c)
    except MissingResult as exc:  # a failed setting is a row, not hidden
        row.update(error=np.nan, cpu_s=np.nan, repeats=0, note=str(exc)[:200], nfev=np.nan)
        return row
    cpu, n = timing(c, result)
    row.update(error=max_dq(result, ref), cpu_s=cpu, repeats=n, note="", nfev=result.stats.get("nfev", np.nan))
    return row
