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

References: compiled DOP853 at rtol :data:`~study.bench.settings.REF_RTOL` (atol = rtol/100), checked by
:data:`~study.bench.settings.REF_CHECK_RTOLS` runs (``references.csv``): tighter tolerances are not more
accurate, round-off sets a floor of ~1e-10 ... 1e-9 rad over 20 s (measured; see the CSV).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from study.bench.harness import inhouse_timer, log, max_dq, repeats_for, timer
from study.bench.settings import (CASES, EPS, EXUDYN_ENGINES, EXUDYN_LEVELS, EXUDYN_REPEATS, EXUDYN_RUN_BUDGET, LEVELS,
                                  MARGIN, OUTPUT_STEP, REF_CHECK_RTOLS, REF_RTOL, SWEEP_BUDGET)


def reference_with_check(mech: str, variant: str, t_end: float, extra: dict) -> tuple[object, float, list[dict]]:
    """The reference run (compiled DOP853 at :data:`REF_RTOL`) and its estimated error.

    Returns
    -------
    ref : SimulationResult
    uncertainty : float
        Largest max|Δq| between the reference and the runs at :data:`REF_CHECK_RTOLS` [rad].
    rows : list of dict
        One row per check run for ``references.csv``.
    """
    ref = inhouse_timer(mech, variant, t_end, extra, "compiled", "DOP853", REF_RTOL)()[1]
    rows = []
    for rtol in REF_CHECK_RTOLS:
        check = inhouse_timer(mech, variant, t_end, extra, "compiled", "DOP853", rtol)()[1]
        d = max_dq(check, ref)
        rows.append({"mechanism": mech, "variant": variant, "t_end": t_end, "integrator": "DOP853 (compiled)",
                     "reference_rtol": REF_RTOL, "reference_atol": REF_RTOL * 1e-2, "check_rtol": rtol,
                     "check_atol": rtol * 1e-2, "max_abs_dq_check_vs_reference": d,
                     "reference_steps": ref.stats["steps"], "check_steps": check.stats["steps"]})
        log(f"reference {mech} {variant} {t_end:g} s: rtol {rtol:g} vs {REF_RTOL:g}: max|dq| {d:.2e}")
    return ref, max(r["max_abs_dq_check_vs_reference"] for r in rows), rows


def order2_step(h: float, err: float, level: float, margin: float = MARGIN) -> float:
    """The fixed step predicted to reach ``margin * level`` from (h, err) if err ∝ h², as 0.01 s / n.

    Parameters
    ----------
    h, err : float
        Finest step tried [s] and its error [rad].
    level : float
        Error to reach [rad].

    Returns
    -------
    float
        ``OUTPUT_STEP / n`` with the smallest whole n such that the step is at most the prediction
        (so output samples and the horizon stay whole multiples of it).
    """
    predicted = h * math.sqrt(margin * level / err)
    return OUTPUT_STEP / math.ceil(OUTPUT_STEP / predicted - 1e-9)


def sweep(mech: str, quick: bool) -> tuple[pd.DataFrame, list[dict]]:
    """Work-precision runs of every engine/method on one mechanism (see the module docstring).

    Returns
    -------
    runs : DataFrame
        One row per run (setting, error, CPU, repeats, stage, note).
    reference_rows : list of dict
        The reference's check runs (``references.csv``).
    """
    variant, t_end, extra = CASES[mech]
    if quick:
        t_end = 1.0
    ref, ref_unc, ref_rows = reference_with_check(mech, variant, t_end, extra)
    rows = []
    rk_tols = [10.0 ** -k for k in range(4, 13)]
    plans = [("in-house compiled", "DOP853", rk_tols), ("in-house compiled", "RK45", rk_tols),
             ("in-house compiled", "RK4", [OUTPUT_STEP / 2 ** k for k in range(0, 9)]),
             ("in-house reference", "DOP853", [10.0 ** -k for k in range(4, 11, 2)]),
             ("Exudyn tuned", "index3", [OUTPUT_STEP / 2 ** k for k in range(0, 12)]),
             ("Exudyn tuned", "index2", [OUTPUT_STEP / 2 ** k for k in range(0, 12)])]
    budget = 2.0 if quick else SWEEP_BUDGET
    friction = (f"{extra['friction']} friction, ε = {extra.get('friction_eps', EPS):g} m/s" if extra.get("friction")
                else "")
    run_budget = 4.0 if quick else EXUDYN_RUN_BUDGET

    def run_one(engine, method, setting, stage):
        try:
            cpu, r = timer(mech, variant, t_end, extra, engine, method, setting)()
        except Exception as exc:  # a failed setting is recorded, not hidden
            log(f"(b) {mech} {engine} {method} {setting:g}: failed: {exc}")
            rows.append({"mechanism": mech, "variant": variant, "friction": friction, "engine": engine, "method": method,
                         "setting": setting, "error": np.nan, "cpu_s": np.nan, "repeats": 0, "stage": stage,
                         "note": str(exc)[:200]})
            return np.nan, np.nan
        err = max_dq(r, ref)
        rows.append({"mechanism": mech, "variant": variant, "friction": friction, "engine": engine, "method": method,
                     "setting": setting, "error": err, "cpu_s": cpu, "repeats": 1, "stage": stage, "note": "",
                     "nfev": r.stats.get("nfev", np.nan)})
        log(f"(b) {mech} {engine} {method} setting {setting:.4g} ({stage}): max|dq| {err:.2e}, cpu {cpu:.4f} s")
        return err, cpu

    for engine, method, settings in plans:
        for setting in settings:
            err, cpu = run_one(engine, method, setting, "sweep")
            if err <= LEVELS[-1] * 0.5 or cpu > budget:
                break
        if engine not in EXUDYN_ENGINES:
            continue
        for level in EXUDYN_LEVELS:  # order-2 refinement of Exudyn's step towards the levels not reached
            for _ in range(3):
                done = [r for r in rows if r["engine"] == engine and r["method"] == method and np.isfinite(r["error"])]
                if not done or min(r["error"] for r in done) <= level:
                    break
                finest = min(done, key=lambda r: r["setting"])
                h = order2_step(finest["setting"], finest["error"], level)
                predicted = finest["cpu_s"] * finest["setting"] / h
                if predicted > run_budget:
                    log(f"(b) {mech} {engine} {method}: {level:g} needs h ~ {h:.3g} s, predicted {predicted:.0f} s > "
                        f"budget {run_budget:g} s: not run")
                    break
                log(f"(b) {mech} {engine} {method}: order-2 step for {level:g}: h = {h:.4g} s (predicted "
                    f"{predicted:.1f} s)")
                err, _ = run_one(engine, method, h, f"order-2 step for {level:g}")
                if not np.isfinite(err):
                    break  # the solver fails at this step: recorded, no retry
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
            run_one("Exudyn (Python user functions)", method, h, "steps of the tuned sweep")
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
            fn = timer(mech, variant, t_end, extra, engine, method, s.setting)
            more = [fn()[0] for _ in range(want - int(s.repeats))]
            df.at[i, "cpu_s"] = float(np.median([s.cpu_s] + more))
            df.at[i, "repeats"] = want
            log(f"(b) {mech} {engine} {method} setting {s.setting:.4g}: median of {want}: {df.at[i, 'cpu_s']:.4f} s")
    df["t_end"] = t_end
    df["reference"] = f"compiled DOP853 rtol {REF_RTOL:g}, atol {REF_RTOL * 1e-2:g}"
    df["reference_uncertainty"] = ref_unc
    return df, ref_rows
