"""Report section: the errata table of the papers' printed formulas (``tables/errata.md``)."""

from __future__ import annotations

from study.pipeline import recorded, verified_text
from study.report.context import ReportContext
from study.report.render import demote_headings


def section(ctx: ReportContext) -> list[str]:
    lines = ["## Errata", ""]
    tables = ctx.reports_dir / "tables"
    md, csv = tables / "errata.md", tables / "errata.csv"
    if md.exists() or recorded(md):   # checked against its record: an edited or vanished table stops the report
        text = verified_text(md)
        ctx.inputs.append(md)
        lines += ["Embedded from [`tables/errata.md`](tables/errata.md)"
                  + (" (same rows as [`tables/errata.csv`](tables/errata.csv))." if csv.exists() else "."), ""]
        lines += [demote_headings(text.strip(), 2), ""]
    elif csv.exists():
        lines += ["`tables/errata.md` is missing; the table exists as [`tables/errata.csv`](tables/errata.csv).", ""]
    else:
        lines += ["The errata table is missing (`tables/errata.md` not found); `python -m study errata` writes it.", ""]
    return lines
