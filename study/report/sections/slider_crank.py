"""Report section: the slider-crank with Coulomb friction, paper 000 (study ``slider_crank``).

Reads the tables ``slider_crank_summary``, ``slider_crank_holding_forces``, ``slider_crank_eps_sweep``
(+ ``slider_crank_eps_sweep_timing``), written by :func:`study.studies.slider_crank.summarize`, and the
study's saved runs, which are only drawn. Figures: friction force, normal force and slider velocity
over time with the stick phases of the exact treatment shaded (regularized and plain-sgn runs
overlaid), one per variant; the regularization-width sweep; the runs from 000's printed initial state.
The slider velocity is x_B' of the saved q, q' with the link lengths of the parameter file.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from study.params import load_parameters
from study.pipeline import Case
from study.report import figures
from study.report.context import ReportContext
from study.report.render import fmt_int, fmt_number, md_table
from study.studies import slider_crank as sc
from study.studies.slider_crank_paper import slider_velocity

STUDY = "slider_crank"
VARIANTS = ("seed", "slip_then_stick", "sustained_sliding")
TREATMENT_STYLE = {
    "exact": {"color": "tab:blue", "lw": 1.6, "ls": "-"},
    "regularized": {"color": "tab:orange", "lw": 1.2, "ls": (0, (5, 2))},
    "sign": {"color": "tab:red", "lw": 0.6, "ls": ":", "alpha": 0.8},
}
EPS_COLORS = ("tab:purple", "tab:orange", "tab:green", "tab:brown", "tab:pink")


def _row(table: pd.DataFrame | None, **where) -> pd.Series | None:
    if table is None:
        return None
    mask = np.ones(len(table), dtype=bool)
    for k, v in where.items():
        mask &= (table[k] == v).to_numpy()
    return table[mask].iloc[0] if mask.any() else None


def _first_time(text) -> float:
    """The first of a ';'-joined list of times in the summary table (NaN if empty).

    A list of one time is read back from the CSV as a number, a longer one as text.
    """
    if isinstance(text, str):
        return float(text.split(";")[0]) if text else float("nan")
    return float(text) if text is not None else float("nan")





def _treatment_cases(ctx: ReportContext, variant: str) -> dict[str, Case]:
    return {c.label("treatment"): c for c in ctx.cases(STUDY, group="treatments", variant=variant) if ctx.has(c)}


# --- figures -----------------------------------------------------------------------------------
def _forces_figure(ctx: ReportContext, variant: str) -> str | None:
    cases = _treatment_cases(ctx, variant)
    if "exact" not in cases:
        return None
    v = load_parameters("slider_crank", variant).values
    runs = {t: ctx.load(c) for t, c in cases.items()}
    panels = {"friction": [], "normal": [], "velocity": []}
    for treatment in ("sign", "regularized", "exact"):
        if treatment not in runs:
            continue
        r, style = runs[treatment], TREATMENT_STYLE[treatment]
        o = cases[treatment].kwargs
        if treatment == "exact":
            label = f"exact (event-located stick/slip, {o['integrator']})"
        elif treatment == "regularized":
            label = f"regularized tanh, ε = {o['friction_eps']:g} m/s ({o['integrator']})"
        else:
            label = f"000's plain sgn ({o['integrator']}, h = {o.get('step', float('nan')):g} s)"
        panels["friction"].append((label, r.t, r.forces["friction_guide"], style))
        panels["normal"].append((label, r.t, r.forces["normal_guide"], style))
        panels["velocity"].append((label, r.t, 1e3 * slider_velocity(v, r.q, r.qd), style))
    exact = runs["exact"]
    fig = figures.stacked_time_series_figure(
        [("friction force F_fr (+x) [N]", panels["friction"]),
         ("normal force N [N]", panels["normal"]),
         ("slider velocity x_B' [mm/s]", panels["velocity"])],
        f"slider-crank (variant {variant}), method none (no stabilization): guide forces and slider velocity,\n"
        f"friction treatments exact / regularized / plain sgn; grey: stick phases of the exact treatment",
        shaded=sc.stick_intervals(exact), shade_label="stick (exact treatment)")
    return ctx.figure(fig, f"slider_crank_forces_{variant}",
                      f"friction force, normal force and slider velocity of the slider-crank, variant {variant}")


def _eps_figure(ctx: ReportContext, sweep: pd.DataFrame) -> str | None:
    variant = "slip_then_stick"
    cases = [c for c in sc.eps_sweep_cases(ctx.cases(STUDY)) if c.variant == variant and ctx.has(c)]
    exact_cases = ctx.cases(STUDY, group="treatments", variant=variant, friction="exact")
    if not cases or not exact_cases or not ctx.has(exact_cases[0]):
        return None
    exact = ctx.load(exact_cases[0])
    series = []
    for color, case in zip(EPS_COLORS, cases):
        r = ctx.load(case)
        n = min(len(r.t), len(exact.t))
        series.append((f"ε = {case.kwargs['friction_eps']:g} m/s", r.t[:n], np.abs(r.q[:n, 0] - exact.q[:n, 0]),
                       {"color": color, "lw": 1.2, "marker": None}))
    stick = sc.stick_intervals(exact)
    time_panel = {"xlabel": "time t [s]", "ylabel": "|q1,regularized - q1,exact| [rad]", "xscale": "linear",
                  "series": series, "legend_title": "regularized tanh",
                  "title": f"{variant}: crank angle difference\n(exact run sticks from t = {stick[-1][0]:.3g} s)"
                  if stick else f"{variant}: crank angle difference"}
    creep, dev, cost = [], [], []
    for color, (var, group) in zip(("tab:blue", "tab:red"), sweep.groupby("variant", sort=False)):
        dev.append((f"{var}: max |Δq1| vs exact", group["friction_eps"], group["max_abs_dq1_vs_exact"],
                    {"color": color}))
        if group["creep_q1"].notna().any():
            creep.append((f"{var}: creep of q1 while exact sticks", group["friction_eps"], group["creep_q1"],
                          {"color": color, "ls": "--", "marker": "s"}))
        cost.append((f"{var}", group["friction_eps"], group["nfev"], {"color": color}))
    panels = [time_panel,
              {"xlabel": "regularization width ε [m/s]", "ylabel": "deviation from the exact treatment [rad]",
               "series": dev + creep, "title": "accuracy against ε"},
              {"xlabel": "regularization width ε [m/s]", "ylabel": "function evaluations [-]",
               "series": cost, "title": "cost against ε (exact treatment: see the table)"}]
    fig = figures.log_lines_figure(panels, "slider-crank, method none: regularized Coulomb friction (tanh, RK45 "
                                   "rtol 1e-8) against the exact treatment, by regularization width eps",
                                   figsize=(15.0, 4.6))
    return ctx.figure(fig, "slider_crank_eps_sweep", "regularized friction against the exact treatment by eps")


def _printed_figure(ctx: ReportContext) -> str | None:
    printed = [c for c in ctx.cases(STUDY, group="printed") if ctx.has(c)]
    consistent = ctx.cases(STUDY, group="treatments", variant="seed", friction="exact")
    if not printed:
        return None
    styles = {"projection": {"color": "tab:green", "lw": 1.4}, "baumgarte": {"color": "tab:purple", "lw": 1.4}}
    normal, friction, q1 = [], [], []
    for case in printed + [c for c in consistent if ctx.has(c)]:
        r = ctx.load(case)
        if case.group == "printed":
            label = f"printed initial state, method {case.kwargs['method']}"
            style = styles.get(case.kwargs["method"], {})
        else:
            label, style = "consistent initial state, method none", {"color": "black", "lw": 1.0, "ls": "--"}
        normal.append((label, r.t, np.abs(r.forces["normal_guide"]), style))
        friction.append((label, r.t, np.abs(r.forces["friction_guide"]), style))
        q1.append((label, r.t, r.q[:, 0], style))
    panels = [{"xlabel": "time t [s]", "ylabel": "|N| [N]", "xscale": "linear", "series": normal,
               "title": "normal force of the guide"},
              {"xlabel": "time t [s]", "ylabel": "|F_fr| [N]", "xscale": "linear", "series": friction,
               "title": "friction force"},
              {"xlabel": "time t [s]", "ylabel": "crank angle q1 [rad]", "xscale": "linear", "yscale": "linear",
               "series": q1, "title": "crank angle"}]
    fig = figures.log_lines_figure(panels, "slider-crank (variant seed), exact friction treatment: 000's printed "
                                   "(inconsistent) initial state with projection or Baumgarte stabilization",
                                   figsize=(15.0, 4.6), markers=False)
    return ctx.figure(fig, "slider_crank_printed_initial_state",
                      "forces and crank angle from 000's printed initial state")


# --- text ----------------------------------------------------------------------------------------
def _seed_text(summary: pd.DataFrame, held: pd.DataFrame | None) -> list[str]:
    seed = _row(summary, case="seed_exact")
    hold = _row(held, variant="seed")
    if seed is None or hold is None:
        return ["The seed runs or their holding forces are missing; see the failed cases.", ""]
    t_stick = _first_time(seed["stick_times"])
    lines = [
        "### What the seed case does",
        "",
        f"From the consistent initial state (000's q1 = π/6 and q1' = 0.001 rad/s, the constraint solved for q2, q2') "
        f"the slider starts in phase `{seed['initial_phase']}` and **sticks at t = {fmt_number(t_stick, 4)} s**, after "
        f"moving {fmt_number(hold['slide_distance'])} m while the crank turns {fmt_number(hold['crank_rotation'])} rad. It stays "
        f"stuck for the rest of the {fmt_number(hold['t'])} s ({seed['n_slip_from_stick']} slip onsets after that). "
        f"**The seed mechanism does not run**: 000's figures show motion over 20 s, which this model cannot "
        f"produce from 000's data.",
        "",
        f"What holds it (static balance at the rest state, 000's D = [1, d12]; torques about the crank axis): "
        f"drive M = {fmt_number(hold['torque_drive_M'], 4)} N m, the α-term {fmt_number(hold['torque_alpha_term'], 3)} N m, "
        f"the rod's weight {fmt_number(hold['torque_rod_weight'], 4)} N m (the slider's weight is normal to the guide: "
        f"{fmt_number(hold['torque_slider_weight'])} N m). Their sum, {fmt_number(hold['torque_sum'], 3)} N m, acts through the "
        f"lever dx_B/dq1 = {fmt_number(hold['lever_dxB_dq1'], 3)} m, so the guide must supply "
        f"f_req = {fmt_number(hold['f_required'], 3)} N against a static limit F + μ|N| = {fmt_number(hold['static_limit'], 3)} N "
        f"(N = {fmt_number(hold['normal_N'], 4)} N): **{fmt_number(100 * hold['holding_fraction'], 2)} % of the limit**. "
        f"The solver's stuck friction force, {fmt_number(hold['friction_solver'], 4)} N, is the same balance. "
        f"**Breaking away at this pose needs M = {fmt_number(hold['breakaway_M'], 3)} N m**, "
        f"{fmt_number(hold['breakaway_M'] / hold['M'], 3)} times 000's M = {fmt_number(hold['M'])} N m.",
        "",
    ]
    damp = _row(summary, case="alpha_damping_exact")
    hold_d = _row(held, variant="alpha_damping")
    if damp is not None and hold_d is not None:
        lines += [f"Reading 000's '−α q1' as a damper −α q1' instead of a spring (variant `alpha_damping`) changes "
                  f"nothing that matters: it sticks at t = {fmt_number(_first_time(damp['stick_times']), 4)} s and needs "
                  f"M = {fmt_number(hold_d['breakaway_M'], 3)} N m to break away.", ""]
    return lines


def _variants_text(summary: pd.DataFrame, held: pd.DataFrame | None) -> list[str]:
    lines = ["### The study's own variants", ""]
    sts = _row(summary, case="slip_then_stick_exact")
    hold = _row(held, variant="slip_then_stick")
    if sts is not None:
        text = (f"`slip_then_stick` (drive torque raised; study's own case): the slider slides, slows as the "
                f"crank's lever on it grows, and **sticks at t = {fmt_number(_first_time(sts['stick_times']), 4)} s** with "
                f"q1 = {fmt_number(sts['q1_t20'], 4)} rad, dissipating {fmt_number(sts['dissipated_energy'], 3)} J.")
        if hold is not None:
            text += (f" There the drive M = {fmt_number(hold['M'])} N m needs {fmt_number(100 * hold['holding_fraction'], 3)} % of "
                     f"the static limit; breaking away at that pose would need M = {fmt_number(hold['breakaway_M'], 3)} N m.")
        lines += [text, ""]
    ss = _row(summary, case="sustained_sliding_exact")
    if ss is not None:
        lines += [f"`sustained_sliding` (drive torque raised further; study's own case): it **never sticks** "
                  f"({ss['n_stick']} stick phases), reverses {ss['n_reversals']} times (first at "
                  f"t = {fmt_number(_first_time(ss['reversal_times']), 4)} s, at the crank's dead centres, where it cannot "
                  f"be held), reaches q1 = {fmt_number(ss['q1_t20'], 4)} rad at 20 s and dissipates "
                  f"{fmt_number(ss['dissipated_energy'], 4)} J in the guide.", ""]
    return lines


def _treatments_text(summary: pd.DataFrame) -> list[str]:
    lines = ["### Friction treatments compared", "",
             "Exact: event-located stick/slip. Regularized: sgn(v) replaced by tanh(v/ε). Sign: 000's plain "
             "sgn(v) with fixed-step RK4. Values at t = 20 s; energy-balance error = max over the run of "
             "|(T + V − work of the loads and friction) − its initial value|.", ""]
    cols = ["case", "treatment", "integrator", "final_phase", "n_stick", "q1_t20", "friction_t20", "normal_t20",
            "dissipated_energy", "energy_balance_error", "max_abs_phi", "nfev"]
    rows = [[r[c] if c in ("case", "treatment", "integrator", "final_phase") else (fmt_int(r[c]) if c in ("nfev", "n_stick") else fmt_number(r[c], 6 if c == "q1_t20" else 4))
             for c in cols] for _, r in summary[summary["initial"] == "consistent"].iterrows()]
    lines += [md_table(["run", "treatment", "integrator", "phase at end", "stick onsets", "q1(20 s) [rad]",
                        "F_fr(20 s) [N]", "N(20 s) [N]", "dissipated [J]", "energy-balance error [J]",
                        "max|Φ| [m]", "evaluations"], rows, [False] * 4 + [True] * 8), ""]
    ex, reg, sign = (_row(summary, case=f"seed_{t}") for t in ("exact", "regularized", "sign"))
    if ex is not None and reg is not None:
        lines.append(f"Where the exact treatment sticks, the regularized law **creeps**: in the seed case its crank "
                     f"turns from {fmt_number(ex['q1_t20'], 6)} rad (exact, stuck) to {fmt_number(reg['q1_t20'], 6)} rad at 20 s, "
                     f"and it needs {fmt_int(reg['nfev'])} function evaluations against {fmt_int(ex['nfev'])} for the exact "
                     f"run.")
    if sign is not None:
        lines.append(f"The plain sgn neither sticks nor creeps smoothly: RK4's stages straddle v = 0, so the "
                     f"friction force jumps between the limits (seed: {fmt_number(sign['friction_t10'], 4)} N at 10 s, "
                     f"{fmt_number(sign['friction_t20'], 4)} N at 20 s, where the exact run holds with "
                     f"{fmt_number(ex['friction_t20'], 4) if ex is not None else '–'} N). Its friction work is not the energy "
                     f"the model loses: the energy-balance error, {fmt_number(sign['energy_balance_error'], 4)} J, is as "
                     f"large as its whole reported dissipation, {fmt_number(sign['dissipated_energy'], 4)} J (exact: "
                     f"{fmt_number(ex['dissipated_energy'], 3) if ex is not None else '–'} J).")
    sts_ex, sts_sign = _row(summary, case="slip_then_stick_exact"), _row(summary, case="slip_then_stick_sign")
    if sts_ex is not None and sts_sign is not None:
        lines.append(f"In `slip_then_stick` the sign run's apparent stick starts at "
                     f"{fmt_number(_first_time(sts_sign['stick_times']), 3)} s (exact: "
                     f"{fmt_number(_first_time(sts_ex['stick_times']), 4)} s; the band |v| ≤ ε on 0.01 s samples).")
    return lines + [""]


def _eps_text(sweep: pd.DataFrame, timing: pd.DataFrame | None) -> list[str]:
    lines = ["### Regularization width ε against the exact treatment", "",
             "Regularized runs (tanh, RK45 rtol 1e-8) of the two moving variants compared with the exact run of the "
             "same variant on common samples. Creep: the crank angle the regularized run still turns after the exact "
             "run has stuck for good.", ""]
    rows = []
    for _, r in sweep.iterrows():
        cpu = np.nan
        if timing is not None:
            t = timing[(timing["variant"] == r["variant"]) & np.isclose(timing["friction_eps"], r["friction_eps"], rtol=1e-6, atol=0)]
            cpu = t["cpu_seconds"].iloc[0] if len(t) else np.nan
        rows.append([r["variant"], fmt_number(r["friction_eps"]), fmt_number(r["max_abs_dq1_vs_exact"]), fmt_number(r["creep_q1"]),
                     fmt_number(r["max_abs_dfriction_vs_exact"]), fmt_number(r["dissipated_energy"], 5),
                     fmt_number(r["dissipated_energy_exact"], 5), fmt_int(r["nfev"]), fmt_number(cpu, 2)])
    lines += [md_table(["variant", "ε [m/s]", "max|Δq1| [rad]", "creep of q1 [rad]", "max|ΔF_fr| [N]",
                        "dissipated [J]", "dissipated, exact [J]", "evaluations", "CPU [s] (this machine)"],
                       rows, [False] + [True] * 8), ""]
    sts = sweep[sweep["variant"] == "slip_then_stick"].sort_values("friction_eps", ascending=False)
    if len(sts) >= 2:
        creep = sts["creep_q1"].to_numpy(dtype=float)
        eps = sts["friction_eps"].to_numpy(dtype=float)
        slopes = np.log(creep[:-1] / creep[1:]) / np.log(eps[:-1] / eps[1:])
        lines.append(f"In `slip_then_stick` the creep falls with ε (log-log slope {fmt_number(slopes.min(), 3)} to "
                     f"{fmt_number(slopes.max(), 3)} between neighbouring ε; 1 is proportional): "
                     f"{fmt_number(creep[0])} rad at ε = {fmt_number(eps[0])} m/s, {fmt_number(creep[-1])} rad at ε = {fmt_number(eps[-1])} m/s, "
                     f"while the cost rises from {fmt_int(sts['nfev'].iloc[0])} to {fmt_int(sts['nfev'].iloc[-1])} function "
                     f"evaluations (the law's stiffness grows like 1/ε). **No ε gives both stick and a cheap run: "
                     f"the exact treatment needs {fmt_int(sts['nfev_exact'].iloc[0])} evaluations.**")
    ss = sweep[sweep["variant"] == "sustained_sliding"].sort_values("friction_eps", ascending=False)
    if len(ss):
        lines.append(f"In `sustained_sliding`, which never sticks, max|Δq1| goes from "
                     f"{fmt_number(ss['max_abs_dq1_vs_exact'].iloc[0])} rad at ε = {fmt_number(ss['friction_eps'].iloc[0])} m/s "
                     f"to {fmt_number(ss['max_abs_dq1_vs_exact'].min())} rad, where the integrator's own error "
                     f"(rtol 1e-8) takes over.")
    return lines + [""]


def _printed_text(summary: pd.DataFrame) -> list[str]:
    proj, baum = _row(summary, case="printed_projection_exact"), _row(summary, case="printed_baumgarte_exact")
    seed = _row(summary, case="seed_exact")
    if proj is None or baum is None or seed is None:
        return []
    return ["### 000's printed initial state", "",
            f"The printed q2 puts the slider off its guide and q' violates the velocity constraint. Used as is: "
            f"post-step **projection** jumps to the nearest assembled configuration (minimum norm), a different crank "
            f"angle, q1 = {fmt_number(proj['q1_t1'], 4)} rad instead of {fmt_number(seed['q1_t1'], 4)} rad, and sticks there at "
            f"t = {fmt_number(_first_time(proj['stick_times']), 3)} s. **Baumgarte** pulls the slider onto the guide with a "
            f"normal force of up to {fmt_number(baum['max_abs_normal'], 4)} N ({fmt_number(baum['max_abs_normal'] / seed['max_abs_normal'], 3)} "
            f"times the consistent run's {fmt_number(seed['max_abs_normal'], 4)} N), hence friction up to "
            f"{fmt_number(baum['max_abs_friction'], 4)} N ({fmt_number(baum['max_abs_friction'] / seed['max_abs_friction'], 3)} times), "
            f"dissipates {fmt_number(baum['dissipated_energy'], 4)} J (consistent: {fmt_number(seed['dissipated_energy'], 3)} J) and "
            f"comes to rest at q1 = {fmt_number(baum['q1_t20'], 4)} rad. The two end at different rest positions, neither the "
            f"consistent run's: the printed state cannot be used as is.", ""]


def section(ctx: ReportContext) -> list[str]:
    lines = ["## Slider-crank with Coulomb friction (paper 000)", ""]
    summary = ctx.table("slider_crank_summary")
    if summary is None:
        return lines + ["The slider-crank study has no saved summary (`tables/slider_crank_summary.csv`); run "
                        "the pipeline first.", ""]
    held = ctx.table("slider_crank_holding_forces")
    n_runs = len(ctx.cases(STUDY))
    lines += [f"Study `slider_crank` ({n_runs} cases in `reference/cases/slider_crank.toml`, 20 s each, no "
              f"stabilization from the consistent initial state): the variants `seed` (000's data), `slip_then_stick` "
              f"and `sustained_sliding` (the study's own larger drive torques) and `alpha_damping`, each with the exact, "
              f"regularized and plain-sgn friction treatments; 000's printed initial state; and the regularization "
              f"width ε.", ""]
    lines += _seed_text(summary, held)
    lines += _variants_text(summary, held)
    for variant in VARIANTS:
        image = _forces_figure(ctx, variant)
        if image:
            lines += [image, ""]
    lines += _treatments_text(summary)
    sweep = ctx.table("slider_crank_eps_sweep")
    if sweep is not None and len(sweep):
        timing = ctx.table("slider_crank_eps_sweep_timing")
        lines += _eps_text(sweep, timing)
        image = _eps_figure(ctx, sweep)
        if image:
            lines += [image, ""]
    lines += _printed_text(summary)
    image = _printed_figure(ctx)
    if image:
        lines += [image, ""]
    lines += _readings_text(ctx.table("seed_breakaway_readings"), summary)
    return lines


def _readings_text(readings: pd.DataFrame | None, summary: pd.DataFrame) -> list[str]:
    """The open assumption about 000's F at rest: break-away torque of the seed pose under each reading."""
    if readings is None or readings.empty:
        return []
    out = ["### The resistance F at rest: an open assumption", "",
           "000 says only that F 'opposes the slider's motion'. Whether it also holds a stuck slider is not stated; "
           "the parameter `resistance_reading` (`reference/slider_crank.toml`) chooses, and the exact friction law "
           "(`study.solver.friction.RESISTANCE_READINGS`) implements both. Break-away torque of the seed's stuck pose "
           "(000's method, `tables/seed_breakaway_readings.csv`):", ""]
    rows = [[r["reading"] + (" (parameter file)" if r["parameter_file"] else ""), r["static_limit_rule"],
             fmt_number(r["breakaway_M"], 3), fmt_number(r["breakaway_over_M_seed"], 3)] for _, r in readings.iterrows()]
    out += [md_table(["reading", "static limit", "break-away M [N m]", "× 000's M"], rows, [False, False, True, True]), ""]
    alt = summary[summary["case"] == "seed_exact_sliding_only"] if "case" in summary else summary.iloc[0:0]
    if len(alt):
        r = alt.iloc[0]
        out += [f"Under `sliding_only` the seed run ends in phase '{r['final_phase']}' "
                f"({int(r['n_stick'])} stick onset(s)): with 000's M = {fmt_number(readings['M_seed'].iloc[0])} N m "
                "the verdict 'the mechanism does not run' holds under either reading.", ""]
    return out
