"""Report section: the papers' claims, each with a verdict and the evidence it rests on.

Every verdict is computed here from the saved tables of the other studies (``errata``,
``initial_conditions``, ``sliding_mode_claims``, ``slider_crank_summary``, ``exudyn_agreement``);
a claim whose table is missing is listed as 'not checked'. The evidence cell names the table.
"""

from __future__ import annotations

import pandas as pd

from study.report.context import ReportContext
from study.report.render import md_table
from study.studies import sliding_mode as sm

# A printed initial state "satisfies the constraints" when max|Phi| is at the level of its printed
# digits: the papers print 4-5 significant digits of O(1..10) m lengths and O(1) rad angles,
# so a residual up to 1e-3 m is rounding; anything larger is an inconsistent state.
PRINTED_STATE_ROUNDING = 1e-3


def _fraction(values: pd.Series) -> tuple[int, int]:
    return int(values.astype(bool).sum()), len(values)


def _verdict(held: int, total: int) -> str:
    if total == 0:
        return "not checked"
    return "holds" if held == total else "fails" if held == 0 else f"partly ({held} of {total})"


def _errata_claims(errata: pd.DataFrame | None) -> list[list[str]]:
    rows = []
    for paper in ("000", "001"):
        claim = "the printed equations of motion are correct"
        if errata is None:
            rows.append([paper, claim, "not checked", "`errata` table missing"])
            continue
        mine = errata[errata["paper"].astype(str).str.zfill(3) == paper]
        counts = mine["verdict"].value_counts()
        wrong, total = int(counts.get("wrong", 0)), len(mine)
        rows.append([paper, claim, "holds" if wrong == 0 else f"fails ({wrong} wrong)",
                     f"{total} printed formulas: {int(counts.get('exact', 0))} exact, "
                     f"{int(counts.get('equivalent on the constraint manifold', 0))} equivalent on the constraint "
                     f"manifold, {wrong} wrong (`errata`)"])
    return rows


def _initial_claims(initial: pd.DataFrame | None) -> list[list[str]]:
    rows = []
    for paper, mech in (("000", "slider_crank"), ("001", "quick_return")):
        claim = "the printed initial state satisfies the constraints"
        if initial is None or mech not in set(initial["mechanism"]):
            rows.append([paper, claim, "not checked", "`initial_conditions` table missing"])
            continue
        phi = float(initial.loc[initial["mechanism"] == mech, "max_abs_phi_printed"].iloc[0])
        ok = phi <= PRINTED_STATE_ROUNDING
        rows.append([paper, claim, "holds" if ok else "fails",
                     f"max|Φ| at the printed q(0) = {phi:.4g} m (rounding of the printed digits allows "
                     f"{PRINTED_STATE_ROUNDING:g} m) (`initial_conditions`)"])
    return rows


def _sliding_mode_claims(claims: pd.DataFrame | None) -> list[list[str]]:
    items = [("none_grows", "without stabilization the constraint error grows over time"),
             ("baumgarte_about_1e-6", f"Baumgarte keeps max|Φ| about {sm.CLAIMED_LEVEL['baumgarte']:g}"),
             ("sliding_mode_about_1e-8", f"sliding mode keeps max|Φ| about {sm.CLAIMED_LEVEL['sliding_mode']:g}"),
             ("sliding_mode_below_baumgarte", "sliding mode keeps the constraints better than Baumgarte")]
    rows = []
    for column, claim in items:
        if claims is None or column not in claims:
            rows.append(["001", claim, "not checked", "`sliding_mode_claims` table missing"])
            continue
        held, total = _fraction(claims[column])
        where = ", ".join(s for s, v in zip(claims["integrator_setting"], claims[column]) if bool(v))
        evidence = f"holds at {held} of {total} integrator settings" + (f" ({where})" if 0 < held < total else "")
        if column == "sliding_mode_below_baumgarte":
            ratio = pd.concat([claims["sliding_mode_max_abs_phi_min"], claims["sliding_mode_max_abs_phi_max"]]) \
                / pd.concat([claims["baumgarte_max_abs_phi"]] * 2)
            claimed = sm.CLAIMED_LEVEL["sliding_mode"] / sm.CLAIMED_LEVEL["baumgarte"]
            evidence += (f"; but only by a ratio of sliding mode's to Baumgarte's max|Φ| between {ratio.min():.2g} "
                         f"and {ratio.max():.2g} at equal gains, where the paper implies {claimed:g}")
        rows.append(["001", claim, _verdict(held, total), evidence + " (`sliding_mode_claims`)"])
    return rows


def _friction_claims(summary: pd.DataFrame | None) -> list[list[str]]:
    claim = "with the paper's data (M = 0.5 N m) the slider-crank moves over the 20 s shown"
    if summary is None:
        return [["000", claim, "not checked", "`slider_crank_summary` table missing"]]
    seed = summary[(summary["variant"] == "seed") & (summary["treatment"] == "exact")
                   & (summary["initial"] == "consistent")]
    if seed.empty:
        return [["000", claim, "not checked", "no seed/exact run in `slider_crank_summary`"]]
    row = seed.iloc[0]
    stuck = int(row["n_stick"]) > 0 and int(row["n_slip_from_stick"]) == 0
    moved = abs(float(row["q1_t20"]) - float(row["q1_t1"]))
    return [["000", claim, "fails" if stuck else "holds",
             f"exact Coulomb law: the slider sticks at t = {row['stick_times']} s and never slips again; "
             f"q1 changes by {moved:.3g} rad between 1 s and 20 s (`slider_crank_summary`)"]]


def section(ctx: ReportContext) -> list[str]:
    rows = (_errata_claims(ctx.table("errata")) + _initial_claims(ctx.table("initial_conditions"))
            + _friction_claims(ctx.table("slider_crank_summary")) + _sliding_mode_claims(ctx.table("sliding_mode_claims")))
    rows.sort(key=lambda r: r[0])  # stable: paper 000 first, each paper's claims in the order above
    return ["## Claims of the papers", "",
            "Each claim with its verdict, computed from the saved tables named in the evidence column "
            "('partly' gives the number of settings where it holds). Paper 000: Coulomb friction in the "
            "slider-crank; paper 001: sliding-mode stabilization of the quick-return mechanism.", "",
            md_table(["paper", "claim", "verdict", "evidence"], rows), ""]
