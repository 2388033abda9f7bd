"""Report section: printed and consistent initial conditions (table ``initial_conditions``)."""

from __future__ import annotations

from study.report.context import ReportContext
from study.report.render import frame_table


def section(ctx: ReportContext) -> list[str]:
    lines = ["## Initial conditions", ""]
    text, values = ctx.table("initial_conditions", as_text=True), ctx.table("initial_conditions")
    if text is None:
        return lines + ["`tables/initial_conditions.csv` is missing; `python -m study initial` writes it.", ""]
    lines += ["From [`tables/initial_conditions.csv`](tables/initial_conditions.csv): the printed initial "
              "conditions of each mechanism, the consistent ones found by Newton-Raphson from the printed "
              "independent coordinates, and the constraint residuals of both.", ""]
    cols = {"mechanism", "max_abs_phi_printed", "max_abs_phi_consistent", "max_abs_phidot_printed",
            "max_abs_phidot_consistent"}
    if cols <= set(text.columns):
        for mech in sorted(set(text["mechanism"])):
            row = text[text["mechanism"] == mech].iloc[0]
            lines.append(f"- `{mech}`: at the printed q(0), max|Φ| = {row['max_abs_phi_printed']} and "
                         f"max|Φ̇| = {row['max_abs_phidot_printed']}; at the consistent q(0), "
                         f"max|Φ| = {row['max_abs_phi_consistent']} and "
                         f"max|Φ̇| = {row['max_abs_phidot_consistent']}.")
        lines.append("")
    return lines + [frame_table(text, values), ""]
