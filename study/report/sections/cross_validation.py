"""Report section: the in-house solver against the independent Exudyn models (study ``cross_validation``).

Reads the tables ``exudyn_agreement``, ``exudyn_agreement_timing`` and ``exudyn_reactions``
(written by :func:`study.studies.cross_validation.summarize`) and the study's saved runs. Figures:
differences from the reference over time (one variant per mechanism), friction and normal force of
both codes over time, joint reactions of both codes, and the convergence of max|dq| with h.
Every number in the text is read from a table; the runs are only drawn.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from study import mechanisms
from study.reference_data import tolerance
from study.report import figures
from study.report.context import ReportContext
from study.report.render import fmt_number, md_table
from study.studies import cross_validation as xv

STUDY = "cross_validation"
SOLVER_STYLE = {"index3": {"color": "tab:blue", "ls": "-"}, "index2": {"color": "tab:orange", "ls": "--"}}


def _report_notes(ctx: ReportContext) -> str:
    """The case list's [report] notes: documented limits that are tests rather than table rows."""
    cl = ctx.case_lists.get(STUDY)
    return str(cl.report.get("notes", "")) if cl is not None else ""


def _report_choices(ctx: ReportContext) -> tuple[list[str], list[str]]:
    """The sets drawn over time and the sets whose joint reactions are drawn (the case list's [report])."""
    cl = ctx.case_lists.get(STUDY)
    choices = cl.report if cl is not None else {}
    return list(choices.get("time_series", [])), list(choices.get("reactions", []))
# Orders below the tests' lower bound are listed as disagreements; force deviations below the
# index-3 round-off floor (a fraction of the largest force) are called round-off.
MIN_ORDER = tolerance("min_order", table="cross_validation")
ROUND_OFF_RELATIVE = tolerance("index3_reaction_floor_relative", table="cross_validation")





def _mech(name: str) -> str:
    return mechanisms.label(name)


def _unit(mechanism: str) -> str:
    return mechanisms.coordinate_unit(mechanism)


def _set_cases(ctx: ReportContext, key: str) -> dict[str, list]:
    out = {r: [] for r in xv.ROLES}
    for case in ctx.cases(STUDY):
        k, role = xv.parse_group(case.group)
        if k == key:
            out[role].append(case)
    return out


def _finest(cases: list, solver: str):
    chosen = [c for c in cases if c.kwargs.get("solver") == solver]
    return min(chosen, key=lambda c: c.kwargs["h"]) if chosen else None


def _load_set(ctx: ReportContext, key: str):
    """(reference, {solver: finest-h Exudyn run}) of a set, or None if anything is missing."""
    cases = _set_cases(ctx, key)
    if len(cases["reference"]) != 1 or not all(ctx.has(c) for c in cases["reference"] + cases["exudyn"]):
        return None
    ref = ctx.load(cases["reference"][0])
    runs = {}
    for solver in ("index3", "index2"):
        case = _finest(cases["exudyn"], solver)
        if case is not None:
            runs[solver] = (case.kwargs["h"], ctx.load(case))
    return ref, runs


def _positive(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float).copy()
    x[x <= 0] = np.nan
    return x


# --- figures ----------------------------------------------------------------------------------
def differences_figure(ref, runs, mechanism: str, variant: str) -> Figure:
    names = ref.meta.get("coordinate_names") or [f"q{i + 1}" for i in range(ref.q.shape[1])]
    with figures._style():
        fig = Figure(figsize=(9.0, 5.4), layout="constrained")
        axes = fig.subplots(2, 1, sharex=True)
        for solver, (h, run) in runs.items():
            ia, ib = xv.common_samples(run, ref)
            for i, name in enumerate(names):
                style = dict(SOLVER_STYLE[solver], lw=1.0, alpha=1.0 - 0.25 * i)
                axes[0].plot(ref.t[ib], _positive(np.abs(run.q[ia, i] - ref.q[ib, i])),
                             label=f"Exudyn {solver}, h={h:g} s: {name}", **style)
                axes[1].plot(ref.t[ib], _positive(np.abs(run.qd[ia, i] - ref.qd[ib, i])),
                             label=f"Exudyn {solver}, h={h:g} s: {name}", **style)
        axes[0].set_ylabel(f"|q_i - q_i,ref| [{_unit(mechanism)}]")
        axes[1].set_ylabel(f"|q̇_i - q̇_i,ref| [{_unit(mechanism)}/s]")
        axes[1].set_xlabel("time t [s]")
        for ax in axes:
            ax.set_yscale("log")
        axes[0].legend(loc="center left", bbox_to_anchor=(1.01, 0.0), frameon=False)
        fig.suptitle(f"{_mech(mechanism)} (variant {variant}): Exudyn minus in-house reference "
                     f"(DOP853 rtol 1e-12, projection), regularized friction", fontsize=10)
    return fig


def forces_figure(ref, runs, mechanism: str, variant: str) -> Figure:
    with figures._style():
        fig = Figure(figsize=(9.0, 5.4), layout="constrained")
        axes = fig.subplots(2, 1, sharex=True)
        pairs = ((axes[0], xv.tangential_force, "tangential force F [N]\n(Coulomb + resistance)"),
                 (axes[1], xv.normal_force, "normal guide force N [N]"))
        for ax, get, label in pairs:
            ax.plot(ref.t, get(ref), color="0.2", lw=2.2, label="in-house reference (DOP853 rtol 1e-12)")
            for solver, (h, run) in runs.items():
                ax.plot(run.t, get(run), lw=1.0, label=f"Exudyn {solver}, h={h:g} s", **SOLVER_STYLE[solver])
            ax.set_ylabel(label)
        axes[1].set_xlabel("time t [s]")
        axes[0].legend(loc="best", frameon=False)
        fig.suptitle(f"{_mech(mechanism)} (variant {variant}): guide forces, Exudyn and in-house "
                     f"(regularized tanh friction, same eps)", fontsize=10)
    return fig


def reactions_figure(ref, runs, mechanism: str, variant: str) -> Figure:
    joints = xv.inhouse_joint_forces(ref)
    names = [f"lam{i + 1}" for i in range(ref.lam.shape[1])] + sorted(k for k in joints if k.endswith("_x"))
    with figures._style():
        fig = Figure(figsize=(10.0, 6.0), layout="constrained")
        axes = fig.subplots(2, 1, sharex=True)
        colors = matplotlib_colors(len(names))
        for name, color in zip(names, colors):
            inhouse = ref.lam[:, int(name[3:]) - 1] if name.startswith("lam") else joints[name]
            axes[0].plot(ref.t, inhouse, color=color, lw=2.0, alpha=0.6, label=f"in-house {name}")
            for solver, (h, run) in runs.items():
                ia, ib = xv.common_samples(run, ref)
                exu = run.lam[:, int(name[3:]) - 1] if name.startswith("lam") else run.forces[name]
                if solver == "index2":
                    axes[0].plot(run.t, exu, color=color, lw=0.9, ls="--", label=f"Exudyn {solver} {name}")
                axes[1].plot(ref.t[ib], _positive(np.abs(exu[ia] - inhouse[ib])), color=color, lw=1.0,
                             ls=SOLVER_STYLE[solver]["ls"], label=f"{solver} h={h:g} s: {name}")
        axes[0].set_ylabel("reaction [N]")
        axes[1].set_ylabel("|Exudyn - in-house| [N]")
        axes[1].set_yscale("log")
        axes[1].set_xlabel("time t [s]")
        axes[0].legend(loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False, fontsize=7)
        axes[1].legend(loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False, fontsize=6, ncol=2)
        fig.suptitle(f"{_mech(mechanism)} (variant {variant}, frictionless): multipliers lam and joint forces "
                     f"(x, on the distal body), Exudyn vs in-house", fontsize=10)
    return fig


def matplotlib_colors(n: int) -> list:
    from matplotlib import colormaps

    cmap = colormaps["tab10"]
    return [cmap(i % 10) for i in range(n)]


def convergence_figure(agree: pd.DataFrame) -> Figure:
    exu = agree[agree.engine == "exudyn"]
    with figures._style():
        fig = Figure(figsize=(10.0, 4.6))
        mechs = sorted(set(exu.mechanism)) or [""]
        axes = np.atleast_1d(fig.subplots(1, len(mechs), sharey=False))
        for ax, mech in zip(axes, mechs):
            sub = exu[exu.mechanism == mech]
            keys = sorted({(v, f) for v, f in zip(sub.variant, sub.friction)})
            colors = matplotlib_colors(len(keys))
            for (variant, friction), color in zip(keys, colors):
                for solver in ("index3", "index2"):
                    rows = sub[(sub.variant == variant) & (sub.friction == friction) & (sub.solver == solver)]
                    rows = rows.sort_values("h")
                    ax.loglog(rows.h, rows.max_abs_dq, marker="o" if solver == "index3" else "s", ms=4,
                              color=color, ls=SOLVER_STYLE[solver]["ls"], lw=1.0,
                              label=f"{variant} ({'no friction' if friction == 'none' else friction}), {solver}")
            if len(sub):
                h = np.array(sorted(set(sub.h)))
                e0 = 3.0 * float(sub.max_abs_dq.max())   # above every line, so the guide stays visible
                ax.loglog(h, e0 * (h / h.max()) ** 2, color="0.5", lw=2.5, alpha=0.4, label="slope 2")
            ax.set_xlabel("step h [s]")
            ax.set_ylabel("max |q - q_ref| over the run [rad]")
            ax.set_title(f"{_mech(mech)}: Exudyn error vs step")
            ax.legend(fontsize=6.5, frameon=False, loc="lower right")
        fig.tight_layout()
    return fig


# --- text -------------------------------------------------------------------------------------
def _agreement_rows(agree: pd.DataFrame, timing: pd.DataFrame | None) -> list[list[str]]:
    keyed = {}
    if timing is not None:
        for r in timing.itertuples(index=False):
            keyed[(r.mechanism, r.variant, r.friction, r.solver, fmt_number(r.h))] = r
    rows = []
    for r in agree.itertuples(index=False):
        t = keyed.get((r.mechanism, r.variant, r.friction, r.solver, fmt_number(r.h)))
        rows.append([_mech(r.mechanism), r.variant, r.friction, fmt_number(r.t_end), r.solver, fmt_number(r.h),
                     fmt_number(r.max_abs_dq), fmt_number(r.max_abs_dqd), fmt_number(r.max_abs_dF_friction), fmt_number(r.max_abs_dN),
                     fmt_number(r.order_dq), fmt_number(r.order_dqd), fmt_number(r.order_dF_friction), fmt_number(r.order_dN),
                     fmt_number(t.cpu_seconds) if t is not None else "–",
                     fmt_number(t.inhouse_reference_cpu_seconds) if t is not None else "–"])
    return rows


def _switched(agree: pd.DataFrame) -> pd.Series:
    """Rows of sets whose reference located switches of an on/off load law (no order expected)."""
    if "reference_switches" not in agree.columns:
        return pd.Series(False, index=agree.index)
    return agree.reference_switches.fillna(0) > 0


def _order_summary(agree: pd.DataFrame) -> list[str]:
    exu = agree[(agree.engine == "exudyn") & ~_switched(agree)]
    lines = []
    for col, what in (("order_dq", "q"), ("order_dqd", "q̇"), ("order_dF_friction", "friction force"),
                      ("order_dN", "normal force")):
        for solver in ("index3", "index2"):
            vals = exu[(exu.solver == solver)][col].dropna()
            if len(vals):
                lines.append(f"- {what}, {solver}: observed orders from {fmt_number(vals.min())} to {fmt_number(vals.max())} "
                             f"({len(vals)} step refinements over every set without an on/off load).")
    return lines


def _disagreements(agree: pd.DataFrame, react: pd.DataFrame | None) -> list[str]:
    lines = []
    exu = agree[(agree.engine == "exudyn") & ~_switched(agree)]
    low = exu[exu.order_dN < MIN_ORDER].dropna(subset=["order_dN"])
    for r in low.itertuples(index=False):
        why = ("round-off floor of the index-3 multipliers (the error grows as h shrinks)" if r.order_dN < 0.5 * MIN_ORDER
               or r.max_abs_dN < ROUND_OFF_RELATIVE * r.max_abs_N_ref else "the O(h) initial layer of index-3 multipliers")
        lines.append(f"- {_mech(r.mechanism)} {r.variant} ({r.friction}), {r.solver}, h = {fmt_number(r.h)} s: the normal "
                     f"force converges at order {fmt_number(r.order_dN)} (max|dN| = {fmt_number(r.max_abs_dN)} N, "
                     f"{fmt_number(r.max_abs_dN / r.max_abs_N_ref)} of max|N|): {why}.")
    worst = exu.loc[exu.groupby(["mechanism"]).max_abs_dq.idxmax()] if len(exu) else exu
    for r in worst.itertuples(index=False):
        lines.append(f"- Largest position disagreement, {_mech(r.mechanism)}: {r.variant} ({r.friction}), {r.solver}, "
                     f"h = {fmt_number(r.h)} s: max|dq| = {fmt_number(r.max_abs_dq)} rad, max|dq̇| = {fmt_number(r.max_abs_dqd)} rad/s"
                     + (f", max|dF| = {fmt_number(r.max_abs_dF_friction)} N of max|F| = {fmt_number(r.max_abs_F_friction_ref)} N"
                        if np.isfinite(r.max_abs_dF_friction) else "") + ".")
    if react is not None and len(react):
        top = react.loc[react.groupby("mechanism").relative.idxmax()]
        for r in top.itertuples(index=False):
            lines.append(f"- Largest reaction disagreement, {_mech(r.mechanism)} ({r.variant}): {r.quantity}, "
                         f"{r.solver}, h = {fmt_number(r.h)} s: {fmt_number(r.max_abs_diff)} N of {fmt_number(r.max_abs_inhouse)} N "
                         f"(relative {fmt_number(r.relative)}).")
    return lines


def _switched_law(agree: pd.DataFrame) -> list[str]:
    """Table and explanation for the sets with an on/off load: Exudyn's error against h next to the
    in-house run that locates the switches."""
    sub = agree[_switched(agree)]
    if not len(sub):
        return []
    lines = []
    for (mech, variant), rows in sub.groupby(["mechanism", "variant"], sort=True):
        exu = rows[rows.engine == "exudyn"]
        table = []
        for r in rows.itertuples(index=False):
            table.append([r.solver, fmt_number(r.h), fmt_number(r.max_abs_dq), fmt_number(r.max_abs_dqd),
                          fmt_number(r.order_dq), fmt_number(r.order_dqd)])
        overall = []
        for solver in ("index3", "index2"):
            s = exu[exu.solver == solver].sort_values("h", ascending=False)
            if len(s) >= 2:
                p = np.log(s.max_abs_dq.iloc[0] / s.max_abs_dq.iloc[-1]) / np.log(s.h.iloc[0] / s.h.iloc[-1])
                overall.append(f"{solver} {fmt_number(p)} (successive orders {fmt_number(s.order_dq.min())} to "
                               f"{fmt_number(s.order_dq.max())})")
        inhouse = rows[rows.engine != "exudyn"]
        t_end = fmt_number(rows.t_end.iloc[0])
        lines += [f"{_mech(mech)} `{variant}` (on/off load law, {int(rows.reference_switches.iloc[0])} switches located by "
                  f"the reference in {t_end} s): Exudyn's error against h, and the in-house run that locates the "
                  f"switches (max over common samples every 0.01 s):", "",
                  md_table(["solver", "h [s]", "max|dq| [rad]", "max|dq̇| [rad/s]", "order q", "order q̇"], table,
                           [False] + [True] * 5), ""]
        lines += ["Exudyn evaluates the on/off force at the states of its steps, so each switch is taken at a step "
                  "boundary instead of its instant: a force jump F applied up to one step early or late changes the "
                  "momentum by up to F h per switch, an O(h) error whose size depends on where the switch falls "
                  "inside the step. The error is therefore first order at best and erratic against h: overall order "
                  "from the largest to the smallest h " + ", ".join(overall) + ". "
                  + (f"The in-house run with located switches ({inhouse.solver.iloc[0]}) is at max|dq| = "
                     f"{fmt_number(inhouse.max_abs_dq.iloc[0])} rad." if len(inhouse) else ""), ""]
    return lines


def section(ctx: ReportContext) -> list[str]:
    lines = ["## In-house vs Exudyn", ""]
    agree = ctx.table("exudyn_agreement")
    if agree is None or not len(agree):
        return lines + ["The cross-validation tables are missing: run the pipeline (`python -m study reproduce`).", ""]
    timing = ctx.table("exudyn_agreement_timing")
    react = ctx.table("exudyn_reactions")
    lines += [
        "Every mechanism is built a second time in Exudyn by one translator (`study/exudyn_models`) from its "
        "joint-level description and parameter file, never from the in-house equations, and solved with fixed steps by generalized-alpha with "
        "index-3 constraints (`index3`) and by Newmark/trapezoidal with index-2 constraints (`index2`). "
        "Friction is the regularized law −(F + μ|N|) tanh(v/ε) with the same ε on both sides, N read from "
        "Exudyn's joint reaction inside a user function. Each run is compared with an in-house high-accuracy "
        "reference (DOP853, rtol 1e-12, projection) on common samples every 0.01 s; ‘order’ is log(e(h')/e(h))/"
        "log(h'/h) against the next larger step h' of the same solver. The last row of each set is an in-house "
        "method for comparison: RK45 at rtol 1e-8, or fixed-step RK4 at Exudyn's largest step where adaptive "
        "steps straddle a smooth law's ramps (those failed the perturbation check). CPU seconds are machine-dependent "
        "(from `timing/exudyn_agreement_timing.csv`).", "",
    ]
    header = ["mechanism", "variant", "friction", "t_end [s]", "solver", "h [s]", "max|dq| [rad]",
              "max|dq̇| [rad/s]", "max|dF| [N]", "max|dN| [N]", "order q", "order q̇", "order F", "order N",
              "CPU [s]", "CPU in-house ref [s]"]
    lines += [md_table(header, _agreement_rows(agree, timing), [False] * 3 + [True] * 13), ""]
    lines += ["Observed orders (Exudyn, every set without an on/off load):", ""] + _order_summary(agree) + [""]
    lines += _switched_law(agree)
    lines += ["Disagreements and limits (numbers from the tables):", ""] + _disagreements(agree, react) + [""]
    notes = _report_notes(ctx)
    if notes:
        lines += [notes, ""]
    if (agree.engine == "exudyn").any():
        lines += [ctx.figure(convergence_figure(agree), "cross_validation_convergence",
                             "max|dq| of Exudyn vs step h, both solvers, all variants, slope-2 guide"), ""]
    else:
        lines += ["No Exudyn runs in `exudyn_agreement`: the convergence figure is not drawn.", ""]
    time_series, reaction_sets = _report_choices(ctx)
    for key in time_series:
        loaded = _load_set(ctx, key)
        if loaded is None:
            lines += [f"Runs of `{key}` are missing; its figures are not drawn.", ""]
            continue
        ref, runs = loaded
        mech, variant = ref.meta["mechanism"], ref.meta["variant"]
        stem = key.replace("/", "_")
        lines += [ctx.figure(differences_figure(ref, runs, mech, variant), f"cross_validation_{stem}_differences",
                             f"{_mech(mech)} {variant}: |Exudyn - reference| over time"), ""]
        lines += [ctx.figure(forces_figure(ref, runs, mech, variant), f"cross_validation_{stem}_forces",
                             f"{_mech(mech)} {variant}: friction and normal force, Exudyn and in-house"), ""]
    for key in reaction_sets:
        loaded = _load_set(ctx, key)
        if loaded is None:
            lines += [f"Runs of `{key}` are missing; its reaction figure is not drawn.", ""]
            continue
        ref, runs = loaded
        stem = "cross_validation_reactions" + ("" if key == reaction_sets[0] else "_" + key.replace("/", "_"))
        lines += [ctx.figure(reactions_figure(ref, runs, ref.meta["mechanism"], ref.meta["variant"]), stem,
                             f"frictionless {_mech(ref.meta['mechanism'])}: joint reactions, Exudyn and in-house"), ""]
    if react is not None and len(react):
        finest = react.loc[react.groupby(["mechanism", "variant", "solver", "quantity"]).h.idxmin()]
        rows = [[_mech(r.mechanism), r.variant, r.solver, fmt_number(r.h), r.quantity, fmt_number(r.max_abs_diff),
                 fmt_number(r.max_abs_inhouse), fmt_number(r.relative), fmt_number(r.order)] for r in finest.itertuples(index=False)]
        lines += ["Joint reactions of the frictionless runs at the finest step (all steps in "
                  "`tables/exudyn_reactions.csv`; revolute joints: global force on the distal body, in-house "
                  "value from the bodies' Newton equations with the in-house accelerations and multipliers):", "",
                  md_table(["mechanism", "variant", "solver", "h [s]", "quantity", "max|diff| [N]",
                            "max|in-house| [N]", "relative", "order"], rows, [False] * 3 + [True, False] + [True] * 4),
                  ""]
    return lines
