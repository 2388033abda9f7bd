"""Report section: the energy balance of every run with friction (``tables/energy_balance.csv``).

The pipeline checks every saved friction run of every study (:func:`study.pipeline.summaries.energy_check`): the
residual (kinetic + potential change) - (work of the drives and loads) + (friction dissipation) against a bound
from the run's tolerances, and that the dissipation never drops. This section counts the runs, names every run the
check flags with its numbers (``make reproduce`` and ``make verify`` then fail), and says which runs are recorded
without a bound and why. It reads that one table.
"""

from __future__ import annotations

import numpy as np

from study.pipeline.summaries import energy_flags
from study.report.context import ReportContext
from study.report.render import fmt_number, md_table


def section(ctx: ReportContext) -> list[str]:
    lines = ["## Energy balance of every run with friction", ""]
    table = ctx.table("energy_balance")
    if table is None:
        return lines + ["No saved table `tables/energy_balance.csv`: the pipeline has not run.", ""]
    if table.empty:
        return lines + ["No study has a run with friction.", ""]
    judged = table[table["residual_within_bound"].astype(str) != "not judged"]
    ratio = (judged["residual_J"] / judged["residual_bound_J"]).to_numpy(dtype=float)
    worst = judged.iloc[int(np.nanargmax(ratio))] if len(judged) else None
    lines += [f"For each of the **{len(table)} saved runs with friction** (`tables/energy_balance.csv`) the pipeline "
              "computes the energy-balance residual, max over t of |(T + V)(t) − (T + V)(0) − W_loads(t) + D(t)|, "
              "with D(t) ≥ 0 the energy the friction took out (minus its work), and D itself. An adaptive in-house "
              "run must keep the residual within energy_drift_factor × (rtol × S + atol × (1 + Λ)) (S: the largest "
              "term of the balance [J]; Λ: the largest constraint multiplier; `reference/tolerances.toml`), and D "
              "may drop by no more than that between two samples; a fixed-step run (RK4, Exudyn) has no tolerance "
              "to derive a bound from, so its residual is recorded only, and its D, a sum of nonpositive powers "
              "with positive weights, may drop by round-off only. Runs started off their constraints (the papers' "
              "printed states) are recorded, not judged: bringing them onto the constraints changes the energy by "
              "construction.", ""]
    if worst is not None:
        share = worst["residual_J"] / worst["residual_bound_J"]
        lines += [f"{len(judged)} runs are judged; the largest residual relative to its bound is "
                  f"{fmt_number(worst['residual_J'])} J of {fmt_number(worst['residual_bound_J'])} J "
                  f"({fmt_number(share, 2)} of the bound, `{worst['case']}`).", ""]
    flags = energy_flags(table)
    if flags:
        rows = [[name, why] for name, why in flags.items()]
        lines += [f"**{len(flags)} runs fail the check** (`make reproduce` and `make verify` exit non-zero):", "",
                  md_table(["case", "what fails"], rows), ""]
    else:
        lines += ["**No run fails the check.**", ""]
    counts = table.groupby("judged", sort=True).size()
    lines += ["Runs by how they are judged: " + "; ".join(f"{n} × {how}" for how, n in counts.items()) + ".", ""]
    return lines
