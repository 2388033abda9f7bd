"""Report section: friction between moving parts (study ``moving_friction``).

One subsection per set of the case list (``<set>:<role>`` groups, :mod:`study.studies.moving_friction`), in list
order, titled by the case list's ``[report.sets."<set>"] title`` (else the mechanism and variant) and followed by its
``note``. Each subsection reads the study's tables (``moving_friction_*``): friction and normal force over time with
the stick intervals shaded and the exact run's transitions marked, the dissipated energy and the energy-balance
residual; the stick/slip intervals; the two backends; Exudyn's errors and orders; the regularized law against the
exact one as eps -> 0; and every run's dissipation and residual against its bound. Every number is read from a
table; a set without some role (no exact law, no Exudyn model) has the parts its tables allow.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from study import mechanisms
from study.reference_data import tolerance
from study.report import figures
from study.report.context import ReportContext
from study.report.render import fmt_int, fmt_number, md_table
from study.studies import moving_friction as mf

STUDY = "moving_friction"
MIN_ORDER = tolerance("min_order", table="cross_validation")
UNITS = {"slider": ("friction force F", "N", "normal force N", "N"),
         "pin": ("friction torque τ", "N m", "joint reaction |R|", "N")}
VERDICT = {"True": "yes", "False": "**no**"}
ORDER_COLUMNS = (("dq", "q"), ("dqd", "q̇"), ("dF_friction", "F"), ("dN", "N"), ("ddissipated_J", "D(t_end)"))


def _slug(key: str) -> str:
    return key.replace("/", "_")


def _rows(table: pd.DataFrame | None, key: str) -> pd.DataFrame:
    if table is None or table.empty:
        return pd.DataFrame()
    return table[table["set"] == key].reset_index(drop=True)


def _title(ctx: ReportContext, key: str) -> tuple[str, str]:
    cl = ctx.case_lists.get(STUDY)
    entry = dict(cl.report.get("sets", {}).get(key, {})) if cl is not None else {}
    mechanism, _, variant = key.partition("/")
    return entry.get("title", f"{mechanisms.label(mechanism)}, variant {variant}"), entry.get("note", "")


# --- figures ----------------------------------------------------------------------------------------------
def forces_figure(forces: pd.DataFrame, phases: pd.DataFrame, title: str) -> Figure:
    """Per contact: friction and normal force (exact, regularized dashed), stick intervals shaded, the exact run's
    transitions marked; then the dissipated energy and the energy-balance residual of the exact run."""
    contacts = list(dict.fromkeys(forces["contact"]))
    with figures._style():
        fig = Figure(figsize=(9.0, 2.1 * (2 * len(contacts) + 2) + 0.6), layout="constrained")
        axes = fig.subplots(2 * len(contacts) + 2, 1, sharex=True)
        for k, name in enumerate(contacts):
            f = forces[forces["contact"] == name]
            p = phases[phases["contact"] == name]
            what_f, unit_f, what_n, unit_n = UNITS[f["kind"].iloc[0]]
            pairs = ((axes[2 * k], "friction", f"{what_f} [{unit_f}]"),
                     (axes[2 * k + 1], "normal", f"{what_n} [{unit_n}]"))
            for ax, column, ylabel in pairs:
                for i, (a, b) in enumerate(p.loc[p["phase"] == "stick", ["t_start", "t_end"]].itertuples(index=False)):
                    ax.axvspan(a, b, color="0.85", lw=0, zorder=0, label="stick (exact law)" if i == 0 else None)
                for i, t in enumerate(p.loc[p["started_by"] != "initial state", "t_start"]):
                    ax.axvline(t, color="tab:red", lw=0.8, ls=":", label="transition (exact law)" if i == 0 else None)
                ax.plot(f["t"], f[column], color="0.15", lw=1.4, label="exact law")
                if f"{column}_regularized" in f:
                    ax.plot(f["t"], f[f"{column}_regularized"], color="tab:orange", lw=1.0, ls="--",
                            label="regularized (tanh)")
                ax.set_ylabel(f"{name}:\n{ylabel}")
            axes[2 * k].legend(loc="best", frameon=False)
        first = forces[forces["contact"] == contacts[0]]
        axes[-2].plot(first["t"], first["dissipated_J"], color="tab:blue", lw=1.4)
        axes[-2].set_ylabel("dissipated energy D [J]")
        axes[-1].plot(first["t"], first["residual_J"], color="tab:green", lw=1.2)
        axes[-1].set_ylabel("energy residual [J]\nΔ(T+V) − W_loads + D")
        axes[-1].set_xlabel("time t [s]")
        fig.suptitle(title, fontsize=10)
    return fig


def convergence_figure(exudyn: pd.DataFrame, eps: pd.DataFrame, title: str) -> Figure:
    """Exudyn's errors against the step h and the regularized law's differences from the exact one against eps."""
    panels = []
    for frame, x, xlabel, slope, what in ((exudyn, "h", "step h [s]", 2, "Exudyn − in-house (regularized)"),
                                          (eps, "friction_eps", "regularization width ε [m/s; rad/s in a pin]", 3,
                                           "regularized − exact (in-house)")):
        if frame.empty:
            continue
        series = [("max|Δq| [rad]", frame[x], frame["max_abs_dq"], {"color": "tab:blue"}),
                  ("max|Δq̇| [rad/s]", frame[x], frame["max_abs_dqd"], {"color": "tab:orange"}),
                  ("max|ΔF| [N; N m for a pin]", frame[x], frame["max_abs_dF_friction"], {"color": "tab:green"}),
                  ("|ΔD(t_end)| [J]", frame[x], frame["abs_ddissipated_J"], {"color": "tab:purple"})]
        xs = np.sort(frame[x].to_numpy(dtype=float))
        top = 3.0 * float(frame[["max_abs_dq", "max_abs_dqd", "max_abs_dF_friction", "abs_ddissipated_J"]].max().max())
        series.append((f"slope {slope}", xs, top * (xs / xs.max()) ** slope, {"color": "0.5", "lw": 2.5, "alpha": 0.4,
                                                                             "marker": ""}))
        panels.append({"xlabel": xlabel, "ylabel": "max difference over the run (units in the legend)",
                       "series": series, "title": what, "legend_loc": "below"})
    return figures.log_lines_figure(panels, title, figsize=(4.8 * len(panels) + 0.6, 5.6))


# --- text ---------------------------------------------------------------------------------------------------
def _phases_text(phases: pd.DataFrame) -> list[str]:
    if phases.empty:
        return []
    rows = [[r["contact"], r["phase"], fmt_number(r["t_start"], 6), fmt_number(r["t_end"], 6), r["started_by"],
             fmt_number(r["f_required_over_limit"])] for _, r in phases.iterrows()]
    stuck = phases[phases["phase"] == "stick"]
    stops = phases[phases["started_by"].str.startswith("came to rest")]
    held = stops[stops["started_by"] == "came to rest, held"]
    text = (f"The exact run ({phases['backend'].iloc[0]} backend) has **{len(stuck)} stick interval(s)**; its contacts "
            f"came to rest {len(stops)} time(s) and were held {len(held)} time(s).")
    if len(stops) > len(held):
        lowest = stops.loc[stops["started_by"] != "came to rest, held", "f_required_over_limit"].min()
        text += (f" Where a contact could not be held, the force (a pin's torque) needed to hold it exceeded its "
                 f"static limit (c R + μ_s|N| in a slider, T0 + μ_s r |R|_δ in a pin) "
                 f"by a factor of {fmt_number(lowest)} or more, and the sliding went on in the direction the other "
                 f"forces push it.")
    return [text, "", md_table(["contact", "phase", "from t [s]", "to t [s]", "started by", "|f_req| / limit"], rows,
                               [False, False, True, True, False, True]), ""]


def _backends_text(backends: pd.DataFrame) -> list[str]:
    if backends.empty:
        return []
    r = backends.iloc[0]
    verdict = "agree" if str(r["agree"]) == "True" and str(r["transitions_agree"]) == "True" else "**do not agree**"
    return [f"Both backends run the exact law; they {verdict}: max|Δq| = {fmt_number(r['max_abs_dq'])} rad "
            f"against the bound {fmt_number(r['bound'])} rad ({r['rule']}), and their "
            f"{fmt_int(r['transitions'])} transitions differ by at most {fmt_number(r['max_abs_dt_transitions'])} s "
            f"(bound {fmt_number(r['transition_time_bound'])} s, `event_time_agreement_adaptive`).", ""]


def _orders_table(frame: pd.DataFrame, x: str, header: str) -> str:
    rows = []
    for _, r in frame.iterrows():
        values = [r[x]] + [r[d] for d in mf.DIFFERENCES]
        rows.append([fmt_number(v) for v in values] + [fmt_number(r[f"order_{c}"], 4) for c, _ in ORDER_COLUMNS])
    head = [header, "max|Δq| [rad]", "max|Δq̇| [rad/s]", "max|ΔF| [N; N m for a pin]", "max|ΔN| [N]",
            "|ΔD(t_end)| [J]"]
    head += [f"order {name}" for _, name in ORDER_COLUMNS]
    return md_table(head, rows, [True] * len(head))


def _exudyn_text(exudyn: pd.DataFrame) -> list[str]:
    if exudyn.empty:
        return []
    orders = exudyn[[f"order_{c}" for c, _ in ORDER_COLUMNS]].to_numpy(dtype=float)
    orders = orders[np.isfinite(orders)]
    low = orders.min() if orders.size else np.nan
    verdict = "at least" if low >= MIN_ORDER else "**below**"
    solvers = ", ".join(sorted(set(exudyn["solver"])))
    return [f"Exudyn ({solvers}, regularized law with the same ε = {fmt_number(exudyn['friction_eps'].iloc[0])}, "
            f"in m/s in a slider and rad/s in a pin) "
            f"against the in-house regularized run (DOP853 at the reference tolerances): observed orders "
            f"{fmt_number(low, 4)} to {fmt_number(orders.max() if orders.size else np.nan, 4)}, {verdict} the "
            f"{fmt_number(MIN_ORDER)} that second order requires (`cross_validation.toml` min_order).", "",
            _orders_table(exudyn, "h", "h [s]"), ""]


def _eps_text(eps: pd.DataFrame) -> list[str]:
    if eps.empty:
        return []
    shrinking = bool(eps["shrinking"].astype(str).eq("True").all())
    how = "shrink at every step" if shrinking else "**do not shrink at every step**"
    dq = eps["order_dq"].dropna()
    order = (f", max|Δq| at an observed order {fmt_number(dq.min(), 4)} to {fmt_number(dq.max(), 4)} in ε"
             if len(dq) else "")
    return [f"The regularized law against the exact one as ε → 0 (both at the reference tolerances, compared on the "
            f"saved samples): the differences {how}{order}. max|ΔF| is read on the samples only, so its orders "
            f"follow where the samples fall near the reversals.",
            "", _orders_table(eps, "friction_eps", "ε [m/s; rad/s in a pin]"), ""]


def _runs_text(runs: pd.DataFrame, timing: pd.DataFrame) -> list[str]:
    if runs.empty:
        return []
    rows = []
    for i, r in runs.iterrows():
        cpu = timing["cpu_seconds"].iloc[i] if timing is not None and len(timing) == len(runs) else np.nan
        setting = (f"{r['solver']} h = {fmt_number(r['h'])} s" if r["engine"] == "exudyn"
                   else f"{r['solver']} ({r['backend']})")
        law = r["friction"] + (f" ε = {fmt_number(r['friction_eps'])}" if r["friction"] == "regularized" else "")
        within = VERDICT.get(str(r["residual_within_bound"]), r["residual_within_bound"])
        rows.append([r["role"], r["engine"], setting, law, fmt_number(r["dissipated_J"], 6),
                     fmt_number(r["residual_J"]), fmt_number(r["residual_bound_J"]), within,
                     "yes" if str(r["dissipation_nondecreasing"]) == "True" else "**no**", fmt_number(cpu, 2)])
    return ["Every run's dissipated energy D(t_end) and energy-balance residual (the pipeline's check, "
            "`tables/energy_balance.csv`); Exudyn's residual is recorded only (fixed step), and falls with h² as its "
            "error does.", "",
            md_table(["role", "engine", "method", "friction law", "dissipated [J]", "residual [J]", "bound [J]",
                      "within bound", "D never drops", "CPU [s] (this machine)"], rows,
                     [False, False, False, False, True, True, True, False, False, True]), ""]


def _set_section(ctx: ReportContext, key: str, tables: dict) -> list[str]:
    title, note = _title(ctx, key)
    lines = [f"### {title}", ""]
    if note:
        lines += [note, ""]
    t = {name: _rows(frame, key) for name, frame in tables.items()}
    if t["forces"].empty and t["runs"].empty:
        return lines + ["No saved runs for this set; see the failed cases.", ""]
    runs = t["runs"]
    exact = runs[(runs["role"] == "exact")]
    if len(exact):
        r = exact.iloc[0]
        lines += [f"Over {fmt_number(r['t_end'])} s the friction takes out "
                  f"**D = {fmt_number(r['dissipated_J'], 6)} J** (exact law); the energy balance closes to "
                  f"{fmt_number(r['residual_J'])} J (bound {fmt_number(r['residual_bound_J'])} J).", ""]
    if not t["forces"].empty:
        fig = forces_figure(t["forces"], t["phases"], f"{title}: forces, dissipated energy and energy balance")
        lines += [ctx.figure(fig, f"moving_friction_{_slug(key)}_forces",
                             f"{title}: friction and normal force against time (exact law, regularized dashed; "
                             f"stick intervals shaded, transitions dotted), the dissipated energy and the energy "
                             f"residual"), ""]
    lines += _phases_text(t["phases"]) + _backends_text(t["backends"])
    if not (t["exudyn"].empty and t["eps"].empty):
        fig = convergence_figure(t["exudyn"], t["eps"], f"{title}: Exudyn against the step, regularized against ε")
        lines += [ctx.figure(fig, f"moving_friction_{_slug(key)}_convergence",
                             f"{title}: Exudyn's differences from the in-house regularized run against h, and the "
                             f"regularized law's differences from the exact one against ε"), ""]
    lines += _exudyn_text(t["exudyn"]) + _eps_text(t["eps"]) + _runs_text(runs, t["timing"])
    return lines


def section(ctx: ReportContext) -> list[str]:
    lines = ["## Friction between moving parts", ""]
    runs = ctx.table("moving_friction_runs")
    if runs is None:
        return lines + ["The study has no saved tables (`tables/moving_friction_*.csv`); run the pipeline first.", ""]
    tables = {"runs": runs, **{name: ctx.table(f"moving_friction_{name}")
                               for name in ("forces", "phases", "backends", "exudyn", "eps", "timing")}}
    keys = list(mf.sets(ctx.cases(STUDY)))
    lines += ["Coulomb friction between moving parts: in a slider whose guide moves, the friction force acts on "
              "slider and guide, equal and opposite, at the sliding velocity relative to the guide; in a pin between "
              "two bodies, the friction torque μ r |R| (R the joint's reaction) acts on both, equal and opposite, "
              "against their relative rotation. ε is in m/s in a slider and rad/s in a pin. Each set below runs the "
              "exact "
              "law (event-located stick/slip) on both backends, the regularized law (tanh(v/ε)) in-house and in "
              f"Exudyn at three steps, and the regularized law at shrinking ε against the exact one "
              f"(`reference/cases/moving_friction.toml`, {len(keys)} set(s)).", ""]
    for key in keys:
        lines += _set_section(ctx, key, tables)
    return lines
