"""Report section: convergence and work-precision of the in-house methods (study ``work_precision``).

Reads the tables ``work_precision``, ``work_precision_timing`` and ``work_precision_orders``
(written by :func:`study.studies.work_precision.summarize`) and, when the cross-validation study has
written them, ``exudyn_agreement`` and ``exudyn_agreement_timing`` for the Exudyn points, and
``backend_cpu_timing`` for the reference-path CPU of the sampled runs. Never a
run. Figures: error against function evaluations and against CPU seconds (log-log), and the RK4
convergence plot with its observed orders. Every number in the text is read from those tables.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from study.reference_data import tolerance
from study.report import figures
from study.report.context import ReportContext
from study.report.render import fmt_int, fmt_number, md_table
from study.studies.work_precision import rk4_order_verdict

STUDY = "work_precision"
MECH = "quick-return (variant seed: on/off cutting law, switches located; 5 s)"
METHOD_NAMES = {"none": "none", "baumgarte": "baumgarte", "sliding_mode": "sliding_mode/tanh",
                "projection": "projection"}
INTEGRATOR_STYLE = {"RK45": {"marker": "o", "ls": "-"}, "DOP853": {"marker": "s", "ls": "--"},
                    "RK4": {"marker": "^", "ls": ":"}}
EXUDYN_STYLE = {"index3": {"color": "tab:red", "marker": "D", "ls": "-"},
                "index2": {"color": "tab:cyan", "marker": "v", "ls": "--"}}
TARGETS = (1e-4, 1e-6, 1e-8)  # error levels [rad] at which the cheapest setting of each series is read


def _style(method: str, integrator: str) -> dict:
    base = figures.method_style(METHOD_NAMES.get(method, method))
    style = {"color": base["color"], "lw": 1.2, **INTEGRATOR_STYLE.get(integrator, {})}
    return style


def _series(table: pd.DataFrame, x: str, y: str = "max_abs_dq") -> list:
    out = []
    main = table[table["group"].isin(["adaptive", "rk4"])]
    for (method, integrator), runs in main.groupby(["method", "integrator"], sort=False):
        runs = runs.sort_values(x)
        out.append((f"{method}, {integrator}", runs[x], runs[y], _style(method, integrator)))
    return out


def _with_cpu(table: pd.DataFrame, timing: pd.DataFrame | None, columns=("cpu_seconds",)) -> pd.DataFrame:
    """``table`` with the ``columns`` of the timing table's row of each run (matched on the run's settings)."""
    if timing is None:
        return table.assign(**{c: np.nan for c in columns})
    keys = ["group", "method", "integrator", "rtol", "step", "t_end"]
    t = timing[timing["group"] != "reference"][keys + list(columns)].copy()
    left, right = table.copy(), t
    for frame in (left, right):
        frame["rtol"] = frame["rtol"].fillna(-1.0)
        frame["step"] = frame["step"].fillna(-1.0)
    merged = left.merge(right, on=keys, how="left")
    merged["rtol"] = merged["rtol"].replace(-1.0, np.nan)
    merged["step"] = merged["step"].replace(-1.0, np.nan)
    return merged


def _reference_path_series(ctx: ReportContext, table: pd.DataFrame, timing: pd.DataFrame | None) -> list:
    """The sampled runs' reference-path (Python) CPU against their error: hollow markers, one series per method.

    The sweeps run compiled; every sampled case also ran on the reference path (case list's
    ``reference_sample``) over a shorter horizon, and ``backend_cpu_timing`` holds both CPU times under the
    case's name, the reference path's scaled to the case's horizon.
    """
    cpu = ctx.table("backend_cpu_timing")
    if cpu is None or timing is None or "case" not in timing:
        return []
    named = _with_cpu(table[table["group"].isin(["adaptive", "rk4"])], timing, columns=("case",))  # the lines' runs
    sampled = named.merge(cpu[cpu["study"] == STUDY][["case", "reference_cpu_scaled_s"]], on="case")
    out = []
    for method, runs in sampled.groupby("method", sort=False):
        style = {"color": _style(method, "RK45")["color"], "marker": "o", "ls": "none", "mfc": "none", "ms": 7, "mew": 1.3}
        out.append((f"{method}, reference path (sampled runs, CPU scaled from its twin's horizon)",
                    runs["reference_cpu_scaled_s"], runs["max_abs_dq"], style))
    return out


def _exudyn_series(ctx: ReportContext) -> tuple[list, str]:
    agree, timing = ctx.table("exudyn_agreement"), ctx.table("exudyn_agreement_timing")
    if agree is None or timing is None or agree.empty:
        return [], ""
    keys = ["mechanism", "variant", "friction", "t_end", "engine", "solver", "h"]
    a, t = agree.copy(), timing.copy()
    for frame in (a, t):
        frame["h"] = frame["h"].fillna(-1.0)
    merged = a.merge(t[keys + ["cpu_seconds"]], on=keys, how="left")
    sel = merged[(merged["mechanism"] == "quick_return") & (merged["variant"] == "smooth_cutting")]
    if sel.empty:
        return [], ""
    series = []
    for solver, runs in sel[sel["engine"] == "exudyn"].groupby("solver", sort=True):
        runs = runs.sort_values("cpu_seconds")
        series.append((f"Exudyn {solver} (h = {fmt_number(runs['h'].max())} … {fmt_number(runs['h'].min())} s)", runs["cpu_seconds"],
                       runs["max_abs_dq"], EXUDYN_STYLE.get(solver, {"color": "tab:gray", "marker": "x"})))
    for _, r in sel[sel["engine"] != "exudyn"].iterrows():
        label = str(r["solver"]) if str(r["solver"]).startswith("in-house") else f"in-house {r['solver']}"
        series.append((label, [r["cpu_seconds"]], [r["max_abs_dq"]],
                       {"color": "tab:green", "marker": "*", "ms": 9, "ls": "none"}))
    return series, fmt_number(sel["t_end"].iloc[0])


def _work_precision_figure(ctx: ReportContext, table: pd.DataFrame, timing: pd.DataFrame | None) -> str:
    panels = [{"xlabel": "function evaluations (right-hand side) [-]", "ylabel": "max |q − q_ref| on common samples [rad]",
               "series": _series(table, "nfev"), "title": "error against evaluations", "legend_title": "method, integrator",
               "legend_loc": "below"},
              {"xlabel": "CPU time [s] (this machine)", "ylabel": "max |q − q_ref| on common samples [rad]",
               "series": _series(table, "cpu_seconds"),
               "title": "error against CPU time: lines compiled path,\nhollow markers reference (Python) path",
               "legend_title": "method, integrator", "legend_loc": "below"}]
    panels[1]["series"] += _reference_path_series(ctx, table, timing)
    exudyn, horizon = _exudyn_series(ctx)
    if exudyn:
        panels.append({"xlabel": "CPU time [s] (this machine)", "ylabel": "max |q − q_ref| [rad]", "series": exudyn,
                       "title": f"Exudyn against the in-house solver\n(cross-validation study, {horizon} s, its own reference)",
                       "legend_title": "engine, solver"})
    fig = figures.log_lines_figure(
        panels, f"{MECH}: work–precision of every stabilization method\n(none; Baumgarte d = 1, ω = 10; sliding mode "
                "tanh, Λ = K = 10; projection), RK45 and DOP853 over rtol 1e-6 … 1e-11, RK4 over h = 2e-3 … 2.5e-4 s;\n"
                "reference DOP853 rtol 1e-13 with projection", figsize=(5.6 * len(panels), 7.6))
    return ctx.figure(fig, "work_precision", "error against function evaluations and CPU time, every method and integrator")


def _order_figure(ctx: ReportContext, table: pd.DataFrame, orders: pd.DataFrame, band: float) -> str:
    colors = {"rk4_order_smooth": "tab:blue", "rk4_order_revolution": "tab:orange", "rk4": "tab:gray"}
    names = {"rk4_order_smooth": "first 0.08 s (smooth)", "rk4_order_revolution": "one revolution, 1 s",
             "rk4": "5 s"}
    err, order = [], []
    for group in ("rk4_order_smooth", "rk4_order_revolution", "rk4"):
        runs = table[(table["group"] == group) & (table["method"] == "none")].sort_values("step")
        if runs.empty:
            continue
        err.append((f"RK4, method none, {names[group]}", runs["step"], runs["max_abs_dq"], {"color": colors[group]}))
        h0, e0 = float(runs["step"].iloc[0]), float(runs["max_abs_dq"].iloc[0])
        hh = runs["step"].to_numpy(dtype=float)
        err.append((f"slope 4 through the finest point ({names[group]})", hh, e0 * (hh / h0) ** 4,
                    {"color": colors[group], "ls": ":", "lw": 0.8, "marker": None}))
        o = orders[(orders["group"] == group) & (orders["method"] == "none")]
        order.append((f"{names[group]}", o["h_fine"], o["observed_order"], {"color": colors[group]}))
    panels = [{"xlabel": "step h [s]", "ylabel": "max |q − q_ref| on common samples [rad]", "series": err,
               "title": "error against step", "legend_title": "series"},
              {"xlabel": "finer step of the pair h [s]", "ylabel": "observed order p [-]", "yscale": "linear",
               "series": order, "title": f"observed order (band 4 ± {band:g} dotted)", "legend_title": "series",
               "hlines": [(4.0, "order 4", {"color": "black", "ls": "-", "lw": 0.8}),
                          (4.0 - band, None, {}), (4.0 + band, None, {})]}]
    fig = figures.log_lines_figure(panels, "quick-return (variant seed, switches located), method none: convergence of "
                                   "fixed-step RK4 against the DOP853 rtol 1e-13 projection reference",
                                   figsize=(12.0, 4.8))
    return ctx.figure(fig, "work_precision_rk4_order", "RK4 error against h and observed order")


def _cheapest(table: pd.DataFrame) -> tuple[list[str], list[list[str]]]:
    header = ["method", "integrator"] + [f"evaluations for max|Δq| ≤ {t:g} rad" for t in TARGETS] + \
             ["error at rtol 1e-8 [rad]"]
    rows = []
    main = table[table["group"].isin(["adaptive", "rk4"])]
    for (method, integrator), runs in main.groupby(["method", "integrator"], sort=False):
        row = [method, integrator]
        for t in TARGETS:
            ok = runs[runs["max_abs_dq"] <= t]
            row.append(fmt_int(ok["nfev"].min()) if len(ok) else "not reached")
        at = runs[np.isclose(runs["rtol"].fillna(0), 1e-8, rtol=1e-6, atol=0)]
        row.append(fmt_number(at["max_abs_dq"].iloc[0]) if len(at) else "–")
        rows.append(row)
    return header, rows


def _reading(table: pd.DataFrame, orders: pd.DataFrame, band: float) -> list[str]:
    items = []
    adaptive = table[table["group"] == "adaptive"]
    non_monotone = []
    for (method, integrator), runs in adaptive.groupby(["method", "integrator"], sort=False):
        runs = runs.sort_values("rtol", ascending=False)
        e = runs["max_abs_dq"].to_numpy(dtype=float)
        r = runs["rtol"].to_numpy(dtype=float)
        non_monotone += [(method, integrator, r[k + 1]) for k in range(len(e) - 1) if e[k + 1] >= e[k]]
    tight = adaptive[np.isclose(adaptive["rtol"], adaptive["rtol"].min(), rtol=1e-6, atol=0)]
    if len(tight):
        best = tight.loc[tight["max_abs_dq"].idxmin()]
        worst = tight.loc[tight["max_abs_dq"].idxmax()]
        items.append(f"At rtol {fmt_number(tight['rtol'].iloc[0])} the error lies between {fmt_number(best['max_abs_dq'])} rad "
                     f"({best['method']}, {best['integrator']}) and {fmt_number(worst['max_abs_dq'])} rad ({worst['method']}, "
                     f"{worst['integrator']}); max|Φ| is {fmt_number(tight['max_abs_phi'].min())} … "
                     f"{fmt_number(tight['max_abs_phi'].max())} m.")
    if non_monotone:
        items.append(f"**The error does not always fall with rtol:** in {len(non_monotone)} of "
                     f"{len(adaptive) - adaptive.groupby(['method', 'integrator']).ngroups} tenfold tightenings it "
                     f"stays level or grows (e.g. " + "; ".join(f"{m}, {i} at rtol {fmt_number(r)}" for m, i, r in non_monotone[:4])
                     + "). These are the tightest settings, where the error approaches the reference's own "
                     "(see `tables/perturbation_check.csv` for how far each error moves when q(0), qd(0) move by 4 ulps).")
    by_method = adaptive[adaptive["integrator"] == "RK45"].pivot_table(index="rtol", columns="method", values="nfev")
    if "none" in by_method and len(by_method):
        extra = {m: float((by_method[m] / by_method["none"]).median()) for m in by_method.columns if m != "none"}
        items.append("Cost of stabilizing (RK45, median over rtol of evaluations relative to none): " +
                     ", ".join(f"{m} ×{fmt_number(v, 3)}" for m, v in extra.items()) +
                     ". Projection does not raise the evaluation count much; its cost is the projections' Newton "
                     "iterations, visible in CPU time.")
    rk4 = table[table["group"] == "rk4"]
    if len(rk4):
        fine = rk4[rk4["step"] == rk4["step"].min()]
        mid = rk4[rk4["step"] == sorted(rk4["step"].unique())[1]] if rk4["step"].nunique() > 1 else fine
        items.append(f"RK4 over 5 s: at h = {fmt_number(mid['step'].iloc[0])} s every method has the same error, "
                     f"{fmt_number(mid['max_abs_dq'].min())} … {fmt_number(mid['max_abs_dq'].max())} rad, and at h = "
                     f"{fmt_number(fine['step'].iloc[0])} s {fmt_number(fine['max_abs_dq'].min())} … {fmt_number(fine['max_abs_dq'].max())} rad: "
                     f"the integration error, not the stabilization, sets it; observed orders between these steps "
                     f"{fmt_number(orders[orders['group'] == 'rk4']['observed_order'].min())} … "
                     f"{fmt_number(orders[orders['group'] == 'rk4']['observed_order'].max())} (switches located, RK4 restarted at each).")
    for group, text in (("rk4_order_smooth", "before the first switch (first 0.08 s)"), ("rk4", "over 5 s with located switches"),
                        ("rk4_order_revolution", "over one crank revolution (1 s, every ramp)")):
        o = orders[orders["group"] == group].sort_values("h_fine", ascending=False)
        if o.empty:
            continue
        v = rk4_order_verdict(orders, group, band)
        items.append(f"**RK4 order {text}: {', '.join(fmt_number(p) for p in o['observed_order'])}** for h from "
                     f"{fmt_number(o['h_coarse'].max())} to {fmt_number(o['h_fine'].min())} s; the finest pair gives "
                     f"{fmt_number(v['observed_order'])}, which {'lies' if v['holds'] else 'does not lie'} within 4 ± {band:g} "
                     f"(`reference/tolerances.toml` [rk4_order_band]): "
                     + ("**order 4 confirmed**." if v["holds"] else "**order 4 not reached**."))
    return ["### Reading", ""] + [f"- {t}" for t in items] + [""]


def section(ctx: ReportContext) -> list[str]:
    lines = ["## Convergence and work–precision", ""]
    table = ctx.table("work_precision")
    orders = ctx.table("work_precision_orders")
    if table is None or orders is None:
        return lines + ["No saved table `tables/work_precision.csv`; run the pipeline first.", ""]
    timing = ctx.table("work_precision_timing")
    band = tolerance("rk4_order_band")
    table = _with_cpu(table, timing)
    lines += [f"Study `work_precision` ({len(ctx.cases(STUDY))} cases in `reference/cases/work_precision.toml`): the "
              f"{MECH} with every in-house stabilization method, adaptive RK45 and DOP853 over rtol 1e-6 … 1e-11 "
              "(atol = rtol/100) and fixed-step RK4 over h, each compared with a DOP853 rtol 1e-13 projection "
              "reference on the common 0.01 s samples (error = max over samples and coordinates of |q − q_ref|). "
              "**Why the on/off law:** the smooth law's tanh ramps (5 mm in x_D, 1 cm/s in v_D) are "
              "crossed in ~0.2 ms, far below an adaptive step, so whether a step lands on a ramp depends on last-bit "
              "differences: moving q(0), qd(0) by 4 ulps moved max|Δq| by 60–97 % (DOP853 rtol 1e-11, RK45 rtol 1e-6) "
              "and the rtol 1e-13 reference by 1.6e-8 rad, which is why these errors differed between machines. With "
              "the switches located, every step lies inside one smooth piece. The errors are still decided partly "
              "by accept/reject decisions at about 70 restarts in 5 s: on another host and under a 4-ulp move of "
              "q(0) some moved by up to a factor 4 (projection, DOP853, rtol 1e-10: 4.2e-9 and 1.1e-9 rad), so read "
              "them by their decade, as the figure does (`make verify` judges them to their decade; section \"How "
              "far the numbers reproduce\"). The sweeps run on the compiled path, so the lines of the CPU panel are the "
              "arithmetic cost of each method; every 5th run also ran on the reference path, whose CPU (hollow markers) "
              "is the cost of the same method evaluated in Python (so did every run of the short RK4 order series, "
              "not drawn there), and the "
              "two paths' trajectories are checked to agree (`tables/backend_agreement.csv`). CPU times are this "
              "machine's (`timing/work_precision_timing.csv`, `timing/backend_cpu_timing.csv`); function evaluations "
              "are deterministic.", ""]
    lines += [_work_precision_figure(ctx, table, timing), ""]
    header, rows = _cheapest(table)
    lines += ["Cheapest setting of each series that reaches a given error (function evaluations):", "",
              md_table(header, rows, [False, False] + [True] * (len(header) - 2)), ""]
    lines += [_order_figure(ctx, table, orders, band), ""]
    lines += _reading(table, orders, band)
    return lines
