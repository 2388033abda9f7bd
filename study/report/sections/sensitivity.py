"""Report section: sensitivity of the stabilization to its gains (study ``sensitivity``).

Reads the tables ``sensitivity``, ``sensitivity_horizon`` and ``sensitivity_timing`` (written by
:func:`study.studies.sensitivity.summarize`); never a run. Figures: Baumgarte (d, omega) heatmaps,
sliding-mode (Lambda, K) heatmaps for each sgn approximation, and the switching gain k and boundary
width sweeps. Every number in the text is read from those tables.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from study.report import figures
from study.report.context import ReportContext
from study.report.render import fmt_int, fmt_number, md_table
from study.studies import sliding_mode as sm_study  # 001's claimed levels and the 'about' rule

STUDY = "sensitivity"
SMOOTH_SGN = ("tanh", "sat", "arctan", "sqrt")
SGN_STYLE = {"tanh": {"color": "tab:purple"}, "sat": {"color": "tab:orange", "ls": "--"},
             "arctan": {"color": "tab:brown", "ls": "-."}, "sqrt": {"color": "tab:pink", "ls": ":"}}
MECH = "quick-return (variant seed, on/off cutting law, {t_end:g} s)"  # horizon from the case list


def _grid(frame: pd.DataFrame, rows: str, cols: str, value: str, counts: bool = False):
    """(row values, col values, grid, annotations) of ``value`` over two gain columns."""
    r_vals = sorted(frame[rows].dropna().unique())
    c_vals = sorted(frame[cols].dropna().unique())
    grid = np.full((len(r_vals), len(c_vals)), np.nan)
    text = [["not run"] * len(c_vals) for _ in r_vals]
    for _, row in frame.iterrows():
        i, j = r_vals.index(row[rows]), c_vals.index(row[cols])
        if row.get("status", "ok") != "ok":
            text[i][j] = "failed"
            continue
        grid[i, j] = float(row[value])
        text[i][j] = fmt_int(row[value]) if counts else fmt_number(row[value], 2)
    return [f"{v:g}" for v in r_vals], [f"{v:g}" for v in c_vals], grid, text


def _baumgarte_figure(ctx: ReportContext, bg: pd.DataFrame, mech: str) -> str:
    panels = []
    for value, what, counts in (("max_abs_phi", r"max $|\Phi|$ [m]", False),
                                ("max_abs_phidot", r"max $|\dot\Phi|$ [m/s]", False),
                                ("max_abs_dq_vs_reference", r"max $|q - q_{ref}|$ [rad]", False),
                                ("nfev", "function evaluations [-]", True)):
        rows, cols, grid, text = _grid(bg, "d", "omega", value, counts)
        panels.append({"title": what, "rows": rows, "cols": cols, "row_label": "damping ratio d [-]",
                       "col_label": "ω [1/s]", "values": grid, "text": text, "colorbar_label": f"{what} (log scale)"})
    fig = figures.grid_heatmaps_figure(
        panels, f"{mech}, method baumgarte (RK45 rtol 1e-8):\nconstraint violation, deviation from the reference "
                "and cost over (d, ω)", "log scale", shared_scale=False, ncols=2)
    return ctx.figure(fig, "sensitivity_baumgarte_heatmaps", "Baumgarte: max|Φ|, max|Φ̇|, max|Δq| and nfev over (d, ω)")


def _sliding_mode_figure(ctx: ReportContext, sm: pd.DataFrame, sign: pd.DataFrame, value: str, what: str,
                         counts: bool, mech: str) -> str:
    panels = []
    for sgn in SMOOTH_SGN:
        rows, cols, grid, text = _grid(sm[sm["sgn"] == sgn], "Lambda", "K", value, counts)
        panels.append({"title": f"sgn ≈ {sgn} (RK45 rtol 1e-8)", "rows": rows, "cols": cols,
                       "row_label": "Λ [1/s]", "col_label": "K [1/s]", "values": grid, "text": text})
    if len(sign):
        rows, cols, grid, text = _grid(sign, "Lambda", "K", value, counts)
        panels.append({"title": "exact sign (RK4 h = 1e-3 s)", "rows": rows, "cols": cols, "row_label": "Λ [1/s]",
                       "col_label": "K [1/s]", "values": grid, "text": text})
    fig = figures.grid_heatmaps_figure(
        panels, f"{mech}, method sliding_mode (k = 1e-6, width 1e-8):\n{what} over (Λ, K) for each sgn approximation",
        f"{what} (log scale)", ncols=3)
    stem = f"sensitivity_sliding_mode_{value}"
    return ctx.figure(fig, stem, f"sliding mode: {value} over (Λ, K), every sgn approximation")


def _sweep_figure(ctx: ReportContext, frame: pd.DataFrame, x: str, xlabel: str, group: str, fixed: str,
                  mech: str) -> str:
    sel = frame[frame["group"] == group]
    panels = []
    for value, ylabel in (("max_abs_phi", r"max $|\Phi|$ [m]"), ("max_abs_phidot", r"max $|\dot\Phi|$ [m/s]"),
                          ("nfev", "function evaluations [-]")):
        series = [(f"sgn ≈ {sgn}", s[x], s[value], SGN_STYLE[sgn])
                  for sgn in SMOOTH_SGN for s in [sel[sel["sgn"] == sgn].sort_values(x)] if len(s)]
        panels.append({"xlabel": xlabel, "ylabel": ylabel, "series": series, "legend_title": "approximation"})
    fig = figures.log_lines_figure(panels, f"{mech}, method sliding_mode (RK45 rtol 1e-8, {fixed}): effect of {xlabel}")
    return ctx.figure(fig, f"sensitivity_{group}", f"sliding mode: max|Φ|, max|Φ̇| and nfev against {x}")


def _groups(table: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """The finished runs of each group of the grid (``ok`` for all of them)."""
    ok = table[table["status"] == "ok"]
    return {"ok": ok, **{g: ok[ok["group"] == g] for g in ("none", "baumgarte", "sliding_mode_gains",
                                                             "sliding_mode_sign", "sliding_mode_k",
                                                             "sliding_mode_width")}}


def _failures_item(table: pd.DataFrame) -> str:
    """The runs that failed, or that none did."""
    failed = table[table["status"] != "ok"]
    if len(failed):
        return f"**{len(failed)} runs failed**: " + "; ".join(
            f"{r['group']} ({r['sgn']} d={fmt_number(r['d'])} ω={fmt_number(r['omega'])} Λ={fmt_number(r['Lambda'])} K={fmt_number(r['K'])} "
            f"k={fmt_number(r['k'])} width={fmt_number(r['width'])})" for _, r in failed.iterrows()) + "."
    return f"All {len(table)} runs finished; no setting in these grids makes the method fail outright."


def _none_items(none: pd.DataFrame, t_end: float) -> list[str]:
    """The drift without stabilization."""
    if not len(none):
        return []
    n = none.iloc[0]
    return [f"Without stabilization max|Φ| = {fmt_number(n['max_abs_phi'])} m over the {fmt_number(t_end)} s (max|Δq| = "
            f"{fmt_number(n['max_abs_dq_vs_reference'])} rad, {fmt_int(n['nfev'])} evaluations)."]


def _baumgarte_items(bg: pd.DataFrame) -> list[str]:
    """Baumgarte's level over (d, ω) against 001's levels, and its cost."""
    if not len(bg):
        return []
    d1 = bg[bg["d"] == bg["d"].max()].sort_values("omega")
    lo, hi = d1.iloc[0], d1.iloc[-1]
    spread = bg.groupby("omega")["max_abs_phi"].agg(lambda s: s.max() / s.min())
    reach = bg[bg["max_abs_phi"] <= sm_study.CLAIMED_LEVEL["sliding_mode"]]
    level = sm_study.CLAIMED_LEVEL["baumgarte"]
    near = bg[(bg["max_abs_phi"] >= level / sm_study.DECADE) & (bg["max_abs_phi"] <= level * sm_study.DECADE)]
    return [
        f"**Baumgarte: ω sets the level, d matters much less.** At d = {fmt_number(lo['d'])} max|Φ| falls from "
        f"{fmt_number(lo['max_abs_phi'])} m (ω = {fmt_number(lo['omega'])} 1/s) to {fmt_number(hi['max_abs_phi'])} m (ω = {fmt_number(hi['omega'])} 1/s), "
        f"a factor {fmt_number(lo['max_abs_phi'] / hi['max_abs_phi'])}; at a given ω the {bg['d'].nunique()} damping ratios "
        f"differ by at most a factor {fmt_number(spread.max(), 2)} (at ω = {fmt_number(spread.idxmax())} 1/s). 001's Baumgarte level, ~1e-6 m (within a decade), holds only for "
        f"ω ≤ {fmt_number(near['omega'].max()) if len(near) else '–'} 1/s; {len(reach)} of {len(bg)} cells even reach "
        f"001's sliding-mode level of 1e-8 m (all at ω ≥ {fmt_number(reach['omega'].min()) if len(reach) else '–'} 1/s).",
        f"**Stiffness:** the cost rises with ω, from {fmt_int(lo['nfev'])} evaluations (ω = {fmt_number(lo['omega'])}) to "
        f"{fmt_int(hi['nfev'])} (ω = {fmt_number(hi['omega'])}), ×{fmt_number(hi['nfev'] / lo['nfev'], 2)}, as the explicit RK45 "
        f"step becomes limited by stability (2dω and ω² enter the constraint dynamics) rather than accuracy."]


def _sliding_mode_items(sm: pd.DataFrame) -> list[str]:
    """The sliding mode's level over (Λ, K) and the four sgn approximations."""
    if not len(sm):
        return []
    by_gain = sm.groupby(["Lambda", "K"])["max_abs_phi"].agg(lambda s: s.max() / s.min())
    low = sm[(sm["Lambda"] == sm["Lambda"].min()) & (sm["K"] == sm["K"].min())]
    high = sm[(sm["Lambda"] == sm["Lambda"].max()) & (sm["K"] == sm["K"].max())]
    reach = sm[sm["max_abs_phi"] <= sm_study.CLAIMED_LEVEL["sliding_mode"]]
    reach_gain = reach[["Lambda", "K"]].max(axis=1).min() if len(reach) else np.nan
    return [
        f"**Sliding mode: Λ and K set the level, the sgn approximation does not.** At any (Λ, K) the four smooth "
        f"approximations give max|Φ| within {fmt_number(100 * (by_gain.max() - 1), 2)} % of each other; max|Φ| goes "
        f"from {fmt_number(low['max_abs_phi'].min())}–{fmt_number(low['max_abs_phi'].max())} m (Λ = K = {fmt_number(sm['Lambda'].min())} 1/s) to "
        f"{fmt_number(high['max_abs_phi'].min())}–{fmt_number(high['max_abs_phi'].max())} m (Λ = K = {fmt_number(sm['Lambda'].max())} 1/s), "
        f"and the cost from {fmt_int(low['nfev'].min())} to {fmt_int(high['nfev'].max())} evaluations. max|Φ| ≤ 1e-8 m "
        f"(001's sliding-mode level) takes max(Λ, K) ≥ {fmt_number(reach_gain)} 1/s: {len(reach)} of {len(sm)} cells."]


def _equal_gains_items(bg: pd.DataFrame, sm: pd.DataFrame) -> list[str]:
    """Sliding mode with Λ = K = ω against Baumgarte with d = 1 at the same ω."""
    if not (len(sm) and len(bg)):
        return []
    pairs = []
    for w in sorted(set(bg["omega"]) & set(sm["Lambda"])):
        b = bg[(bg["d"] == 1.0) & (bg["omega"] == w)]
        s = sm[(sm["Lambda"] == w) & (sm["K"] == w)]
        if len(b) and len(s):
            pairs.append((w, float(b["max_abs_phi"].iloc[0]), s["max_abs_phi"].min(), s["max_abs_phi"].max()))
    if not pairs:
        return []
    ratio = [x / b for _, b, lo_, hi_ in pairs for x in (lo_, hi_)]
    return [
        "**At equal gains the two methods coincide.** With Λ = K = ω the sliding surface gives "
        "Φ̈ = −(Λ + K)Φ̇ − ΛKΦ − k sgn(s), which is Baumgarte with d = 1 plus the switching term: max|Φ| of "
        "the sliding-mode runs over Baumgarte's (d = 1) lies between " f"{fmt_number(min(ratio))} and {fmt_number(max(ratio))} "
        f"at ω = {', '.join(fmt_number(p[0]) for p in pairs)} 1/s."]


def _switching_items(k_sweep: pd.DataFrame, w_sweep: pd.DataFrame) -> list[str]:
    """The sweeps of the switching gain k and of the boundary width."""
    items = []
    if len(k_sweep):
        lo, hi = k_sweep[k_sweep["k"] == k_sweep["k"].min()], k_sweep[k_sweep["k"] == k_sweep["k"].max()]
        items.append(
            f"**The switching gain k adds cost, not accuracy.** From k = {fmt_number(k_sweep['k'].min())} to "
            f"{fmt_number(k_sweep['k'].max())} (width {fmt_number(k_sweep['width'].iloc[0])}) max|Φ| stays between "
            f"{fmt_number(k_sweep['max_abs_phi'].min())} and {fmt_number(k_sweep['max_abs_phi'].max())} m, while the evaluations rise "
            f"from {fmt_int(lo['nfev'].max())} to {fmt_int(hi['nfev'].min())}–{fmt_int(hi['nfev'].max())}: inside the boundary layer "
            f"the sgn term is a linear gain k/width (up to {fmt_number(k_sweep['k'].max() / k_sweep['width'].iloc[0])} 1/s), "
            f"which makes the ODE stiff; max|Φ̇| grows from {fmt_number(lo['max_abs_phidot'].max())} to "
            f"{fmt_number(hi['max_abs_phidot'].max())} m/s.")
    if len(w_sweep):
        items.append(
            f"**The boundary width barely matters at k = {fmt_number(w_sweep['k'].iloc[0])}:** over width "
            f"{fmt_number(w_sweep['width'].min())} … {fmt_number(w_sweep['width'].max())} max|Φ| stays within "
            f"{fmt_number(w_sweep['max_abs_phi'].min())}–{fmt_number(w_sweep['max_abs_phi'].max())} m and the evaluations within "
            f"{fmt_int(w_sweep['nfev'].min())}–{fmt_int(w_sweep['nfev'].max())}.")
    return items


def _sign_items(sign: pd.DataFrame, sm: pd.DataFrame) -> list[str]:
    """The exact sign at a fixed step: its chattering against the smooth approximations."""
    if not len(sign):
        return []
    best = sign.loc[sign["max_abs_phi"].idxmin()]
    worst = sign.loc[sign["max_abs_phi"].idxmax()]
    chatter = sign.loc[sign["max_abs_phidot"].idxmax()]
    smooth_phidot = sm["max_abs_phidot"].max() if len(sm) else np.nan
    return [
        f"**The exact sign with RK4 (h = 1e-3 s) chatters.** max|Φ| ranges from {fmt_number(best['max_abs_phi'])} m "
        f"(Λ = {fmt_number(best['Lambda'])}, K = {fmt_number(best['K'])}) to {fmt_number(worst['max_abs_phi'])} m (Λ = {fmt_number(worst['Lambda'])}, "
        f"K = {fmt_number(worst['K'])}); max|Φ̇| reaches {fmt_number(chatter['max_abs_phidot'])} m/s (Λ = {fmt_number(chatter['Lambda'])}, "
        f"K = {fmt_number(chatter['K'])}, max|Φ| = {fmt_number(chatter['max_abs_phi'])} m) against at most "
        f"{fmt_number(smooth_phidot)} m/s for the smooth approximations, and max|Δq| is "
        f"{fmt_number(sign['max_abs_dq_vs_reference'].min())}–{fmt_number(sign['max_abs_dq_vs_reference'].max())} rad (fixed step, "
        f"{fmt_int(sign['nfev'].iloc[0])} evaluations)."]


def _accuracy_items(ok: pd.DataFrame, none: pd.DataFrame) -> list[str]:
    """The deviation of q from the reference over every smooth run."""
    smooth = ok[ok["group"].isin(["baumgarte", "sliding_mode_gains", "sliding_mode_k", "sliding_mode_width"])]
    if not (len(smooth) and len(none)):
        return []
    return [
        f"**Accuracy of q is mostly the integrator's:** over every smooth run max|Δq| against the reference lies "
        f"between {fmt_number(smooth['max_abs_dq_vs_reference'].min())} and {fmt_number(smooth['max_abs_dq_vs_reference'].max())} "
        f"rad (none: {fmt_number(none.iloc[0]['max_abs_dq_vs_reference'])} rad) and varies irregularly over the grids, "
        f"unlike max|Φ|: at RK45 rtol 1e-8 the integration error of q dominates once |Φ| is small."]


def _horizon_lines(horizon: pd.DataFrame | None) -> list[str]:
    """Why the grids' horizon is long enough (group ``horizon_check``), or nothing without that table."""
    if horizon is None or not len(horizon):
        return []
    short, full = fmt_number(horizon["short_horizon"].iloc[0]), fmt_number(horizon["t_end"].max())
    lines = [f"Why {short} s is long enough (group `horizon_check`, {full} s runs): max|Φ| over the first "
             f"{short} s and over the whole run.", "",
             md_table(["setting", f"max|Φ| 0–{short} s [m]", "max|Φ| whole run [m]", "run [s]", "ratio"],
                      [[r["setting"], fmt_number(r["max_abs_phi_short"]), fmt_number(r["max_abs_phi_full"]), fmt_number(r["t_end"]),
                        fmt_number(r["ratio_full_to_short"])] for _, r in horizon.iterrows()],
                      [False, True, True, True, True]), ""]
    stab = horizon[horizon["setting"] != "none"]
    if len(stab):
        lines += [f"With the weakest stabilizing gains the {full} s maximum is at most "
                  f"{fmt_number(stab['ratio_full_to_short'].max())} times the {short} s one; without stabilization it grows "
                  f"{fmt_number(horizon[horizon['setting'] == 'none']['ratio_full_to_short'].max())} times. The grids' "
                  f"stabilized levels are therefore those of a long run; the drift of 'none' is not (see the "
                  f"sliding-mode study for long runs).", ""]
    return lines


def _reading(table: pd.DataFrame, horizon: pd.DataFrame | None, timing: pd.DataFrame | None,
             t_end: float) -> list[str]:
    """The section's reading: one item per finding, then the horizon check."""
    g = _groups(table)
    items = ([_failures_item(table)] + _none_items(g["none"], t_end) + _baumgarte_items(g["baumgarte"])
             + _sliding_mode_items(g["sliding_mode_gains"])
             + _equal_gains_items(g["baumgarte"], g["sliding_mode_gains"])
             + _switching_items(g["sliding_mode_k"], g["sliding_mode_width"])
             + _sign_items(g["sliding_mode_sign"], g["sliding_mode_gains"]) + _accuracy_items(g["ok"], g["none"]))
    if timing is not None and len(timing):
        items.append(f"CPU time of the whole grid on this machine: {fmt_number(timing['cpu_seconds'].sum())} s "
                     f"(`timing/sensitivity_timing.csv`).")
    return ["### Reading", ""] + [f"- {t}" for t in items] + [""] + _horizon_lines(horizon)


def section(ctx: ReportContext) -> list[str]:
    lines = ["## Sensitivity of the stabilization to its gains", ""]
    table = ctx.table("sensitivity")
    if table is None:
        return lines + ["No saved table `tables/sensitivity.csv`; run the pipeline first.", ""]
    n_cases = len(ctx.cases(STUDY))
    grid_cases = ctx.cases(STUDY, group="none") or ctx.cases(STUDY)
    t_end = grid_cases[0].t_end if grid_cases else float("nan")
    mech = MECH.format(t_end=t_end)
    lines += [f"Study `sensitivity` ({n_cases} cases in `reference/cases/sensitivity.toml`): the {mech} with "
              "Baumgarte over a (d, ω) grid and sliding mode over a (Λ, K) grid for each sgn approximation, plus "
              "sweeps of the switching gain k and the boundary width; all at RK45 rtol 1e-8 (the exact sign at "
              "RK4, h = 1e-3 s), against a DOP853 rtol 1e-12 projection reference. 001 gives no gains. "
              "The study runs 001's on/off cutting law with its switches located, not the smooth law: every step "
              "then lies inside one smooth piece, so the errors are fixed by the settings and not by where an "
              "adaptive step happens to land on a 5 mm tanh ramp (`tables/perturbation_check.csv` gives "
              "how far each column moves when q(0), qd(0) move by a few ulps). "
              "Colours are on a log scale; each cell is annotated with the table's value.", ""]
    ok = table[table["status"] == "ok"] if "status" in table else table
    bg = table[table["group"] == "baumgarte"]
    if len(bg):
        lines += [_baumgarte_figure(ctx, bg, mech), ""]
    sm = table[table["group"] == "sliding_mode_gains"]
    sign = table[table["group"] == "sliding_mode_sign"]
    if len(sm):
        lines += [_sliding_mode_figure(ctx, sm, sign, "max_abs_phi", r"max $|\Phi|$ [m]", False, mech), ""]
        lines += [_sliding_mode_figure(ctx, sm, sign, "nfev", "function evaluations", True, mech), ""]
    if (ok["group"] == "sliding_mode_k").any():
        lines += [_sweep_figure(ctx, ok, "k", "switching gain k [m/s²]", "sliding_mode_k",
                                "Λ = K = 10 1/s, width 1e-8", mech), ""]
    if (ok["group"] == "sliding_mode_width").any():
        lines += [_sweep_figure(ctx, ok, "width", "boundary width (ε of sat/sqrt, 1/c of tanh/arctan) [m/s]",
                                "sliding_mode_width", "Λ = K = 10 1/s, k = 1e-6", mech), ""]
    lines += _reading(table, ctx.table("sensitivity_horizon"), ctx.table("sensitivity_timing"), t_end)
    return lines
