"""Report section that opens the report: the study's answers, one sentence per question, each with its number.

Every number is read from the saved tables (``tables/``) or the benchmark's (``benchmarks/``), as the sections
they link to read them; a question whose table is missing says so. The questions:

- how well each stabilization holds the constraints (``sliding_mode_runs``);
- which friction treatment reproduces paper 000 (``slider_crank_summary``);
- whether sliding mode beats Baumgarte at equal gains (``sliding_mode_claims``);
- in-house against Exudyn at equal accuracy and CPU (``exudyn_agreement``, ``benchmarks/ratio_inhouse_exudyn``);
- each benchmark by its own criterion (``a01_runs``, ``singular_four_bar_runs``, ``andrews_reference``,
  ``exudyn_test_models_verdict``);
- what the papers got wrong (``errata``, ``initial_conditions``).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import pandas as pd
from mdit_py_plugins.anchors.index import slugify

from study import mechanisms
from study.bench.settings import RATIO_LEVEL
from study.reference_data import tolerance
from study.report.context import ReportContext
from study.report.sections.benchmarks import FOLDER as BENCHMARKS_FOLDER
from study.report.sections.spatial import finding as spatial
from study.studies import sliding_mode as sm

TITLE = "Findings at a glance"
ANCHOR = slugify(TITLE)

# The headings the answers link to (each section's own title; a renamed heading breaks the link test).
DRIFT = "Constraint drift: the sliding-mode claims of paper 001"
KEY_FINDING = "Key finding: sliding mode against Baumgarte at equal gains"
FRICTION = "Slider-crank with Coulomb friction (paper 000)"
EXUDYN = "In-house vs Exudyn"
PERFORMANCE = "Performance: accuracy per CPU second"
BENCHMARKS = "Benchmarks beyond the papers"
CLAIMS = "Claims of the papers"
ERRATA = "Errata"
METHOD_NAMES = {"none": "no stabilization", "baumgarte": "Baumgarte", "sliding_mode": "sliding mode",
                "projection": "projection"}


def link(heading: str) -> str:
    """A Markdown link to a heading of the report (the same id in index.md on a code host and in report.html)."""
    return f"[{heading}](#{slugify(heading)})"


def _missing(*names: str) -> str:
    return "not computed: " + ", ".join(f"`{n}`" for n in names) + " missing"


def stabilization(ctx: ReportContext) -> str:
    runs = ctx.table("sliding_mode_runs")
    if runs is None:
        return _missing("sliding_mode_runs")
    base = runs["method"].str.split("/").str[0]
    parts = []
    for method, name in METHOD_NAMES.items():
        phi = runs.loc[base == method, "max_abs_phi"]
        if not phi.empty:
            parts.append(f"{name} {phi.min():.2g} to {phi.max():.2g} m")
    settings = runs["integrator_setting"].nunique()
    return (f"Largest constraint violation max|Φ| of the quick-return over 20 s, across {settings} integrator "
            f"settings: {'; '.join(parts)} (`sliding_mode_runs`; {link(DRIFT)}).")


def friction(ctx: ReportContext) -> str:
    summary = ctx.table("slider_crank_summary")
    if summary is None:
        return _missing("slider_crank_summary")
    seed = summary[(summary["variant"] == "seed") & (summary["initial"] == "consistent")
                   & (summary["resistance_reading"] == "holds")].set_index("treatment")
    if not {"exact", "regularized", "sign"} <= set(seed.index):
        return "not computed: `slider_crank_summary` lacks a seed run of each treatment"
    exact, reg, sign = (seed.loc[t] for t in ("exact", "regularized", "sign"))
    return (f"None reproduces paper 000's figures: with 000's data the exact Coulomb law sticks the slider at "
            f"t = {float(exact['stick_times']):.4g} s for the rest of the 20 s. The regularized law agrees with it "
            f"(friction force at 20 s {reg['friction_t20']:.4g} N against {exact['friction_t20']:.4g} N); 000's plain "
            f"sgn with RK4 chatters at the static limit ({sign['friction_t20']:.3g} N, dissipating "
            f"{sign['dissipated_energy']:.3g} J where the exact law dissipates {exact['dissipated_energy']:.2g} J) "
            f"(`slider_crank_summary`; {link(FRICTION)}).")


def sliding_mode(ctx: ReportContext) -> str:
    claims = ctx.table("sliding_mode_claims")
    if claims is None:
        return _missing("sliding_mode_claims")
    ratio = pd.concat([claims["sliding_mode_max_abs_phi_min"], claims["sliding_mode_max_abs_phi_max"]]) \
        / pd.concat([claims["baumgarte_max_abs_phi"]] * 2)
    held = int(claims["sliding_mode_below_baumgarte"].astype(bool).sum())
    implied = sm.CLAIMED_LEVEL["sliding_mode"] / sm.CLAIMED_LEVEL["baumgarte"]
    return (f"Not by the margin paper 001 implies: at equal gains sliding mode's max|Φ| is {ratio.min():.2g} to "
            f"{ratio.max():.2g} times Baumgarte's (below it at {held} of {len(claims)} integrator settings), where "
            f"001's levels imply {implied:g} (`sliding_mode_claims`; {link(KEY_FINDING)}).")


def exudyn(ctx: ReportContext) -> str:
    agreement = ctx.table("exudyn_agreement")
    path = ctx.reports_dir / BENCHMARKS_FOLDER / "ratio_inhouse_exudyn.csv"
    if agreement is None or not path.exists():
        return _missing("exudyn_agreement", f"{BENCHMARKS_FOLDER}/ratio_inhouse_exudyn")
    ctx.inputs.append(path)
    ratios = pd.read_csv(path)
    orders = agreement.loc[agreement["engine"] == "exudyn", ["mechanism", "variant", "order_dq"]].dropna()
    min_order = tolerance("min_order", table="cross_validation")
    low = orders[orders["order_dq"] < min_order]
    at = ratios[(ratios["comparison"] == "compiled / Exudyn tuned") & ratios["ratio_inhouse_over_exudyn"].notna()
                & np.isclose(ratios["level"], RATIO_LEVEL, rtol=1e-9, atol=0)]
    low_text = "" if low.empty else (
        f"; the {len(low)} below it are all of the "
        f"{' and '.join(sorted({f'{mechanisms.label(m)}, variant {v}' for m, v in zip(low['mechanism'], low['variant'])}))}"
        ", whose cutting force switches on and off between fixed steps")
    return (f"Exudyn's models, built from the same descriptions, converge to the in-house reference: "
            f"{len(orders) - len(low)} of {len(orders)} step halvings show order ≥ {min_order:g} in q{low_text} "
            f"(`exudyn_agreement`; {link(EXUDYN)}). At equal accuracy (max|Δq| ≤ {RATIO_LEVEL:g} rad) the compiled "
            f"in-house path needs {at['ratio_inhouse_over_exudyn'].min():.2g} to "
            f"{at['ratio_inhouse_over_exudyn'].max():.2g} of tuned Exudyn's CPU time on {len(at)} mechanisms "
            f"(`benchmarks/ratio_inhouse_exudyn`; {link(PERFORMANCE)}).")


def _counts(verdicts: pd.Series) -> str:
    counts = verdicts.value_counts()
    return ", ".join(f"{n} {v}" for v, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))


def benchmarks(ctx: ReportContext) -> str:
    a01, a02 = ctx.table("a01_runs"), ctx.table("singular_four_bar_runs")
    andrews, peer = ctx.table("andrews_reference"), ctx.table("exudyn_test_models_verdict")
    if a01 is None or a02 is None or andrews is None or peer is None:
        return _missing("a01_runs", "singular_four_bar_runs", "andrews_reference", "exudyn_test_models_verdict")
    inhouse = a01[a01["engine"] == "inhouse"]["a01_verdict"]
    a02_in = a02[a02["engine"] == "inhouse"]["a02_verdict"]
    a02_ex = a02[a02["engine"] == "exudyn"]["a02_verdict"]
    agrees = "agrees" if bool(peer["agrees"].astype(bool).all()) else "disagrees"
    bricard = ctx.table("exudyn_bricard_test_model_verdict")
    peer_bricard = "" if bricard is None else (
        f"; Exudyn's Bricard test model {'agrees' if bool(bricard['agrees'].astype(bool).all()) else 'disagrees'} "
        f"with its published value ({bricard['inhouse_minus_published'].abs().max():.2g}, bound "
        f"{bricard['bound'].max():.2g})")
    return (f"IFToMM A01 (2000 s): in-house runs {_counts(inhouse)}; IFToMM A02: "
            f"in-house {_counts(a02_in)}, Exudyn {_counts(a02_ex)}; Andrews' squeezer matches the Test Set's "
            f"published solution to {andrews['relative_difference'].abs().max():.2g} relative; Exudyn's "
            f"slider-crank test model {agrees} with its published value "
            f"({peer['inhouse_minus_published_m'].abs().max():.2g} m, bound {peer['bound_m'].max():.2g} m)"
            f"{peer_bricard} ({link(BENCHMARKS)}).")


def errata(ctx: ReportContext) -> str:
    table, initial = ctx.table("errata"), ctx.table("initial_conditions")
    if table is None or initial is None:
        return _missing("errata", "initial_conditions")
    papers = table["paper"].astype(str).str.zfill(3)
    wrong = [f"{int(((papers == p) & (table['verdict'] == 'wrong')).sum())} of {int((papers == p).sum())} printed "
             f"formulas of paper {p}" for p in ("000", "001")]
    phi = float(initial.loc[initial["mechanism"] == "slider_crank", "max_abs_phi_printed"].iloc[0])
    return (f"{wrong[0]} and {wrong[1]} are wrong ({link(ERRATA)}); 000's printed initial state misses its "
            f"constraints by max|Φ| = {phi:.3g} m, and 000's data leave the slider-crank at rest ({link(CLAIMS)}).")


QUESTIONS: tuple[tuple[str, Callable[[ReportContext], str]], ...] = (
    ("How well does each stabilization hold the constraints?", stabilization),
    ("Which friction treatment reproduces paper 000?", friction),
    ("Does sliding mode beat Baumgarte at equal gains?", sliding_mode),
    ("In-house against Exudyn, at equal accuracy and CPU?", exudyn),
    ("Each benchmark by its own criterion?", benchmarks),
    ("Spatial mechanisms: the heavy top, Bricard, joint friction, and sliding mode's energy?", spatial),
    ("What did the papers get wrong?", errata),
)


def section(ctx: ReportContext) -> list[str]:
    lines = [f"## {TITLE}", ""]
    for question, answer in QUESTIONS:
        lines += [f"- **{question}** {answer(ctx)}"]
    return lines + [""]
