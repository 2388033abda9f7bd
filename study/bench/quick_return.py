"""The quick-return over 20 s to max |dq| <= 1e-8 (benchmark part f; issue 7, target 2).

For the smooth cutting law and for the seed's on/off law (switches located by the compiled loop):
DOP853 over rtol, each against a reference whose own error is estimated by a further run, with the
loop overhead of every run (part g's first measure).
"""

from __future__ import annotations

from dataclasses import replace

import pandas as pd

from study.bench.evaluations import eval_cost_us
from study.bench.harness import execute, log, max_dq, timed
from study.bench.settings import REF_RTOL, T2_REF_RTOL, T2_T_END, T2_VARIANTS, group, repeats


def independent_reference(variant: str, t_end: float) -> tuple[object, float, dict]:
    """A reference independent of the DOP853 runs it judges: compiled RK45 (another integrator, other
    coefficients, other error estimator) at rtol :data:`T2_REF_RTOL` (group ``"quick_return 20 s:
    reference"``); its error is bounded by its distance to compiled DOP853 at :data:`REF_RTOL` (``"...:
    reference check"``; the two share no step, so the distance bounds the error of either unless both
    err alike)."""
    ref_case, = (replace(c, t_end=t_end) for c in group("quick_return 20 s: reference") if c.variant == variant)
    check_case, = (replace(c, t_end=t_end) for c in group("quick_return 20 s: reference check") if c.variant == variant)
    ref, other = execute(ref_case), execute(check_case)
    unc = max_dq(other, ref)
    log(f"reference quick_return {variant} {t_end:g} s: RK45 rtol {T2_REF_RTOL:g} vs DOP853 rtol {REF_RTOL:g}: "
        f"max|dq| {unc:.2e}")
    return ref, unc, {"mechanism": "quick_return", "variant": variant, "t_end": t_end, "integrator": "RK45 (compiled)",
                      "reference_rtol": ref_case.kwargs["rtol"], "reference_atol": ref_case.kwargs["atol"],
                      "check_rtol": check_case.kwargs["rtol"], "check_atol": check_case.kwargs["atol"],
                      "max_abs_dq_check_vs_reference": unc, "reference_steps": ref.stats["steps"],
                      "check_steps": other.stats["steps"]}


def quick_return_20s(quick: bool) -> tuple[pd.DataFrame, list[dict]]:
    """Compiled DOP853 over the rtol grid of ``"quick_return 20 s: DOP853"`` (decades) on the 20 s
    quick-return, smooth and on/off cutting laws, each against :func:`independent_reference`, with the
    loop overhead of every run.

    Every candidate is timed :func:`~study.bench.settings.repeats` times (runs of ~0.1 s). The loop
    overhead is the run's CPU divided by (its evaluations × the cost of one evaluation,
    :func:`eval_cost_us`, timed in the same process right before the runs; a run saved by an earlier
    benchmark of the same code keeps its CPU: ``--remeasure`` times everything in one process).

    Returns
    -------
    runs : DataFrame
        Columns variant, t_end, integrator, rtol, atol, error, cpu_s, repeats, steps, events, nfev,
        eval_us, loop_overhead, reference, reference_rtol, reference_uncertainty.
    reference_rows : list of dict
    """
    t_end = 2.0 if quick else T2_T_END
    n = repeats(quick)
    rows, ref_rows = [], []
    for variant in T2_VARIANTS:
        ref, unc, rr = independent_reference(variant, t_end)
        ref_rows.append(rr)
        eval_us = eval_cost_us("quick_return", variant, {}, n, 2000 if quick else 20000)
        log(f"(f) quick_return {variant}: one evaluation {eval_us:.3f} us (compiled loop)")
        for case in (replace(c, t_end=t_end) for c in group("quick_return 20 s: DOP853") if c.variant == variant):
            rtol, atol = case.kwargs["rtol"], case.kwargs["atol"]
            cpu, r = timed(case, n)
            err = max_dq(r, ref)
            overhead = cpu / (r.stats["nfev"] * eval_us * 1e-6)
            rows.append({"variant": variant, "t_end": t_end, "integrator": "DOP853 (compiled)", "rtol": rtol,
                         "atol": atol, "error": err, "cpu_s": cpu, "repeats": n,
                         "steps": r.stats["steps"], "events": r.stats.get("events", 0), "nfev": r.stats["nfev"],
                         "eval_us": eval_us, "loop_overhead": overhead,
                         "reference": f"compiled RK45 rtol {T2_REF_RTOL:g}", "reference_rtol": T2_REF_RTOL,
                         "reference_uncertainty": unc})
            log(f"(f) quick_return {variant} {t_end:g} s DOP853 rtol {rtol:g}: max|dq| {err:.2e}, "
                f"median cpu {cpu:.4f} s, {r.stats['steps']} steps, {r.stats.get('events', 0)} events, "
                f"loop overhead {overhead:.2f}")
    return pd.DataFrame(rows), ref_rows
