"""Work-precision sweeps (benchmark part b): CPU time to reach each accuracy level, per engine and method.

Over 5 s of the quick-return ``smooth_cutting``, 20 s of the slider-crank ``sustained_sliding``
(regularized friction, eps = 1e-3 on both sides) and 5 s of the four-bar. In-house: rtol
(atol = rtol/100) or the RK4 step refined tenfold / by halves. Exudyn: the fixed step h halved from
0.01 s until one run costs more than :data:`~study.bench.settings.SWEEP_BUDGET`, then, for 1e-4 and 1e-6
when not yet reached, the step predicted by the error's order-2 decrease (h = h_f sqrt(MARGIN level /
err_f), rounded to 0.01 s / n) as long as the predicted run costs at most
:data:`~study.bench.settings.EXUDYN_RUN_BUDGET`. 1e-8 is not attempted for Exudyn (order 2 puts it at
~1e3 s a run); it is recorded as not reached with the finest step tried. Exudyn runs in two
configurations (:data:`~study.bench.settings.EXUDYN_ENGINES`): 'tuned' (swept as above) and 'Python user
functions' (run at the steps the tuned sweep chose: both solve the same discrete equations). Every
Exudyn run entering a ratio is timed at least :data:`~study.bench.settings.EXUDYN_REPEATS` times.

The candidates are the groups ``"<mechanism>: <engine>, <method>"`` of ``reference/cases/bench.toml``
(:func:`plans`), walked in list order; every run and timing repeat is a case run through the
pipeline's store (:mod:`study.bench.harness`), and :mod:`study.bench.summary` makes the tables.

References: compiled DOP853 at rtol :data:`~study.bench.settings.REF_RTOL` (atol = rtol/100), checked by
:data:`~study.bench.settings.REF_CHECK_RTOLS` runs (``references.csv``): tighter tolerances are not more
accurate, round-off sets a floor of ~1e-10 ... 1e-9 rad over 20 s (measured; see the CSV).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd

from study.bench.harness import at_setting, execute, log, max_dq, repeat_of, repeats_for, setting, timed, with_labels
from study.bench.settings import (CASE_LIST, CASES, EXUDYN_ENGINES, EXUDYN_LEVELS, EXUDYN_REPEATS, EXUDYN_RUN_BUDGET,
                                  LEVELS, MARGIN, OUTPUT_STEPS, REF_RTOL, SWEEP_BUDGET, group)
from study.pipeline import Case, MissingResult

PYTHON_EXUDYN = "Exudyn (Python user functions)"   # run at the tuned sweep's steps, not swept


def plans(mech: str) -> list[tuple[str, str, list[Case]]]:
    """The swept groups of a mechanism in list order: (engine, method, candidate cases).

    A group ``"<mech>: <engine>, <method>"`` of ``bench.toml``; Exudyn with Python user functions is
    not swept (see :func:`sweep`), the reference groups are not plans.
    """
    prefix, found = f"{mech}: ", {}
    for case in CASE_LIST.cases:
        if case.group.startswith(prefix) and ", " in case.group:
            found.setdefault(case.group, []).append(case)
    out = []
    for name, cases in found.items():
        engine, method = name[len(prefix):].rsplit(", ", 1)
        if engine != PYTHON_EXUDYN:
            out.append((engine, method, cases))
    return out


def order2_step(h: float, err: float, level: float, output_step: float, margin: float = MARGIN) -> float:
    """The fixed step predicted to reach ``margin * level`` from (h, err) if err ∝ h², as output_step / n.

    Parameters
    ----------
    h, err : float
        Finest step tried [s] and its error [rad].
    level : float
        Error to reach [rad].
    output_step : float
        Sampling step of the runs [s].

    Returns
    -------
    float
        ``output_step / n`` with the smallest whole n such that the step is at most the prediction
        (so output samples and the horizon stay whole multiples of it).
    """
    predicted = h * math.sqrt(margin * level / err)
    return output_step / math.ceil(output_step / predicted - 1e-9)


def _order2_steps(run_one, rows: list[dict], mech: str, engine: str, method: str, candidates: list[Case],
                  t_end: float, run_budget: float) -> None:
    """Exudyn's step refined by its order-2 error decrease towards each of EXUDYN_LEVELS not reached yet."""
    for level in EXUDYN_LEVELS:  # order-2 refinement of Exudyn's step towards the levels not reached
        for _ in range(3):
            done = [r for r in rows if r["engine"] == engine and r["method"] == method and np.isfinite(r["error"])]
            if not done or min(r["error"] for r in done) <= level:
                break
            finest = min(done, key=lambda r: r["setting"])
            h = order2_step(finest["setting"], finest["error"], level, OUTPUT_STEPS[mech])
            predicted = finest["cpu_s"] * finest["setting"] / h
            if predicted > run_budget:
                log(f"(b) {mech} {engine} {method}: {level:g} needs h ~ {h:.3g} s, predicted {predicted:.0f} s > "
                    f"budget {run_budget:g} s: not run")
                break
            log(f"(b) {mech} {engine} {method}: order-2 step for {level:g}: h = {h:.4g} s (predicted "
                f"{predicted:.1f} s)")
            case = at_setting(replace(candidates[0], t_end=t_end), h)
            err, _ = run_one(engine, method, case, f"order-2 step for {level:g}")
            if not np.isfinite(err):
                break  # the solver fails at this step: recorded, no retry


def _python_exudyn_runs(run_one, rows: list[dict], mech: str, t_end: float) -> None:
    """Exudyn with Python user functions at the steps the tuned sweep chose for each level (and the finest)."""
    # Exudyn with Python user functions solves the same discrete equations as the tuned configuration
    # (tests/test_exudyn_tuned.py: equal to ~1e-10 rad), so its error at a step is the tuned one's: it is run
    # at the steps the tuned sweep chose for each level (and the finest tried), not swept again.
    done = pd.DataFrame(rows)
    for method in ("index3", "index2"):
        tuned = done[(done.engine == "Exudyn tuned") & (done.method == method) & done.error.notna()]
        picks = {float(tuned.setting.min())} if len(tuned) else set()
        for level in EXUDYN_LEVELS:
            ok = tuned[tuned.error <= level]
            if len(ok):
                picks.add(float(ok.loc[ok.cpu_s.idxmin(), "setting"]))
        for h in sorted(picks, reverse=True):
            template = replace(group(f"{mech}: {PYTHON_EXUDYN}, {method}")[0], t_end=t_end)
            run_one(PYTHON_EXUDYN, method, at_setting(template, h), "steps of the tuned sweep")


def _median_timings(rows: list[dict], ran: list[Case], executed: list[Case], mech: str, quick: bool) -> None:
    """The cheapest setting reaching each level timed repeatedly (median); its repeats appended to ``executed``."""
    df = pd.DataFrame(rows)
    # medians for the cheapest setting reaching each level
    for level in LEVELS:
        for (engine, method), g in df.groupby(["engine", "method"]):
            ok = g[g.error <= level]
            if ok.empty:
                continue
            i = ok.cpu_s.idxmin()
            s = df.loc[i]
            want = repeats_for(s.cpu_s, quick)
            want = max(want, EXUDYN_REPEATS) if engine in EXUDYN_ENGINES else want
            if df.at[i, "repeats"] >= want:
                continue
            df.at[i, "cpu_s"] = timed(ran[i], want)[0]   # the run's first timing and want - 1 more
            df.at[i, "repeats"] = want
            executed += [repeat_of(ran[i], k) for k in range(1, want)]
            log(f"(b) {mech} {engine} {method} setting {s.setting:.4g}: median of {want}: {df.at[i, 'cpu_s']:.4f} s")


def sweep(mech: str, quick: bool) -> list[Case]:
    """Work-precision runs of every engine/method on one mechanism (see the module docstring).

    Returns
    -------
    list of Case
        Every case run, in order: the mechanism's reference and its checks, each swept run (label
        ``stage``) and its timing repeats; :func:`study.bench.summary.summarize` makes the tables.
    """
    t_end = min(1.0, CASES[mech][1]) if quick else CASES[mech][1]
    ref_case = replace(group(f"{mech}: reference")[0], t_end=t_end)
    checks = [replace(c, t_end=t_end) for c in group(f"{mech}: reference check")]
    ref = execute(ref_case)
    for c in checks:
        log(f"reference {mech} {ref_case.variant} {t_end:g} s: rtol {c.kwargs['rtol']:g} vs {REF_RTOL:g}: max|dq| "
            f"{max_dq(execute(c), ref):.2e}")
    executed = [ref_case, *checks]
    rows, ran = [], []   # what the sweep decides by: one row per run, and its case (same index)
    budget = 2.0 if quick else SWEEP_BUDGET
    run_budget = 4.0 if quick else EXUDYN_RUN_BUDGET

    def run_one(engine, method, case, stage):
        case = with_labels(case, stage=stage)
        ran.append(case)
        executed.append(case)
        value = setting(case)
        try:
            cpu, r = timed(case, 1)
        except MissingResult as exc:  # a failed setting is recorded (summary: a row with its error), not hidden
            log(f"(b) {mech} {engine} {method} {value:g}: failed: {exc}")
            rows.append({"engine": engine, "method": method, "setting": value, "error": np.nan, "cpu_s": np.nan,
                         "repeats": 0})
            return np.nan, np.nan
        err = max_dq(r, ref)
        rows.append({"engine": engine, "method": method, "setting": value, "error": err, "cpu_s": cpu, "repeats": 1})
        log(f"(b) {mech} {engine} {method} setting {value:.4g} ({stage}): max|dq| {err:.2e}, cpu {cpu:.4f} s")
        return err, cpu

    for engine, method, candidates in plans(mech):
        for case in candidates:
            err, cpu = run_one(engine, method, replace(case, t_end=t_end), "sweep")
            if err <= LEVELS[-1] * 0.5 or cpu > budget:
                break
        if engine not in EXUDYN_ENGINES:
            continue
        _order2_steps(run_one, rows, mech, engine, method, candidates, t_end, run_budget)
    _python_exudyn_runs(run_one, rows, mech, t_end)
    _median_timings(rows, ran, executed, mech, quick)
    return executed
