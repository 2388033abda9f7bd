"""Report section: the compiled path against the reference path on the studies' sampled cases.

The sweeps of several studies run on the compiled path (``backend = "compiled"`` in their case
lists); every n-th of their cases (``reference_sample = n``) also runs on the reference path. The
pipeline writes how far each pair's trajectories are apart and the bound they must stay within
(``tables/backend_agreement.csv``, :func:`study.pipeline.sample_agreement`) and both CPU times
(``timing/backend_cpu_timing.csv``). This section reads those two tables; a pair that does not agree
is listed with its numbers, never left to the table alone.
"""

from __future__ import annotations

import numpy as np

from study.report.context import ReportContext
from study.report.render import fmt_number, md_table


def section(ctx: ReportContext) -> list[str]:
    lines = ["## The compiled and the reference path", ""]
    agree = ctx.table("backend_agreement")
    if agree is None or agree.empty:
        return lines + ["No saved table `tables/backend_agreement.csv`: no study samples a compiled sweep, or the "
                        "pipeline has not run.", ""]
    ok = agree["agree"].astype(str) == "True"
    per_study = ", ".join(f"{study} {int(ok[g.index].sum())} of {len(g)}" for study, g in agree.groupby("study", sort=True))
    lines += [f"The sweeps marked `backend = \"compiled\"` in the case lists run on the compiled path (numba code "
              f"generated from the same equations); every n-th of their cases also ran on the reference path. "
              f"**{int(ok.sum())} of {len(agree)} sampled pairs agree** within their bound ({per_study}), compared "
              "on the reference-path run's horizon: the case's own, cut to `backend_sample_horizon` (an adaptive "
              "run) or to `backend_sample_steps` steps (a fixed-step run), the horizons the bounds' reasons assume "
              "(`reference/tolerances.toml`). The bound of an adaptive pair is 2 × `adaptive_global_error_factor` × "
              "rtol × max|q|: each run is expected to stay within the global error of its tolerance of the exact "
              "solution; a fixed-step pair takes the same steps, so only round-off may differ "
              "(`fast_fixed_step_agreement`).", ""]
    bad = agree[~ok]
    if len(bad):
        rows = [[r["study"], r["case"], fmt_number(r["max_abs_dq"]), fmt_number(r["bound"]),
                 fmt_number(r["max_abs_dq"] / r["bound"]) if np.isfinite(r["bound"]) and r["bound"] > 0 else "–",
                 r["rule"]] for _, r in bad.iterrows()]
        lines += ["**Pairs that do not agree** (max|Δq| between the two paths over the compared horizon):", "",
                  md_table(["study", "case", "max|Δq| [rad]", "bound [rad]", "ratio", "rule"], rows,
                           [False, False, True, True, True, False]), "",
                  "Both paths take the same method at the same tolerances, but the compiled loop is not step-for-step "
                  "scipy's: its step-size control can choose other steps, so each path has its own global error. A "
                  "pair above its bound means at least one run's error exceeds what the rule expects of that "
                  "tolerance; it is a finding about the rule on that problem, and the studies' tables use the compiled "
                  "run.", ""]
    cpu = ctx.table("backend_cpu_timing")
    if cpu is not None and len(cpu):
        parts = [f"{fmt_number(r.min())} … {fmt_number(r.max())} (median {fmt_number(r.median())}) over the {len(r)} "
                 f"pairs {where}" for steps, where in (("compiled loop", "in the compiled loop"),
                                                       ("scipy", "where scipy takes the steps (Radau, LSODA)"))
                 if len(r := cpu.loc[cpu["steps"] == steps, "compiled_over_reference"])]
        lines += ["CPU on this machine (`timing/backend_cpu_timing.csv`): the compiled run takes "
                  + "; ".join(parts) + " of the reference path's CPU per simulated second.", ""]
    return lines
