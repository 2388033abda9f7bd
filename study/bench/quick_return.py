"""The quick-return over 20 s to max |dq| <= 1e-8 (benchmark part f; target 2).

For the smooth cutting law and for the seed's on/off law (switches located by the compiled loop):
DOP853 over rtol, each against a reference whose own error is estimated by a further run, with the
loop overhead of every run (part g's first measure).
"""

from __future__ import annotations

from dataclasses import replace

import pandas as pd

from study.bench.evaluations import eval_cost_us
from study.bench.harness import bench_store, execute, log, max_dq, repeat_of, timed
from study.bench.summary import summarize
from study.bench.settings import REF_RTOL, T2_REF_RTOL, T2_T_END, T2_VARIANTS, group, repeats


def quick_return_20s(quick: bool) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Compiled DOP853 over the rtol grid of ``"quick_return 20 s: DOP853"`` (decades) on the 20 s
    quick-return, smooth and on/off cutting laws, each against a reference independent of the runs it
    judges, with the loop overhead of every run.

    The reference is compiled RK45 (another integrator, other coefficients, other error estimator) at
    rtol :data:`T2_REF_RTOL` (``"...: reference"``); its error is bounded by its distance to compiled
    DOP853 at :data:`REF_RTOL` (``"...: reference check"``; the two share no step, so the distance
    bounds the error of either unless both err alike).

    Every candidate is timed :func:`~study.bench.settings.repeats` times (runs of ~0.1 s). The loop
    overhead is the run's CPU divided by (its evaluations × the cost of one evaluation,
    :func:`eval_cost_us`, timed in the same process right before the runs; a run saved by an earlier
    benchmark of the same code keeps its CPU: ``--remeasure`` times everything in one process).

    Returns
    -------
    runs : DataFrame
        Columns variant, t_end, integrator, rtol, atol, error, cpu_s, repeats, steps, events, nfev,
        eval_us, loop_overhead, reference, reference_rtol, reference_uncertainty.
    reference_rows : DataFrame
        The references' check rows (``references.csv``).
    """
    t_end = 2.0 if quick else T2_T_END
    n = repeats(quick)
    executed, eval_us = [], {}
    for variant in T2_VARIANTS:
        ref_case, = (replace(c, t_end=t_end) for c in group("quick_return 20 s: reference") if c.variant == variant)
        check, = (replace(c, t_end=t_end) for c in group("quick_return 20 s: reference check") if c.variant == variant)
        log(f"reference quick_return {variant} {t_end:g} s: RK45 rtol {T2_REF_RTOL:g} vs DOP853 rtol {REF_RTOL:g}: "
            f"max|dq| {max_dq(execute(check), execute(ref_case)):.2e}")
        executed += [ref_case, check]
        eval_us[variant] = eval_cost_us("quick_return", variant, {}, n, 2000 if quick else 20000)
        log(f"(f) quick_return {variant}: one evaluation {eval_us[variant]:.3f} us (compiled loop)")
        for case in (replace(c, t_end=t_end) for c in group("quick_return 20 s: DOP853") if c.variant == variant):
            timed(case, n)
            executed += [repeat_of(case, k) for k in range(n)]
    tables = summarize(executed, bench_store().load)
    runs = tables["quick_return_20s"]
    runs.insert(runs.columns.get_loc("nfev") + 1, "eval_us", runs.variant.map(eval_us))
    runs.insert(runs.columns.get_loc("eval_us") + 1, "loop_overhead", runs.cpu_s / (runs.nfev * runs.eval_us * 1e-6))
    for r in runs.itertuples():
        log(f"(f) quick_return {r.variant} {t_end:g} s DOP853 rtol {r.rtol:g}: max|dq| {r.error:.2e}, "
            f"median cpu {r.cpu_s:.4f} s, {r.steps} steps, {r.events} events, loop overhead {r.loop_overhead:.2f}")
    return runs, tables["references"]
