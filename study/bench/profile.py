"""Where the compiled loop's time goes (benchmark part g): start-up, evaluations, switches, the loop itself."""

from __future__ import annotations

import numpy as np
import pandas as pd

from study.bench.harness import inhouse_case, log, timed
from study.bench.settings import CASES, OUTPUT_STEPS, RATIO_LEVEL, T2_LEVEL


def overhead_profile(qr20: pd.DataFrame, wp: pd.DataFrame, accel: pd.DataFrame, repeats: int,
                     mechanisms=None) -> pd.DataFrame:
    """Split the CPU of each run behind a loop-overhead row of ``mechanisms`` (default: all) into its parts
    (numba code has no profiler hooks, so the parts are measured, not sampled).

    * ``startup_s``: the same run stopped after one output step (setup of the loop state, initial
      mode, the first Python -> compiled call, first step-size selection);
    * ``evaluations_s``: evaluations × the cost of one inside the compiled loop (the model's work);
    * ``events_s``: located switches × one Python -> compiled call (after a switch the loop returns
      to Python, which flips the mode and calls the compiled loop again);
    * ``loop_s``: the rest, the integrator's own work per step (stage combinations, error norm, step
      control, dense output at the samples, switch detection), also given per step.
    """
    loop = accel[accel.path == "compiled, in compiled loop"].set_index("mechanism")
    call = accel[accel.path == "compiled, one call from Python"].set_index("mechanism")
    mechanisms = list(mechanisms or CASES)
    runs = []
    for variant, g in (qr20.groupby("variant", sort=False) if "quick_return" in mechanisms else ()):
        ok = g[g.error + g.reference_uncertainty <= T2_LEVEL]
        b = ok.loc[ok.cpu_s.idxmin()] if not ok.empty else g.loc[g.error.idxmin()]
        runs.append(("quick_return", variant, float(b.t_end), {}, float(b.rtol), float(b.eval_us)))
    for mech, g in wp[(wp.engine == "in-house compiled") & (wp.method == "DOP853")].groupby("mechanism", sort=False):
        ok = g[g.error <= RATIO_LEVEL]
        if mech in mechanisms and mech != "quick_return" and not ok.empty and mech in loop.index:
            b = ok.loc[ok.cpu_s.idxmin()]
            runs.append((mech, b.variant, float(b.t_end), CASES[mech][2], float(b.setting),
                         float(loop.loc[mech, "us_per_evaluation"])))
    rows = []
    for mech, variant, t_end, extra, rtol, eval_us in runs:
        cpu, r = timed(inhouse_case(mech, variant, t_end, extra, "compiled", "DOP853", rtol, "profile"), repeats)
        start, _ = timed(inhouse_case(mech, variant, OUTPUT_STEPS[mech], extra, "compiled", "DOP853", rtol, "profile"),
                         repeats)   # stopped after one output step: the start-up
        call_us = float(call.loc[mech, "us_per_evaluation"]) if mech in call.index else np.nan
        nfev = int(r.stats["nfev"])
        ev = int(r.stats.get("events", 0))
        evals = nfev * eval_us * 1e-6
        events = ev * call_us * 1e-6 if ev else 0.0
        rest = cpu - start - evals - events
        rows.append({"mechanism": mech, "variant": variant, "t_end": t_end, "rtol": rtol, "cpu_s": cpu,
                     "repeats": repeats, "steps": int(r.stats["steps"]), "nfev": nfev, "events": ev,
                     "startup_s": start, "evaluations_s": evals, "events_s": events, "loop_s": rest,
                     "loop_us_per_step": rest / max(int(r.stats["steps"]), 1) * 1e6,
                     "overhead": cpu / evals})
        log(f"(g) {mech} {variant} rtol {rtol:g}: cpu {cpu:.4f} s = start-up {start:.4f} + evaluations {evals:.4f} "
            f"+ switches {events:.4f} + loop {rest:.4f} ({rows[-1]['loop_us_per_step']:.2f} us/step)")
    return pd.DataFrame(rows)
