"""The overview table that opens "Benchmarks beyond the papers": every benchmark in one layout, each run judged by
the benchmark's own criterion against the benchmark's own reference.

Columns: benchmark | reference (what it is, where it comes from) | criterion | engine | method, setting | error by
the criterion | verdict by the criterion | CPU [s]. Rows:

- IFToMM A01 (``a01_runs``, CPU from ``a01_timing``): every run; a run shorter than the horizon is not judged;
- IFToMM A02, N = 2 and N = 40 (``singular_four_bar_runs``, CPU from ``singular_four_bar_timing``): every run,
  with its ``a02_verdict``;
- Andrews' squeezer against the Test Set's published solution (``andrews_reference``, ``andrews_work_precision``,
  CPU from ``andrews_work_precision_timing``): the in-house reference and the finest setting of every series, by
  the Test Set's significant correct digits (it sets no pass limit);
- Exudyn's slider-crank test model (``exudyn_test_models``, ``exudyn_test_models_verdict``, CPU from
  ``exudyn_test_models_timing``): the in-house reference and the Exudyn runs, by the agreement rule of
  reference/benchmarks.toml [exudyn_slider_crank_agreement_factor];
- Exudyn's IFToMM four-bar test model: every N = 2 run of ``singular_four_bar_runs`` that reaches 10 s against the
  x_B0(10 s) the model prints (reference/benchmarks.toml [a02_published_x_b0_10s]), to half a unit of its last digit.

Every number comes from those tables or from reference/*.toml; never a run.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from study.reference_data import tolerance
from study.report.context import ReportContext
from study.report.render import fmt_int, fmt_number, md_table
from study.report.sections.andrews import with_cpu

HEADER = ["benchmark", "reference", "criterion", "engine", "method, setting", "error by the criterion",
          "verdict by the criterion", "CPU [s]"]
COLUMNS = ["benchmark", "reference", "criterion", "engine", "method", "error", "verdict", "cpu_s"]
ENGINE = {"inhouse": "in-house", "exudyn": "Exudyn"}
A01 = "IFToMM A01 simple pendulum"
ANDREWS = "A03 Andrews' squeezer"
SLIDER_CRANK = "Exudyn test model sliderCrankFloatingTest"
FOUR_BAR = "Exudyn test model fourBarMechanismIftomm (A02, N = 2)"
NO_LIMIT = "the Test Set sets no limit"
MATCHES = "matches the published {digits} digits"


def _a02(n: int) -> str:
    return f"IFToMM A02 N-four-bar, N = {n}"


def _with_timing(runs: pd.DataFrame, timing: pd.DataFrame | None, keys: list[str]) -> pd.DataFrame:
    """``runs`` with the ``cpu_s`` of its timing table (matched on ``keys``; NaN where a run has none)."""
    if timing is None:
        return runs.assign(cpu_s=np.nan)
    return runs.merge(timing[keys + ["cpu_s"]], on=keys, how="left")


def printed_digits(value: float) -> tuple[int, float]:
    """The significant digits of a published decimal as printed (its shortest repr), and half a unit of its last
    digit: the largest distance at which a value still rounds to it."""
    text = repr(float(value)).lstrip("-")
    if "e" in text or "." not in text:
        raise ValueError(f"{value!r}: expected a plain decimal fraction")
    whole, fraction = text.split(".")
    return len((whole + fraction).lstrip("0")), 0.5 * 10.0 ** -len(fraction)


def _a01_rows(ctx: ReportContext) -> list[dict]:
    runs = ctx.table("a01_runs")
    if runs is None:
        return []
    runs = _with_timing(runs.fillna({"error": ""}), ctx.table("a01_timing"), ["engine", "method", "setting"])
    high, low, horizon = (tolerance(k, table="benchmarks") for k in ("a01_high_precision", "a01_low_precision",
                                                                      "a01_horizon"))
    reference = ("the exact motion (Jacobi's elliptic sine, `study/reference_solutions.py`) of the pendulum of the "
                 "IFToMM A01 specification")
    criterion = (f"larger of max|x − x_ref|, max|y − y_ref| of P1 over {fmt_int(runs['output_steps'].max())} "
                 f"output steps of {horizon:g} s: ≤ {high:g} m high, ≤ {low:g} m low precision")
    rows = []
    for r in runs.itertuples(index=False):
        if r.a01_verdict == "stopped":
            error, verdict = "–", f"stopped ({r.error})"
        else:
            larger = "x" if r.x_max_error_m >= r.y_max_error_m else "y"
            error = (f"{fmt_number(max(r.x_max_error_m, r.y_max_error_m))} m ({larger})"
                     + (f" over {r.t_end_s:g} s" if r.t_end_s < horizon else ""))
            verdict = r.a01_verdict
        method = f"{r.method}, {r.setting}" if r.engine == "inhouse" else r.setting
        rows.append(dict(zip(COLUMNS, [A01, reference, criterion, ENGINE[r.engine], method, error, verdict,
                                       r.cpu_s])))
    return rows


def _singular_runs(ctx: ReportContext) -> pd.DataFrame | None:
    runs = ctx.table("singular_four_bar_runs")
    if runs is None:
        return None
    return _with_timing(runs, ctx.table("singular_four_bar_timing"), ["N", "engine", "method", "setting"])


def _a02_rows(runs: pd.DataFrame) -> list[dict]:
    high, low, rtol = (tolerance(k, table="benchmarks") for k in ("a02_high_precision", "a02_low_precision",
                                                                   "a02_reference_rtol"))
    reference = ("the exact motion of the parallelogram branch (its one-degree-of-freedom equation integrated at "
                 f"rtol {rtol:g}, `study/reference_solutions.py`) of the IFToMM A02 specification")
    rows = []
    for r in runs.sort_values("N", kind="stable").itertuples(index=False):   # N = 2, then N = 40
        criterion = (f"max|x_B0 − ref| and max|ẋ_B0 − ref| over every output sample of {r.t_end_s:g} s: "
                     f"≤ {high:g} (m, m/s) high, ≤ {low:g} low precision")
        if r.a02_verdict == "stopped":
            error = "–"
            where = f" at t = {fmt_number(r.stopped_at_s, 6)} s" if np.isfinite(r.stopped_at_s) else ""
            verdict = f"stopped{where} ({r.error})"
        else:
            error = f"x {fmt_number(r.x_B0_max_error_m)} m, ẋ {fmt_number(r.vx_B0_max_error_m_s)} m/s"
            verdict = r.a02_verdict
        rows.append(dict(zip(COLUMNS, [_a02(int(r.N)), reference, criterion, ENGINE[r.engine],
                                       f"{r.method}, {r.setting}", error, verdict, r.cpu_s])))
    return rows


def _andrews_method(r) -> str:
    setting = f"rtol={r.rtol:g}" if np.isfinite(r.rtol) else f"h={r.step:g}"
    if r.engine == "exudyn":
        return f"{r.integrator}, {setting}"
    return f"{r.method}, {r.integrator} {setting}" + (" (compiled)" if r.backend == "compiled" else "")


def _scd_cells(relative: float) -> tuple[str, str]:
    """Error and verdict by the Test Set's measure: scd = -log10 of the largest relative error."""
    return f"{fmt_number(relative)} (relative)", f"scd {fmt_number(-np.log10(relative))}; {NO_LIMIT}"


def _andrews_rows(ctx: ReportContext) -> list[dict]:
    ref, table = ctx.table("andrews_reference"), ctx.table("andrews_work_precision")
    if ref is None or table is None or "relative_error_published" not in table:
        return []
    table = with_cpu(table, ctx.table("andrews_work_precision_timing"))
    reference = ("the Test Set for IVP Solvers' published solution of problem andrews at t = 0.03 s (PSIDE on a Cray "
                 "C90, 16 digits; `reference/andrews_published.toml` [q_t003])")
    criterion = ("significant correct digits, scd = −log10 of the largest relative error max_i |q_i − q_i,pub| / "
                 "|q_i,pub| over the seven angles; the Test Set scores by scd and publishes no pass limit")
    angles = ref[ref["quantity"] == "angle"]
    own = next(table[table["group"] == "reference"].itertuples(index=False))
    rows = [dict(zip(COLUMNS, [ANDREWS, reference, criterion, "in-house", f"reference: {_andrews_method(own)}",
                               *_scd_cells(float(angles["relative_difference"].abs().max())), own.cpu_seconds]))]
    finest = [series["rtol" if series["rtol"].notna().any() else "step"].idxmin()   # each series' finest setting
              for _, series in table[table["group"] != "reference"].groupby(["engine", "backend", "method",
                                                                             "integrator"], sort=False)]
    for r in table.loc[finest].itertuples(index=False):
        rows.append(dict(zip(COLUMNS, [ANDREWS, reference, criterion, ENGINE[r.engine], _andrews_method(r),
                                       *_scd_cells(r.relative_error_published), r.cpu_seconds])))
    return rows


def _slider_crank_rows(ctx: ReportContext) -> list[dict]:
    table, verdict = ctx.table("exudyn_test_models"), ctx.table("exudyn_test_models_verdict")
    if table is None or verdict is None:
        return []
    table = _with_timing(table, ctx.table("exudyn_test_models_timing"), ["source"])
    v = verdict.iloc[0]
    factor = tolerance("exudyn_slider_crank_agreement_factor", table="benchmarks")
    run = table.loc[table["source"].str.startswith("published"), "source"].iloc[0]
    run = run.removeprefix("published (the test model: ").removesuffix(")")
    reference = (f"Σ|x_slider(0.3 s)| of the fixed- and the floating-frame case = "
                 f"{tolerance('exudyn_slider_crank_published', table='benchmarks')!r} m, as the model file "
                 f"(jgerstmayr/EXUDYN, pythonDev/TestModels/sliderCrankFloatingTest.py) publishes it from its own run "
                 f"({run})")
    criterion = (f"|Σ − published| ≤ {factor:g} × the published run's discretization error, estimated by "
                 f"Richardson's rule from Exudyn at h and h/2 ({fmt_number(v['published_run_error_estimate_m'])} m): "
                 f"≤ {fmt_number(v['bound_m'])} m (`reference/benchmarks.toml`)")
    rows = []
    for r in table.itertuples(index=False):
        if r.source.startswith("in-house"):
            engine, method = "in-house", r.source.removeprefix("in-house reference (").removesuffix(")")
            agrees = str(v["agrees"]) == "True"   # the saved verdict of the rule
        elif r.source.startswith("Exudyn"):
            engine, method = "Exudyn", r.source.removeprefix("Exudyn from the descriptions, ")
            agrees = abs(r.minus_published_m) <= v["bound_m"]
        else:   # the published value itself and the extrapolation: not runs
            continue
        rows.append(dict(zip(COLUMNS, [SLIDER_CRANK, reference, criterion, engine, method,
                                       f"{fmt_number(abs(r.minus_published_m))} m",
                                       f"{'agrees' if agrees else 'does not agree'}: "
                                       f"{'within' if agrees else 'beyond'} {fmt_number(v['bound_m'])} m",
                                       r.cpu_s])))
    return rows


def _four_bar_model_rows(runs: pd.DataFrame) -> list[dict]:
    published = tolerance("a02_published_x_b0_10s", table="benchmarks")
    digits, limit = printed_digits(published)
    reference = (f"x_B0(10 s) = {published!r} m for N = 2 ({digits} digits), as Exudyn's IFToMM four-bar test model "
                 "(jgerstmayr/EXUDYN, pythonDev/TestModels/fourBarMechanismIftomm.py) prints it")
    criterion = f"|x_B0(10 s) − {published!r} m| ≤ {limit:g} m, half a unit of its last printed digit"
    rows = []
    for r in runs[runs["x_B0_10s_minus_published_m"].notna()].itertuples(index=False):
        miss = abs(r.x_B0_10s_minus_published_m)
        verdict = (MATCHES.format(digits=digits) if miss <= limit
                   else f"misses the published {digits} digits by {fmt_number(miss)} m")
        rows.append(dict(zip(COLUMNS, [FOUR_BAR, reference, criterion, ENGINE[r.engine], f"{r.method}, {r.setting}",
                                       f"{fmt_number(miss)} m", verdict, r.cpu_s])))
    return rows


def rows(ctx: ReportContext) -> pd.DataFrame:
    """One row per judged run of every benchmark (columns ``COLUMNS``), in the order of the report's subsections."""
    singular = _singular_runs(ctx)
    out = _a01_rows(ctx)
    if singular is not None:
        out += _a02_rows(singular)
    out += _andrews_rows(ctx) + _slider_crank_rows(ctx)
    if singular is not None and "x_B0_10s_minus_published_m" in singular:
        out += _four_bar_model_rows(singular)
    return pd.DataFrame(out, columns=COLUMNS)


def overview(ctx: ReportContext) -> list[str]:
    """The overview table and its reading note; nothing if no benchmark table is saved."""
    table = rows(ctx)
    if table.empty:
        return []
    limit = printed_digits(tolerance("a02_published_x_b0_10s", table="benchmarks"))[1]
    cells, previous = [], None
    for r in table.itertuples(index=False):
        first = r.benchmark != previous   # reference and criterion once per benchmark
        cells.append([r.benchmark, r.reference if first else "", r.criterion if first else "", r.engine, r.method,
                      r.error, f"**{r.verdict}**", fmt_number(r.cpu_s)])
        previous = r.benchmark
    return ["### Overview: every benchmark by its own criterion", "",
            "One row per run; for Andrews' squeezer the in-house reference and the finest setting of every series "
            "(all settings: its subsection). Reference and criterion are named in the first row of each benchmark. "
            "A01's Exudyn runs cover only part of the horizon, so the criterion does not judge them; the slider-crank "
            "model's CPU is that of its two cases together; CPU is process time on this machine (`timing/`). "
            "x_B0(10 s) is compared with fourBarMechanismIftomm's value at full precision (column "
            "x_B0_10s_minus_published_m of `singular_four_bar_runs`; x_B0_end_m keeps 6 digits, too few to decide "
            f"at {limit:g} m).", "",
            md_table(HEADER, cells, [False] * 7 + [True]), ""]
