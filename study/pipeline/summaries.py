"""What the pipeline computes from saved results: each study's summary and its own checks (failures, backend agreement,
the energy balance of every friction run)."""

from __future__ import annotations

import importlib
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from study.pipeline.cases import CaseList, CaseListError
from study.pipeline.store import Store
from study.compare import common_samples
from study.integrity import read_json
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


# --- the energy balance of every run with friction ---------------------------------------------------
FRICTION_TREATMENTS = ("exact", "regularized", "sign")   # a result's meta['friction'] when friction was applied
ENERGY_COLUMNS = ["study", "case", "engine", "friction", "integrator", "rtol", "atol", "step", "t_end",
                  "energy_scale_J", "force_scale", "residual_J", "residual_bound_J", "dissipated_J",
                  "largest_dissipation_decrease_J", "dissipation_bound_J", "judged", "residual_within_bound",
                  "dissipation_nondecreasing", "flagged"]


def dissipation(result: SimulationResult) -> np.ndarray:
    """D(t) = -(sum of the ``work_friction_*`` series minus their initial values): the energy friction took out [J]."""
    works = [np.asarray(v, dtype=float) - v[0] for k, v in result.energies.items() if k.startswith("work_friction_")]
    return 0.0 - np.sum(works, axis=0) if works else np.zeros(len(result.t))   # 0.0 - x, not -x: D(0) = +0.0


def energy_check(result: SimulationResult, options: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The energy balance of one friction run, its dissipation, and whether each is within its bound.

    residual(t) = (K + V)(t) - (K + V)(0) - (work of the drives and loads) + (friction dissipation) is
    :meth:`SimulationResult.energy_balance` minus its initial value (every ``work_*`` series, friction included); the
    dissipation is D(t) (:func:`dissipation`). ``residual_J`` = max |residual|,
    ``dissipated_J`` = D(t_end), ``largest_dissipation_decrease_J`` = the largest drop of D between two samples (0 if
    it never drops).

    Bounds, from the run's tolerances: an adaptive in-house run (meta ``rtol``) must keep the residual within
    energy_drift_factor * (rtol * S + atol * (1 + Lambda)) (reference/tolerances.toml, reason there): S is the
    largest |term| of the balance (K, V - V(0), each work), the energy the relative tolerance acts on; atol is the
    absolute tolerance of every state, the work integrals (J) and the coordinates, whose error moves the energy by
    the generalized forces, of the size of the largest multiplier Lambda (N or N m). Its dissipation may drop by
    no more than that bound (a step's weights or the dense output between steps can be negative). A fixed-step
    run (in-house RK4, Exudyn) has no tolerance: its residual is recorded, not judged, and its dissipation is a sum
    of nonpositive powers with positive weights, so it may drop by round-off only, round_off * S. The residual of a
    run started off its constraints (``options['initial'] == 'printed'``) is recorded, not judged: the projection
    or the stabilization that brings it onto them changes the energy by construction; its dissipation is judged.
    """
    options = {} if options is None else dict(options)
    e = result.energies
    balance = result.energy_balance()
    residual = float(np.max(np.abs(balance - balance[0]))) if balance.size else 0.0
    dissipated = dissipation(result)
    terms = [np.asarray(e.get("kinetic", np.zeros(1)), dtype=float)]
    if "potential" in e:
        terms.append(np.asarray(e["potential"], dtype=float) - e["potential"][0])
    terms += [np.asarray(v, dtype=float) - v[0] for k, v in e.items() if k.startswith("work_")]
    scale = max(float(np.max(np.abs(x))) for x in terms)
    forces = float(np.max(np.abs(result.lam))) if result.lam.size else 0.0
    drop = float(max(0.0, -np.min(np.diff(dissipated)))) if len(dissipated) > 1 else 0.0
    rtol, atol = result.meta.get("rtol"), result.meta.get("atol")
    adaptive = result.meta.get("engine") == "in-house" and rtol is not None
    rule = "energy_drift_factor * (rtol * S + atol * (1 + Lambda))"
    if adaptive:
        bound = tolerance("energy_drift_factor") * (float(rtol) * scale + float(atol) * (1.0 + forces))
        judged, drop_bound = rule, bound
    else:
        judged, bound = "residual not judged: fixed step, no tolerance; dissipation to round_off * S", float("nan")
        drop_bound = tolerance("round_off") * scale
    if options.get("initial") == "printed":
        judged = (f"residual not judged: started off its constraints (printed state); dissipation to "
                  f"{rule if adaptive else 'round_off * S'}")
        bound = float("nan")
    within = "not judged" if np.isnan(bound) else str(bool(residual <= bound))
    nondecreasing = bool(drop <= drop_bound)
    step = result.meta.get("step", result.meta.get("h"))
    return {"engine": result.meta.get("engine"), "friction": result.meta.get("friction"),
            "integrator": result.meta.get("integrator", result.meta.get("method")),
            "rtol": np.nan if rtol is None else float(rtol), "atol": np.nan if atol is None else float(atol),
            "step": np.nan if step is None else float(step), "t_end": float(result.t[-1]),
            "energy_scale_J": scale, "force_scale": forces, "residual_J": residual, "residual_bound_J": bound,
            "dissipated_J": float(dissipated[-1]) if len(dissipated) else 0.0,
            "largest_dissipation_decrease_J": drop, "dissipation_bound_J": drop_bound, "judged": judged,
            "residual_within_bound": within, "dissipation_nondecreasing": nondecreasing,
            "flagged": within == "False" or not nondecreasing}


def energy_balance(case_lists: Iterable[CaseList], store: Store) -> pd.DataFrame:
    """:func:`energy_check` of every saved friction run of the case lists (their reference-path twins included)."""
    rows, seen = [], set()
    for cl in case_lists:
        for case in cl.all_cases:
            if case.key() in seen or not store.has(case):
                continue
            seen.add(case.key())
            if read_json(store.file(case, ".json"))["meta"].get("friction") not in FRICTION_TREATMENTS:
                continue   # the sidecar (checked by store.has) tells; the series are read for friction runs only
            rows.append({"study": cl.study, "case": case.name, **energy_check(store.load(case), case.kwargs)})
    return pd.DataFrame(rows, columns=ENERGY_COLUMNS)


def energy_flags(table: pd.DataFrame) -> dict[str, str]:
    """The flagged runs of an energy-balance table: case name -> what is wrong, with its numbers."""
    out = {}
    for _, r in table[table["flagged"].astype(str) == "True"].iterrows():
        why = []
        if str(r["residual_within_bound"]) == "False":
            why.append(f"energy-balance residual {r['residual_J']:.3g} J above its bound {r['residual_bound_J']:.3g} J "
                       f"({r['judged']})")
        if str(r["dissipation_nondecreasing"]) != "True":
            why.append(f"friction dissipation drops by {r['largest_dissipation_decrease_J']:.3g} J between two samples "
                       f"(allowed {r['dissipation_bound_J']:.3g} J): the friction did positive work")
        out[str(r["case"])] = "; ".join(why)
    return out
