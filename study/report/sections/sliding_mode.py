"""Report section: constraint drift and paper 001's sliding-mode claims (study ``sliding_mode``).

Reads the study's tables (``sliding_mode_runs``, ``sliding_mode_claims``) and its saved runs; draws
the max|Phi| heatmap, |Phi(t)| and |Phidot(t)| per integrator setting (001's H.6, H.8, H.9) and the
trajectories with their differences from the reference.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from study.report import figures
from study.report.context import ReportContext
from study.report.render import fmt_number, frame_table, md_table
from study.results import SimulationResult, package_versions
from study.studies import sliding_mode as sm

STUDY = "sliding_mode"
REFERENCE_KEY = ("reference", "reference")
# Integrator setting whose runs are compared with the reference in the trajectory figure.
TRAJECTORY_SETTING = "RK45 rtol=1e-8"
# A saved table and the saved runs agree when max|Phi| matches to 1e-3 relative (the tables keep
# 6 significant digits, so this only catches a table that belongs to other runs).
TABLE_RTOL = 1e-3


@dataclass
class SavedTable:
    """A CSV table as text (exactly the saved digits, for display) and as values (for arithmetic)."""

    name: str
    text: pd.DataFrame
    values: pd.DataFrame


@dataclass
class SlidingModeRuns:
    """The study's saved runs, keyed by (integrator setting, method), in the case list's order."""

    settings: list[str]
    methods: list[str]
    results: dict[tuple[str, str], SimulationResult] = field(default_factory=dict)
    missing: list[tuple[str, str]] = field(default_factory=list)

    @property
    def reference(self) -> SimulationResult | None:
        return self.results.get(REFERENCE_KEY)

    def at(self, setting: str) -> dict[str, SimulationResult]:
        """method -> result at one integrator setting, in the study's method order."""
        return {m: self.results[(setting, m)] for m in self.methods if (setting, m) in self.results}


def load_runs(ctx: ReportContext) -> SlidingModeRuns:
    """Every saved run of the study (missing ones listed)."""
    settings, methods = [], []
    runs = SlidingModeRuns(settings, methods)
    for case in ctx.cases(STUDY):
        key = (case.label("setting", "reference"), case.label("method", "reference"))
        if key != REFERENCE_KEY:
            settings += [key[0]] if key[0] not in settings else []
            methods += [key[1]] if key[1] not in methods else []
        if ctx.has(case):
            runs.results[key] = ctx.load(case)
        else:
            runs.missing.append(key)
    return runs


def _saved_table(ctx: ReportContext, name: str) -> SavedTable | None:
    values = ctx.table(name)
    return None if values is None else SavedTable(name, ctx.table(name, as_text=True), values)


def _ordered(frame: pd.DataFrame, settings: list[str], methods: list[str] | None = None) -> pd.DataFrame:
    """Rows in the study's order (unknown settings/methods last, sorted)."""
    rank_s = {s: i for i, s in enumerate(settings)}
    keys = [frame["integrator_setting"].map(lambda s: (rank_s.get(s, len(rank_s)), s))]
    if methods is not None and "method" in frame:
        rank_m = {m: i for i, m in enumerate(methods)}
        keys.append(frame["method"].map(lambda m: (rank_m.get(m, len(rank_m)), m)))
    order = sorted(range(len(frame)), key=lambda i: tuple(k.iloc[i] for k in keys))
    return frame.iloc[order].reset_index(drop=True)





def _slug(setting: str) -> str:
    return re.sub(r"[^A-Za-z0-9.+-]+", "_", setting.replace("=", "")).strip("_")


def _meta_values(results: list[SimulationResult], key: str) -> list:
    return sorted({json.dumps(r.meta.get(key)) for r in results})


def _make_figures(ctx: ReportContext, runs: SlidingModeRuns, runs_table: SavedTable | None) -> dict[str, list[str]]:
    """Draw every figure; returns part -> [Markdown image lines]."""
    out: dict[str, list[str]] = {"heatmap": [], "phi": [], "trajectories": []}
    if runs_table is not None and len(runs_table.values):
        values = runs_table.values
        settings = [s for s in runs.settings if s in set(values["integrator_setting"])]
        settings += sorted(set(values["integrator_setting"]) - set(settings))
        methods = [m for m in runs.methods if m in set(values["method"])]
        methods += sorted(set(values["method"]) - set(methods))
        mech = figures.pretty_mechanism(runs.reference.meta) if runs.reference is not None else "quick-return"
        fig = figures.heatmap_figure(
            values, "max_abs_phi", settings, methods,
            f"{mech}: max |Φ| over the run, every stabilization method and integrator setting",
            "max |Φ| over the run [m] (log scale)", labels=runs_table.text,
            expected=set(runs.results) | set(runs.missing))
        out["heatmap"].append(ctx.figure(fig, "sliding_mode_max_abs_phi_heatmap",
                                         "max |Φ| of every run of the sliding-mode study (from sliding_mode_runs.csv)"))
    for setting in runs.settings:
        at = runs.at(setting)
        if not at:
            continue
        for quantity, what in (("phi", "max_i |Φ_i(t)|"), ("phidot", "max_i |Φ̇_i(t)|")):
            fig = figures.constraint_violation_figure(at, setting, quantity)
            stem = ("quick_return_constraint_violation_" if quantity == "phi"
                    else "quick_return_velocity_constraint_violation_") + _slug(setting)
            out["phi"].append(ctx.figure(fig, stem, f"{what}, {setting}, every method"))
    if runs.reference is not None:
        setting = TRAJECTORY_SETTING if runs.at(TRAJECTORY_SETTING) else next(
            (s for s in runs.settings if runs.at(s)), None)
        if setting is not None:
            fig = figures.trajectories_figure(runs.reference, runs.at(setting), setting)
            out["trajectories"].append(ctx.figure(
                fig, "quick_return_trajectories", f"q(t) of the reference run and |Δq| of every method at {setting}"))
    return out



# --- text ----------------------------------------------------------------------------------
def _settings_where(claims: pd.DataFrame, column: str) -> tuple[list[str], list[str]]:
    holds = [s for s, v in zip(claims["integrator_setting"], claims[column]) if bool(v)]
    fails = [s for s, v in zip(claims["integrator_setting"], claims[column]) if not bool(v)]
    return holds, fails


def _equal_gain_rows(runs: SlidingModeRuns, table: SavedTable) -> list[dict]:
    """Pairs of runs at one setting whose laws differ only by the switching term.

    A Baumgarte run (omega, d = 1) is paired with every sliding-mode run at the same integrator
    setting with Lambda = K = omega, as read from the runs' metadata; max|Phi| comes from the table.
    """
    text = {(s, m): v for s, m, v in zip(table.text["integrator_setting"], table.text["method"],
                                          table.text["max_abs_phi"])}
    rows = []
    for setting in runs.settings:
        at = runs.at(setting)
        for bm, br in at.items():
            if br.meta.get("stabilization") != "baumgarte" or br.meta.get("d") != 1 or (setting, bm) not in text:
                continue
            w = br.meta.get("omega")
            partners = [m for m, r in at.items() if r.meta.get("stabilization") == "sliding_mode"
                        and r.meta.get("Lambda") == w and r.meta.get("K") == w and (setting, m) in text]
            if not partners:
                continue
            bg = float(text[(setting, bm)])
            values = {m: float(text[(setting, m)]) for m in partners}
            lo, hi = min(values, key=values.get), max(values, key=values.get)
            rows.append({"setting": setting, "omega": w, "baumgarte": bm, "bg_text": text[(setting, bm)],
                         "n": len(partners), "lo_text": text[(setting, lo)], "hi_text": text[(setting, hi)],
                         "ratio_lo": values[lo] / bg, "ratio_hi": values[hi] / bg,
                         "partners": [runs.results[(setting, m)] for m in partners], "baumgarte_run": br})
    return rows


def _key_finding(runs: SlidingModeRuns, table: SavedTable) -> list[str]:
    lines = ["### Key finding: sliding mode against Baumgarte at equal gains", ""]
    rows = _equal_gain_rows(runs, table)
    if not rows:
        return lines + ["No Baumgarte and sliding-mode runs with equal gains (Λ = K = ω, d = 1) are saved at "
                        "the same setting, so the two cannot be compared here.", ""]
    lines += ["Each row pairs a Baumgarte run with the sliding-mode runs at the same integrator setting that "
              "have Λ = K = ω (gains read from the runs' metadata, d = 1); max|Φ| from `sliding_mode_runs.csv`, "
              "smallest and largest over the sgn approximations, and their ratio to Baumgarte's:", ""]
    lines += [md_table(["integrator_setting", "ω = Λ = K [1/s]", "Baumgarte max|Φ|", "sliding-mode runs",
                        "sliding-mode max|Φ| (min)", "(max)", "ratio min", "ratio max"],
                       [[r["setting"], f"{r['omega']:g}", r["bg_text"], str(r["n"]), r["lo_text"], r["hi_text"],
                         fmt_number(r["ratio_lo"]), fmt_number(r["ratio_hi"])] for r in rows],
                       [False, True, True, True, True, True, True, True]), ""]
    lo = min(r["ratio_lo"] for r in rows)
    hi = max(r["ratio_hi"] for r in rows)
    method_factor = max(hi, 1.0 / lo)
    lines.append(f"Over all {len(rows)} pairs the ratio lies between **{fmt_number(lo)}** and **{fmt_number(hi)}**: "
                 + (f"at a given setting and equal gains the two methods reach the same constraint error to "
                    f"within a factor of {fmt_number(method_factor)} (the study's 'about' means within a factor of "
                    f"{sm.DECADE:g})." if method_factor <= sm.DECADE else
                    f"at equal gains the two methods differ by up to a factor of {fmt_number(method_factor)}, more "
                    f"than the study's 'about' (a factor of {sm.DECADE:g})."))
    setting_factor = 1.0
    for w in sorted({r["omega"] for r in rows}):
        group = [r for r in rows if r["omega"] == w]
        if len(group) < 2:
            continue
        values = [float(r["bg_text"]) for r in group]
        i_lo, i_hi = int(np.argmin(values)), int(np.argmax(values))
        setting_factor = max(setting_factor, values[i_hi] / values[i_lo])
        lines[-1] += (f" With ω = {w:g}, Baumgarte's max|Φ| ranges over the settings from {group[i_lo]['bg_text']} "
                      f"({group[i_lo]['setting']}) to {group[i_hi]['bg_text']} ({group[i_hi]['setting']}), a factor "
                      f"of {fmt_number(values[i_hi] / values[i_lo])}.")
    if setting_factor > sm.DECADE * method_factor:
        lines[-1] += (" The level is set by the integrator and its tolerance (and by the gains) far more than by "
                      "the choice between the two methods.")
    lines.append("")
    return lines + _equivalence_paragraph(rows)


def _equivalence_paragraph(rows: list[dict]) -> list[str]:
    text = ("Why they agree: the sliding-mode law (001, eqs. 14-17) defines the surface s = Φ̇ + ΛΦ and "
            "imposes ṡ = -K s - k sgn(s), that is Φ̈ = -(Λ + K) Φ̇ - K Λ Φ - k sgn(s). Baumgarte imposes "
            "Φ̈ = -2 d ω Φ̇ - ω² Φ. With Λ = K = ω and d = 1 the linear parts are the same (2ω Φ̇ and ω² Φ), "
            "so the sliding-mode law is Baumgarte's plus the switching term -k sgn(s). Any difference "
            "between the two then comes from the gains (at equal Λ, K and ω only the switching gain k and "
            "the sgn approximation remain) and from how the integrator's step-size control reacts to that "
            "small extra term, not from a different way of stabilizing.")
    sliding = [r for row in rows for r in row["partners"]]
    gains = {k: _meta_values(sliding, k) for k in ("k", "width", "sgn")}
    shown = ", ".join(f"{k} = {' or '.join(v)}" for k, v in gains.items())
    levels = sm.CLAIMED_LEVEL
    return [text, "", f"Switching term of the paired sliding-mode runs (from their metadata): {shown}.", "",
            f"A {fmt_number(levels['baumgarte'] / levels['sliding_mode'])}-fold advantage of sliding mode over "
            f"Baumgarte (the claimed {levels['sliding_mode']:g} against {levels['baumgarte']:g}) therefore "
            "cannot come from the method at equal gains.", ""]


def _sliding_mode_section(runs: SlidingModeRuns, runs_table: SavedTable | None, claims: SavedTable | None,
                          figs: dict[str, list[str]]) -> list[str]:
    lines = ["## Constraint drift: the sliding-mode claims of paper 001", ""]
    levels = sm.CLAIMED_LEVEL
    lines += [f"Paper 001 (sec. 4, figures H.6, H.8 and H.9) claims that over long runs of the quick-return "
              f"mechanism the constraint error stays about {levels['sliding_mode']:g} with sliding-mode "
              f"stabilization, about {levels['baumgarte']:g} with Baumgarte's, and grows without "
              "stabilization. It names neither integrator, tolerance, step nor gains, so the study "
              "(`study.studies.sliding_mode`) repeats every method and sgn approximation over a sweep of "
              "integrator settings and compares each run with a high-accuracy reference run.", ""]
    if not runs.results:
        lines += ["**No saved runs found**; `python -m study run sliding_mode` makes them. Figures are skipped.", ""]
    else:
        expected = len(runs.results) + len(runs.missing)
        lines += [f"Saved runs: {len(runs.results)} of {expected} (cases in `reference/cases/sliding_mode.toml`)"
                  + (" (reference included)." if runs.reference is not None else "; **the reference run is missing**.")]
        if runs.reference is not None:
            ref = runs.reference.meta
            lines[-1] += (f" Reference: {ref.get('integrator')} rtol={ref.get('rtol')} atol={ref.get('atol')}, "
                          f"stabilization {ref.get('stabilization')}, t_end = {ref.get('t_end')} s, "
                          f"samples every {ref.get('output_step')} s.")
        lines.append("")
    if claims is None:
        lines += ["The claims table `tables/sliding_mode_claims.csv` is missing; `python -m study run` writes it.", ""]
    else:
        lines += [f"Verdict rules (the study's): 'about L' holds when L/{sm.DECADE:g} ≤ max|Φ| ≤ "
                  f"{sm.DECADE:g}·L (the paper reads its levels off a log plot); 'grows' holds when max|Φ| "
                  f"over the last quarter of the run exceeds that over the first quarter by more than "
                  f"{sm.GROWTH_FACTOR:g} times.", ""]
        lines += ["From [`tables/sliding_mode_claims.csv`](tables/sliding_mode_claims.csv):", ""]
        ordered_text = _ordered(claims.text, runs.settings)
        ordered_vals = _ordered(claims.values, runs.settings)
        lines += ["### Verdicts per integrator setting", "", frame_table(ordered_text, ordered_vals, True), "",
                  "The residuals and energy errors behind these verdicts reproduce to their decade (which is what the "
                  "verdicts use), except the LSODA rows, which are one host's values: LSODA changes its order and its "
                  "Adams/BDF method by heuristics that last bits decide (sliding mode sat, max|Φ(20 s)|: 1.1e-8 m on "
                  "one host, 2.5e-9 m on another). Section \"How far the numbers reproduce\" lists the rules.", ""]
        for column in [c for c in ordered_vals.columns if pd.api.types.is_bool_dtype(ordered_vals[c])]:
            holds, fails = _settings_where(ordered_vals, column)
            lines.append(f"- `{column}` holds at {len(holds)} of {len(ordered_vals)} settings"
                         + (f" ({', '.join(holds)})" if holds and fails else "") + ".")
        lines.append("")
    if runs_table is not None and runs.results:
        lines += _key_finding(runs, runs_table)
    if any(figs.values()):
        lines += ["### Figures", "",
                  "Each line is one saved run; exact zeros cannot be drawn on a log axis and show as gaps. "
                  "Baumgarte is the wide pale blue line; the sliding-mode variants (dashed) mostly lie on it.", ""]
        for image in figs["heatmap"] + figs["phi"] + figs["trajectories"]:
            lines += [image, ""]
    if runs_table is not None:
        lines += ["### All runs", ""]
        lines += ["From [`tables/sliding_mode_runs.csv`](tables/sliding_mode_runs.csv).", ""]
        lines += [frame_table(_ordered(runs_table.text, runs.settings, runs.methods),
                               _ordered(runs_table.values, runs.settings, runs.methods)), ""]
    lines += _data_checks(runs, runs_table)
    return lines


def _data_checks(runs: SlidingModeRuns, runs_table: SavedTable | None) -> list[str]:
    lines = ["### Checks of the saved data", ""]
    if runs.missing:
        lines.append("- Missing runs: " + ", ".join(f"{s} / {m}" for s, m in runs.missing) + ".")
    horizons = _meta_values(list(runs.results.values()), "t_end")
    if len(horizons) > 1:
        lines.append(f"- The runs do not share one horizon: t_end = {', '.join(horizons)} s.")
    if runs_table is not None and runs.results:
        values = runs_table.values
        listed = {(s, m) for s, m in zip(values["integrator_setting"], values["method"])}
        bad = []
        for s, m, v in zip(values["integrator_setting"], values["method"], values["max_abs_phi"]):
            if (s, m) in runs.results:
                saved = float(np.abs(runs.results[(s, m)].phi).max())
                if not np.isclose(saved, float(v), rtol=TABLE_RTOL, atol=0.0):
                    bad.append(f"{s} / {m} (table {v}, saved run {saved:.4g})")
        not_in_table = sorted(k for k in runs.results if k != REFERENCE_KEY and k not in listed)
        not_saved = sorted(k for k in listed if k not in runs.results)
        lines.append("- `sliding_mode_runs.csv` against the saved runs: "
                     + (f"max|Φ| differs for {len(bad)} runs: {'; '.join(bad)}." if bad
                        else f"max|Φ| agrees for every run in both (to {TABLE_RTOL:g} relative)."))
        if not_in_table:
            lines.append("- Saved runs missing from the table: " + ", ".join(f"{s} / {m}" for s, m in not_in_table) + ".")
        if not_saved:
            lines.append("- Table rows without a saved run: " + ", ".join(f"{s} / {m}" for s, m in not_saved) + ".")
    if runs.results:
        mine = package_versions()
        lines.append("- Package versions of the saved runs (from their metadata) against this report's environment:")
        lines.append("")
        rows = []
        for name in sorted(mine):
            if name == "platform":
                continue
            saved = sorted({str(r.meta.get("versions", {}).get(name, "not recorded")) for r in runs.results.values()})
            rows.append([name, ", ".join(saved), mine[name], "yes" if saved == [mine[name]] else "**no**"])
        lines += [md_table(["package", "saved runs", "report", "same"], rows), ""]
    return lines + [""] if lines[-1] != "" else lines


def section(ctx: ReportContext) -> list[str]:
    runs = load_runs(ctx)
    runs_table = _saved_table(ctx, "sliding_mode_runs")
    claims = _saved_table(ctx, "sliding_mode_claims")
    figs = _make_figures(ctx, runs, runs_table)
    return _sliding_mode_section(runs, runs_table, claims, figs)
