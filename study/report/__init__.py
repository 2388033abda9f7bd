"""The automated report, built from saved results only: it never runs a simulation.

:func:`build_report` reads the tables in ``reports/tables`` and the saved runs of the
sliding-mode study (:mod:`study.studies.sliding_mode`) and writes

- ``reports/figures/*.png`` and ``*.svg``: constraint violation per integrator setting (paper 001's
  H.6, H.8, H.9), trajectories with differences from the reference, a max|Phi| heatmap;
- ``reports/index.md``: the report, readable on a code host;
- ``reports/report.html``: the same text as one self-contained page (figures as base64 PNG);
- ``reports/manifest.json``: package versions, git commit, platform, and every input and output
  file with its SHA-256.

Every number in the text is read from a saved file. If ``sliding_mode_runs.csv`` or
``sliding_mode_claims.csv`` is missing, they are derived from the saved runs with the study's own
:func:`~study.studies.sliding_mode.summarize` and :func:`~study.studies.sliding_mode.claims`, at the
study's precision, and the report says so. Iteration is sorted or follows the study's fixed case
order, floats have fixed formats and nothing carries a date, so the same inputs give the same files.
"""

from __future__ import annotations

import hashlib
import io
import json
import platform
import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from study.report import figures
from study.report.render import demote_headings, markdown_to_html, md_table, png_data_uri
from study.results import SimulationResult, package_versions
from study.studies import sliding_mode as sm

__all__ = ["build_report", "find_runs_folder", "load_sliding_mode_runs", "saved_run_stem"]

REFERENCE_KEY = ("reference", "reference")
# Integrator setting whose runs are compared with the reference in the trajectory figure.
TRAJECTORY_SETTING = "RK45 rtol=1e-8"
# A saved table and the saved runs agree when max|Phi| matches to the table's 4 significant digits.
TABLE_RTOL = 1e-3
FIGURE_PREFIXES = ("quick_return_", "sliding_mode_")
MAX_LISTED = 12  # file names listed in the data checks before "..."


# --- saved inputs ------------------------------------------------------------------------------
@dataclass
class SavedTable:
    """A CSV table as text (exactly the saved digits, for display) and as values (for arithmetic)."""

    name: str
    text: pd.DataFrame
    values: pd.DataFrame
    path: Path | None  # None when derived from the saved runs
    note: str = ""


@dataclass
class SlidingModeRuns:
    """The saved runs of the sliding-mode study found in the cache.

    ``ignored`` lists saved files in the folder that belong to no current case (stale inputs).
    """

    folder: Path | None
    searched: list[Path]
    settings: list[str]
    methods: list[str]
    results: dict[tuple[str, str], SimulationResult] = field(default_factory=dict)
    paths: dict[tuple[str, str], Path] = field(default_factory=dict)
    missing: list[tuple[str, str]] = field(default_factory=list)
    ignored: list[str] = field(default_factory=list)

    @property
    def reference(self) -> SimulationResult | None:
        return self.results.get(REFERENCE_KEY)

    def at(self, setting: str) -> dict[str, SimulationResult]:
        """method -> result at one integrator setting, in the study's method order."""
        return {m: self.results[(setting, m)] for m in self.methods if (setting, m) in self.results}


def _table_from_text(name: str, text: str, path: Path | None, note: str = "") -> SavedTable:
    shown = pd.read_csv(io.StringIO(text), dtype=str, keep_default_na=False)
    return SavedTable(name, shown, pd.read_csv(io.StringIO(text)), path, note)


def _read_table(path: Path) -> SavedTable | None:
    return _table_from_text(path.name, path.read_text(encoding="utf-8"), path) if path.exists() else None


def _study_cases() -> list[tuple[str, str, dict]]:
    """The study's cases and its reference run, in the study's own (fixed) order."""
    return [*sm.cases(), (*REFERENCE_KEY, sm.reference_options())]


def _study_order() -> tuple[list[str], list[str]]:
    """Integrator settings and methods in the study's order (the reference excluded)."""
    settings, methods = [], []
    for setting, method, _ in sm.cases():
        settings += [setting] if setting not in settings else []
        methods += [method] if method not in methods else []
    return settings, methods


def saved_run_stem(setting: str, method: str, options: dict) -> str:
    """The file name the study saves a case under (see :func:`study.studies.sliding_mode.run_name`)."""
    return sm.run_name(setting, method, options, sm.T_END)


def find_runs_folder(cache_dir: Path) -> tuple[Path | None, list[Path]]:
    """Where ``python -m study sliding-mode`` saves its runs: ``<cache>/results/sliding_mode``.

    Returns that folder if it holds any run (else None) and the folders searched.
    """
    folder = cache_dir / "results" / "sliding_mode"
    return (folder if folder.is_dir() and any(folder.glob("*.json")) else None), [folder]


def load_sliding_mode_runs(cache_dir: Path) -> SlidingModeRuns:
    """Load the saved run of every case of the study (and of the reference) that exists.

    A case's run is the file named by :func:`saved_run_stem` (its name hashes the case's inputs).
    """
    settings, methods = _study_order()
    folder, searched = find_runs_folder(cache_dir)
    runs = SlidingModeRuns(folder, searched, settings, methods)
    if folder is None:
        return runs
    stems = sorted(p.stem for p in folder.glob("*.json") if p.with_suffix(".csv").exists())
    used = set()
    for setting, method, options in _study_cases():
        key, chosen = (setting, method), saved_run_stem(setting, method, options)
        if chosen not in stems:
            runs.missing.append(key)
            continue
        runs.results[key] = SimulationResult.load(folder / chosen)
        runs.paths[key] = folder / chosen
        used.add(chosen)
    runs.ignored = [s for s in stems if s not in used]
    return runs


def _sliding_mode_tables(tables_dir: Path, runs: SlidingModeRuns) -> tuple[SavedTable | None, SavedTable | None]:
    """The study's two tables: read from ``tables_dir`` or, if missing, derived from the saved runs."""
    runs_table = _read_table(tables_dir / "sliding_mode_runs.csv")
    claims_table = _read_table(tables_dir / "sliding_mode_claims.csv")
    full = None
    can_derive = runs.reference is not None and len(runs.results) > 1
    if runs_table is None and can_derive:
        full = sm.summarize({k: v for k, v in runs.paths.items()})
        runs_table = _table_from_text(
            "sliding_mode_runs.csv", full.to_csv(index=False, float_format="%.4g"), None,
            "derived at report time from the saved runs with `study.studies.sliding_mode.summarize` "
            "(`tables/sliding_mode_runs.csv` was not found)")
    if claims_table is None and runs_table is not None:
        source = full if full is not None else runs_table.values
        try:
            claims_text = sm.claims(source).to_csv(index=False, float_format="%.4g")
        except KeyError as exc:  # a setting without 'none' or 'baumgarte' runs
            claims_text = None
            runs_table.note += f"; the claims could not be derived (no {exc} run at some setting)"
        if claims_text is not None:
            claims_table = _table_from_text(
                "sliding_mode_claims.csv", claims_text, None,
                "derived at report time with `study.studies.sliding_mode.claims` "
                "(`tables/sliding_mode_claims.csv` was not found)")
    return runs_table, claims_table


# --- formatting helpers ------------------------------------------------------------------------
def _ordered(frame: pd.DataFrame, settings: list[str], methods: list[str] | None = None) -> pd.DataFrame:
    """Rows in the study's order (unknown settings/methods last, sorted)."""
    rank_s = {s: i for i, s in enumerate(settings)}
    keys = [frame["integrator_setting"].map(lambda s: (rank_s.get(s, len(rank_s)), s))]
    if methods is not None and "method" in frame:
        rank_m = {m: i for i, m in enumerate(methods)}
        keys.append(frame["method"].map(lambda m: (rank_m.get(m, len(rank_m)), m)))
    order = sorted(range(len(frame)), key=lambda i: tuple(k.iloc[i] for k in keys))
    return frame.iloc[order].reset_index(drop=True)


def _verdict(text: str) -> str:
    return {"True": "holds", "False": "fails"}.get(text, text)


def _frame_table(frame: pd.DataFrame, numeric: pd.DataFrame | None = None, verdicts: bool = False) -> str:
    """Markdown table of a text frame; numeric columns of ``numeric`` are right-aligned."""
    numeric = frame if numeric is None else numeric
    right = [pd.api.types.is_numeric_dtype(numeric[c]) and not pd.api.types.is_bool_dtype(numeric[c])
             for c in frame.columns]
    rows = [[_verdict(v) if verdicts else v for v in row] for row in frame.itertuples(index=False)]
    return md_table(list(frame.columns), rows, right)


def _fmt(x: float) -> str:
    return f"{x:.3g}"


def _slug(setting: str) -> str:
    return re.sub(r"[^A-Za-z0-9.+-]+", "_", setting.replace("=", "")).strip("_")


def _meta_values(results: list[SimulationResult], key: str) -> list:
    return sorted({json.dumps(r.meta.get(key)) for r in results})


# --- figures -----------------------------------------------------------------------------------
def _make_figures(runs: SlidingModeRuns, runs_table: SavedTable | None, folder: Path) -> dict[str, list[tuple[str, str]]]:
    """Draw every figure; returns section -> [(caption, path relative to reports/)]."""
    out: dict[str, list[tuple[str, str]]] = {"heatmap": [], "phi": [], "trajectories": []}
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
        png = figures.save_figure(fig, folder, "sliding_mode_max_abs_phi_heatmap")
        out["heatmap"].append(("max |Φ| of every run of the sliding-mode study (from sliding_mode_runs.csv)",
                               f"figures/{png.name}"))
    for setting in runs.settings:
        at = runs.at(setting)
        if not at:
            continue
        for quantity, what in (("phi", "max_i |Φ_i(t)|"), ("phidot", "max_i |Φ̇_i(t)|")):
            fig = figures.constraint_violation_figure(at, setting, quantity)
            stem = ("quick_return_constraint_violation_" if quantity == "phi"
                    else "quick_return_velocity_constraint_violation_") + _slug(setting)
            png = figures.save_figure(fig, folder, stem)
            out["phi"].append((f"{what}, {setting}, every method", f"figures/{png.name}"))
    if runs.reference is not None:
        setting = TRAJECTORY_SETTING if runs.at(TRAJECTORY_SETTING) else next(
            (s for s in runs.settings if runs.at(s)), None)
        if setting is not None:
            fig = figures.trajectories_figure(runs.reference, runs.at(setting), setting)
            png = figures.save_figure(fig, folder, "quick_return_trajectories")
            out["trajectories"].append((f"q(t) of the reference run and |Δq| of every method at {setting}",
                                        f"figures/{png.name}"))
    return out


# --- sections ----------------------------------------------------------------------------------
def _initial_section(table: SavedTable | None) -> list[str]:
    lines = ["## Initial conditions", ""]
    if table is None:
        return lines + ["`tables/initial_conditions.csv` is missing; `python -m study initial` writes it.", ""]
    lines += ["From [`tables/initial_conditions.csv`](tables/initial_conditions.csv): the printed initial "
              "conditions of each mechanism, the consistent ones found by Newton-Raphson from the printed "
              "independent coordinates, and the constraint residuals of both.", ""]
    t = table.text
    cols = {"mechanism", "max_abs_phi_printed", "max_abs_phi_consistent", "max_abs_phidot_printed",
            "max_abs_phidot_consistent"}
    if cols <= set(t.columns):
        for mech in sorted(set(t["mechanism"])):
            row = t[t["mechanism"] == mech].iloc[0]
            lines.append(f"- `{mech}`: at the printed q(0), max|Φ| = {row['max_abs_phi_printed']} and "
                         f"max|Φ̇| = {row['max_abs_phidot_printed']}; at the consistent q(0), "
                         f"max|Φ| = {row['max_abs_phi_consistent']} and "
                         f"max|Φ̇| = {row['max_abs_phidot_consistent']}.")
        lines.append("")
    return lines + [_frame_table(t, table.values), ""]


def _errata_section(tables_dir: Path) -> list[str]:
    lines = ["## Errata", ""]
    md, csv = tables_dir / "errata.md", tables_dir / "errata.csv"
    if md.exists():
        lines += [f"Embedded from [`tables/errata.md`](tables/errata.md)"
                  + (" (same rows as [`tables/errata.csv`](tables/errata.csv))." if csv.exists() else "."), ""]
        lines += [demote_headings(md.read_text(encoding="utf-8").strip(), 2), ""]
    elif csv.exists():
        lines += ["`tables/errata.md` is missing; the table exists as [`tables/errata.csv`](tables/errata.csv).", ""]
    else:
        lines += ["The errata table is missing (`tables/errata.md` not found); `python -m study errata` writes it.", ""]
    return lines


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
                         _fmt(r["ratio_lo"]), _fmt(r["ratio_hi"])] for r in rows],
                       [False, True, True, True, True, True, True, True]), ""]
    lo = min(r["ratio_lo"] for r in rows)
    hi = max(r["ratio_hi"] for r in rows)
    method_factor = max(hi, 1.0 / lo)
    lines.append(f"Over all {len(rows)} pairs the ratio lies between **{_fmt(lo)}** and **{_fmt(hi)}**: "
                 + (f"at a given setting and equal gains the two methods reach the same constraint error to "
                    f"within a factor of {_fmt(method_factor)} (the study's 'about' means within a factor of "
                    f"{sm.DECADE:g})." if method_factor <= sm.DECADE else
                    f"at equal gains the two methods differ by up to a factor of {_fmt(method_factor)}, more "
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
                      f"of {_fmt(values[i_hi] / values[i_lo])}.")
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
            f"A {_fmt(levels['baumgarte'] / levels['sliding_mode'])}-fold advantage of sliding mode over "
            f"Baumgarte (the claimed {levels['sliding_mode']:g} against {levels['baumgarte']:g}) therefore "
            "cannot come from the method at equal gains.", ""]


def _sliding_mode_section(runs: SlidingModeRuns, runs_table: SavedTable | None, claims: SavedTable | None,
                          figs: dict[str, list[tuple[str, str]]]) -> list[str]:
    lines = ["## Constraint drift: the sliding-mode claims of paper 001", ""]
    levels = sm.CLAIMED_LEVEL
    lines += [f"Paper 001 (sec. 4, figures H.6, H.8 and H.9) claims that over long runs of the quick-return "
              f"mechanism the constraint error stays about {levels['sliding_mode']:g} with sliding-mode "
              f"stabilization, about {levels['baumgarte']:g} with Baumgarte's, and grows without "
              "stabilization. It names neither integrator, tolerance, step nor gains, so the study "
              "(`study.studies.sliding_mode`) repeats every method and sgn approximation over a sweep of "
              "integrator settings and compares each run with a high-accuracy reference run.", ""]
    if runs.folder is None:
        searched = " or ".join(f"`{p}`" for p in runs.searched)
        lines += [f"**No saved runs found** (looked in {searched}); `python -m study sliding-mode` makes them. "
                  "Figures are skipped.", ""]
    else:
        expected = len(runs.results) + len(runs.missing)
        lines += [f"Saved runs: {len(runs.results)} of {expected} found in `{_display_path(runs.folder, Path.cwd())}`"
                  + (" (reference included)." if runs.reference is not None else "; **the reference run is missing**.")]
        if runs.reference is not None:
            ref = runs.reference.meta
            lines[-1] += (f" Reference: {ref.get('integrator')} rtol={ref.get('rtol')} atol={ref.get('atol')}, "
                          f"stabilization {ref.get('stabilization')}, t_end = {ref.get('t_end')} s, "
                          f"samples every {ref.get('output_step')} s.")
        lines.append("")
    if claims is None:
        lines += ["The claims table is missing and could not be derived from saved runs.", ""]
    else:
        lines += [f"Verdict rules (the study's): 'about L' holds when L/{sm.DECADE:g} ≤ max|Φ| ≤ "
                  f"{sm.DECADE:g}·L (the paper reads its levels off a log plot); 'grows' holds when max|Φ| "
                  f"over the last quarter of the run exceeds that over the first quarter by more than "
                  f"{sm.GROWTH_FACTOR:g} times.", ""]
        if claims.note:
            lines += [f"Note: this table was {claims.note}.", ""]
        else:
            lines += ["From [`tables/sliding_mode_claims.csv`](tables/sliding_mode_claims.csv):", ""]
        ordered_text = _ordered(claims.text, runs.settings)
        ordered_vals = _ordered(claims.values, runs.settings)
        lines += ["### Verdicts per integrator setting", "", _frame_table(ordered_text, ordered_vals, True), ""]
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
        for caption, path in figs["heatmap"] + figs["phi"] + figs["trajectories"]:
            lines += [f"![{caption}]({path})", ""]
    if runs_table is not None:
        lines += ["### All runs", ""]
        lines += [f"Note: this table was {runs_table.note}." if runs_table.note and runs_table.path is None
                  else "From [`tables/sliding_mode_runs.csv`](tables/sliding_mode_runs.csv)."
                  + (f" {runs_table.note}" if runs_table.note else ""), ""]
        lines += [_frame_table(_ordered(runs_table.text, runs.settings, runs.methods),
                               _ordered(runs_table.values, runs.settings, runs.methods)), ""]
    lines += _data_checks(runs, runs_table)
    return lines


def _data_checks(runs: SlidingModeRuns, runs_table: SavedTable | None) -> list[str]:
    lines = ["### Checks of the saved data", ""]
    if runs.missing:
        lines.append("- Missing runs: " + ", ".join(f"{s} / {m}" for s, m in runs.missing) + ".")
    if runs.ignored:
        shown = runs.ignored[:MAX_LISTED]
        lines.append(f"- {len(runs.ignored)} saved runs in the folder are not used (stale names or not in the "
                     "study's case list): " + ", ".join(f"`{n}`" for n in shown)
                     + (", ..." if len(runs.ignored) > len(shown) else "") + ".")
    horizons = _meta_values(list(runs.results.values()), "t_end")
    if len(horizons) > 1:
        lines.append(f"- The runs do not share one horizon: t_end = {', '.join(horizons)} s.")
    if runs_table is not None and runs_table.path is not None and runs.results:
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


def _other_tables_section(tables_dir: Path, shown: set[str]) -> list[str]:
    lines = ["## All tables", ""]
    files = sorted(tables_dir.glob("*.csv")) if tables_dir.is_dir() else []
    if not files:
        return lines + [f"No tables found in `{tables_dir.name}/`.", ""]
    rows = []
    for path in files:
        frame = pd.read_csv(path, dtype=str, keep_default_na=False)
        rows.append([f"[`tables/{path.name}`](tables/{path.name})", str(len(frame)), str(len(frame.columns)),
                     "above" if path.name in shown else "linked only"])
    return lines + [md_table(["file", "rows", "columns", "shown"], rows, [False, True, True, False]), ""]


def _provenance_section(manifest: dict) -> list[str]:
    rows = [[k, v] for k, v in sorted(manifest["package_versions"].items())]
    return ["## Provenance", "",
            f"Git commit `{manifest['git_commit']}` (uncommitted changes are not detected); "
            f"{len(manifest['inputs'])} input files with their SHA-256 are listed in "
            "[`manifest.json`](manifest.json).", "",
            md_table(["package", "version"], rows), ""]


# --- manifest ----------------------------------------------------------------------------------
def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _git_commit(where: Path) -> str:
    try:
        proc = subprocess.run(["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True,
                              timeout=10, check=False)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return proc.stdout.strip() if proc.returncode == 0 and proc.stdout.strip() else "unknown"


def _display_path(path: Path, root: Path) -> str:
    path = path.resolve()
    try:
        return path.relative_to(root.resolve()).as_posix()
    except ValueError:
        return path.as_posix()


def _file_list(paths: list[Path], root: Path) -> list[dict]:
    unique = sorted({p.resolve() for p in paths})
    return [{"path": _display_path(p, root), "sha256": _sha256(p)} for p in unique]


# --- entry point -------------------------------------------------------------------------------
def build_report(reports_dir: Path, cache_dir: Path) -> Path:
    """Write the report from saved results only; returns the path of ``index.md``.

    Parameters
    ----------
    reports_dir : the report folder; tables are read from ``<reports_dir>/tables``, and
        ``figures/``, ``index.md``, ``report.html`` and ``manifest.json`` are written into it.
    cache_dir : the cache root holding the saved runs (``<cache>/results/sliding_mode``).
    """
    reports_dir, cache_dir = Path(reports_dir), Path(cache_dir)
    if reports_dir.exists() and not reports_dir.is_dir():
        raise ValueError(f"reports_dir = {reports_dir} exists and is not a folder")
    tables_dir, figures_dir = reports_dir / "tables", reports_dir / "figures"
    root = reports_dir.resolve().parent

    runs = load_sliding_mode_runs(cache_dir)
    initial = _read_table(tables_dir / "initial_conditions.csv")
    runs_table, claims_table = _sliding_mode_tables(tables_dir, runs)

    figures_dir.mkdir(parents=True, exist_ok=True)
    figs = _make_figures(runs, runs_table, figures_dir)
    written_figures = {Path(p).name for items in figs.values() for _, p in items}
    written_figures |= {Path(n).with_suffix(".svg").name for n in written_figures}
    for stale in sorted(figures_dir.iterdir()):
        if (stale.suffix in (".png", ".svg") and stale.name.startswith(FIGURE_PREFIXES)
                and stale.name not in written_figures):
            stale.unlink()

    inputs = [t.path for t in (initial, runs_table, claims_table) if t is not None and t.path is not None]
    inputs += [p for p in (tables_dir / "errata.md",) if p.exists()]
    inputs += [base.with_suffix(s) for base in runs.paths.values() for s in (".csv", ".json")]
    versions = package_versions()
    manifest = {
        "generator": "study.report.build_report",
        "git_commit": _git_commit(Path(__file__).resolve().parent),
        "platform": versions["platform"],
        "package_versions": {k: v for k, v in versions.items() if k != "platform"},
        "runs_folder": _display_path(runs.folder, root) if runs.folder is not None else None,
        "inputs": _file_list(inputs, root),
    }

    shown = {t.name for t in (initial, runs_table, claims_table) if t is not None and t.path is not None}
    lines = ["# Validation study: report", "",
             "Generated by `study.report.build_report` from saved results only: building it never runs a "
             "simulation. Every number below is read from a saved file (the tables in `tables/` and the "
             "saved runs); the inputs and their SHA-256 are listed in [`manifest.json`](manifest.json). "
             "The same content as one self-contained page is [`report.html`](report.html).", ""]
    lines += _initial_section(initial)
    lines += _errata_section(tables_dir)
    lines += _sliding_mode_section(runs, runs_table, claims_table, figs)
    lines += _other_tables_section(tables_dir, shown)
    lines += _provenance_section(manifest)
    markdown = "\n".join(lines).rstrip() + "\n"

    index = reports_dir / "index.md"
    index.write_text(markdown, encoding="utf-8")
    html_text = markdown_to_html(markdown, lambda src: png_data_uri(reports_dir / src),
                                 "Validation study: report")
    (reports_dir / "report.html").write_text(html_text, encoding="utf-8")

    outputs = [index, reports_dir / "report.html"]
    outputs += sorted(figures_dir / n for n in written_figures)
    manifest["outputs"] = _file_list(outputs, root)
    (reports_dir / "manifest.json").write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n",
                                                encoding="utf-8")
    return index
