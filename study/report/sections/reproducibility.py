"""Report section: how far each published number reproduces (the rules of ``reference/verify.toml``).

The rules are the ones ``make verify`` and the perturbation check apply; this section lists the
columns that are not judged to their printed digits, with the reason each rule gives, so a reader
knows which numbers are results to their digits, which only to their decade and which are one
host's values. It reads the rules, not the tables.
"""

from __future__ import annotations

from study.report.context import ReportContext
from study.verify import rules


def section(ctx: ReportContext) -> list[str]:
    data = rules()
    lines = ["## How far the numbers reproduce", "",
             "Every table is regenerated and compared with the committed one by `make verify`, and every in-house "
             "case is rerun from q(0), q̇(0) moved by ±4 ulps by `python -m study verify --perturb` "
             "(`tables/perturbation_check.csv`). Both apply the per-column rules of `reference/verify.toml`: a "
             "number passes if it is within the rule's relative and absolute tolerance. Most columns are held to "
             "the digits the text quotes. The columns below are not, for the reasons given:", ""]
    for cls, entry in data["class"].items():
        columns = sorted({f"{t}.{c}" for t, cols in data.get("table", {}).items() for c, k in cols.items() if k == cls}
                         | {f"*.{c}" for c, k in data["column"].items() if k == cls})
        cells = [f"{e['table']}.{{{', '.join(e['columns'])}}} where "
                 + ", ".join(f"{k} = {v}" for k, v in e["where"].items())
                 for e in data.get("rows", []) if e["class"] == cls]
        if not (columns or cells):
            continue
        if entry.get("compare", True) is False:
            how = "one host's values, not compared"
        elif entry.get("decades", 0) > 0:
            how = f"judged to {entry['decades']:g} decade, a factor {10 ** entry['decades']:.3g}"
        else:
            continue
        where = "; ".join(f"`{x}`" for x in columns + cells)
        lines += [f"- **{cls}**, {how}: {where}. Why: {entry['reason']}."]
    return lines + [""]
