"""The benchmark's summary: its work-precision tables from the saved runs of the cases it ran.

:func:`summarize` is the case list's summary (``reference/cases/bench.toml``, ``[study] summary``):
given the cases the sweeps ran (:func:`study.bench.sweeps.sweep`: each mechanism's reference and
reference checks, every swept run labelled with its ``stage``, and the timing repeats, option
``repeat``) and the store's ``load``, it builds

* ``work_precision``: one row per run (not per repeat): its setting, max|Δq| against the mechanism's
  reference over the same horizon, the median CPU of the run and its repeats and their number, and
  for a failed run the error in ``note``;
* ``references``: each reference check run against its reference (the sweeps' part of ``references.csv``).

A pure function of the saved results: the sweeps decide which runs to make, this computes the tables.
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


def _base(case: Case) -> tuple:
    """What identifies a run whatever its repeat: group, horizon and options without ``repeat``."""
    return (case.group, case.variant, case.t_end, tuple((k, v) for k, v in case.options if k != "repeat"))


def _friction(reference: Case) -> str:
    options = reference.kwargs
    if not options.get("friction"):
        return ""
    return f"{options['friction']} friction, ε = {options.get('friction_eps', EPS):g} m/s"


def summarize(cases: Iterable[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    """The sweeps' tables from the saved runs of ``cases`` (see the module docstring).

    Raises
    ------
    LookupError
        A swept run whose mechanism and horizon have no reference among ``cases``.
    """
    cases = list(cases)
    references = {(c.mechanism, c.t_end): c for c in cases if c.group == f"{c.mechanism}: reference"}
    loaded = {(m, t): load(c) for (m, t), c in references.items()}
    ref_rows, uncertainty = [], {}
    for c in cases:
        if c.group != f"{c.mechanism}: reference check":
            continue
        ref_case, check = references[(c.mechanism, c.t_end)], load(c)
        ref = loaded[(c.mechanism, c.t_end)]
        d = max_dq(check, ref)
        uncertainty[(c.mechanism, c.t_end)] = max(d, uncertainty.get((c.mechanism, c.t_end), -np.inf))
        ref_rows.append({"mechanism": c.mechanism, "variant": c.variant, "t_end": c.t_end,
                         "integrator": "DOP853 (compiled)", "reference_rtol": ref_case.kwargs["rtol"],
                         "reference_atol": ref_case.kwargs["atol"], "check_rtol": c.kwargs["rtol"],
                         "check_atol": c.kwargs["atol"], "max_abs_dq_check_vs_reference": d,
                         "reference_steps": ref.stats["steps"], "check_steps": check.stats["steps"]})
    timings: dict[tuple, dict[int, float]] = {}
    for c in cases:   # the repeats of each run (a repeat listed twice counts once)
        if "repeat" in c.kwargs:
            timings.setdefault(_base(c), {})[c.kwargs["repeat"]] = cpu_seconds(c, load(c))
    rows = []
    for c in cases:
        if "stage" not in dict(c.labels) or "repeat" in c.kwargs:
            continue
        key = (c.mechanism, c.t_end)
        if key not in references:
            raise LookupError(f"run {c.name} ({c.t_end:g} s): no reference of {c.mechanism} over {c.t_end:g} s "
                              f"among the cases")
        ref_case = references[key]
        engine, method = c.group[len(c.mechanism) + 2:].rsplit(", ", 1)
        row = {"mechanism": c.mechanism, "variant": c.variant, "friction": _friction(ref_case), "engine": engine,
               "method": method, "setting": setting(c), "stage": c.label("stage"), "t_end": c.t_end,
               "reference": f"compiled DOP853 rtol {ref_case.kwargs['rtol']:g}, atol {ref_case.kwargs['atol']:g}",
               "reference_uncertainty": uncertainty.get(key, np.nan)}
        try:
            result = load(c)
        except MissingResult as exc:  # a failed setting is a row, not hidden
            row.update(error=np.nan, cpu_s=np.nan, repeats=0, note=str(exc)[:200], nfev=np.nan)
        else:
            cpus = [cpu_seconds(c, result), *timings.get(_base(c), {}).values()]
            row.update(error=max_dq(result, loaded[key]), cpu_s=float(np.median(cpus)), repeats=len(cpus), note="",
                       nfev=result.stats.get("nfev", np.nan))
        rows.append(row)
    return {"work_precision": pd.DataFrame(rows, columns=WORK_PRECISION_COLUMNS),
            "references": pd.DataFrame(ref_rows)}
