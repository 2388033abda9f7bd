"""What the pipeline computes from saved results: each study's summary and its own checks (failures, backend agreement)."""

from __future__ import annotations

import importlib
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from study.pipeline.cases import CaseList, CaseListError
from study.pipeline.store import Store
from study.compare import common_samples
from study.reference_data import tolerance
from study.results import SimulationResult


def summary_function(case_list: CaseList):
    """The study's ``summarize`` function; CaseListError (naming the file and module) if it cannot be had.

    Called for every case list before any case runs, so a misspelt module costs no computation.
    """
    where = f"{case_list.path.name}: [study] summary = {case_list.summary!r}"
    try:
        module = importlib.import_module(case_list.summary)
    except ImportError as exc:
        raise CaseListError(f"{where} cannot be imported ({exc})") from None
    except Exception as exc:  # noqa: BLE001 - a module that fails on import is named, not a traceback
        raise CaseListError(f"{where} fails on import: {type(exc).__name__}: {exc}") from None
    func = getattr(module, "summarize", None)
    if not callable(func):
        raise CaseListError(f"{where} has no function summarize(cases, load)")
    return func


def summarize(case_list: CaseList, store: Store) -> dict[str, pd.DataFrame]:
    """Call the study's ``summarize(cases, load)`` on its saved results."""
    return summary_function(case_list)(list(case_list.cases), store.load)


def failures_table(case_lists: Iterable[CaseList], store: Store) -> pd.DataFrame:
    """Every case whose last attempt failed, with its error message."""
    rows = []
    for cl in case_lists:
        for case in cl.all_cases:
            failure = None if store.has(case) else store.failure(case)
            if failure is not None:
                rows.append({"study": cl.study, "case": case.name, "key": case.key(), "error": failure["error"],
                             "expected": bool(case.expect_error) and failure["error"].startswith(case.expect_error + ":")})
    return pd.DataFrame(rows, columns=["study", "case", "key", "error", "expected"])


def sample_agreement(compiled: SimulationResult, reference: SimulationResult, options: Mapping[str, Any]) -> dict:
    """How far a compiled run is from its reference-path twin on the twin's horizon, and the bound it must stay within.

    Adaptive methods: both paths take the same method at the same tolerances, so each is within the global
    error of the tolerance, adaptive_global_error_factor * rtol * max|q| (reference/tolerances.toml, with its
    reason), of the exact solution, and they are within twice that of each other. Fixed-step RK4: the same
    steps, only round-off differs, fast_fixed_step_agreement * max|q|. The twin runs over the horizon those
    reasons assume (study.pipeline.cases.sample_horizon); the compiled run is compared on its samples up to there.
    """
    scale = float(np.max(np.abs(reference.q)))
    if "rtol" in options:
        bound = 2 * tolerance("adaptive_global_error_factor") * float(options["rtol"]) * scale
        rule = "2 * adaptive_global_error_factor * rtol * max|q|"
    else:
        bound = tolerance("fast_fixed_step_agreement") * scale
        rule = "fast_fixed_step_agreement * max|q|"
    t_end = float(reference.t[-1])
    try:
        ia, ib = common_samples(compiled, reference, t_end)
    except ValueError:
        ia = ib = np.array([], dtype=int)
    if len(ib) != len(reference.t):   # every sample of the twin must have its compiled counterpart
        return {"max_abs_dq": np.nan, "sample_t_end": t_end, "bound": bound, "rule": rule, "agree": False}
    dq = float(np.max(np.abs(compiled.q[ia] - reference.q[ib])))
    return {"max_abs_dq": dq, "sample_t_end": t_end, "bound": bound, "rule": rule, "agree": bool(dq <= bound)}


def backend_agreement(case_lists: Iterable[CaseList], store: Store) -> pd.DataFrame:
    """Every sampled compiled case against its reference-path twin, on the twin's horizon (see sample_agreement)."""
    rows = []
    for cl in case_lists:
        for case, twin in cl.samples:
            row = {"study": cl.study, "case": case.name, "t_end": case.t_end}
            if store.has(case) and store.has(twin):
                row.update(sample_agreement(store.load(case), store.load(twin), case.kwargs))
            else:
                row.update(max_abs_dq=np.nan, sample_t_end=twin.t_end, bound=np.nan, rule="a run failed", agree=False)
            rows.append(row)
    return pd.DataFrame(rows, columns=["study", "case", "t_end", "sample_t_end", "max_abs_dq", "bound", "rule", "agree"])


def backend_cpu(case_lists: Iterable[CaseList], store: Store) -> pd.DataFrame:
    """CPU of every sampled compiled case and of its reference-path twin (machine-dependent: timing/).

    The twin runs a shorter horizon (study.pipeline.cases.sample_horizon); ``reference_cpu_scaled_s`` is its
    CPU scaled to the case's horizon (CPU is linear in simulated time, bench_linearity_deviation), and
    ``compiled_over_reference`` compares CPU per simulated second. ``steps``: who takes the compiled case's
    steps, the compiled loop ('compiled loop') or scipy on compiled evaluations ('scipy', study.fast.support.SCIPY_STEPS_ONLY).
    """
    from study.fast.support import SCIPY_STEPS_ONLY

    rows = []
    for cl in case_lists:
        for case, twin in cl.samples:
            if store.has(case) and store.has(twin):
                fast, ref = (float(store.load(c).stats["cpu_seconds"]) for c in (case, twin))
                scaled = ref * case.t_end / twin.t_end
                steps = "scipy" if case.kwargs.get("integrator") in SCIPY_STEPS_ONLY else "compiled loop"
                rows.append({"study": cl.study, "case": case.name, "steps": steps, "t_end": case.t_end,
                             "compiled_cpu_s": fast,
                             "reference_t_end": twin.t_end, "reference_cpu_s": ref, "reference_cpu_scaled_s": scaled,
                             "compiled_over_reference": fast / scaled if scaled > 0 else np.nan})
    return pd.DataFrame(rows, columns=["study", "case", "steps", "t_end", "compiled_cpu_s", "reference_t_end",
                                       "reference_cpu_s", "reference_cpu_scaled_s", "compiled_over_reference"])
