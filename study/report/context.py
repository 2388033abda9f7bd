"""What a report section sees: the saved tables, the saved runs of every study, and a figure writer.

A section is a module ``study/report/sections/<name>.py`` with ``section(ctx) -> list[str]``: the
Markdown lines of its part of the report, starting with a ``## `` heading. It reads numbers only
from ``ctx.table(...)`` and ``ctx.load(case)`` (never runs a simulation), and writes each figure
with ``ctx.figure(fig, stem, alt)``, which saves PNG + SVG and returns the Markdown image line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd
from matplotlib.figure import Figure

from study.pipeline import Case, CaseList, Store, find
from study.report.figures import save_figure
from study.results import SimulationResult


@dataclass
class ReportContext:
    """Read access to saved results for the report's sections.

    Attributes
    ----------
    reports_dir : the report folder (``tables/``, ``timing/``, ``figures/`` inside)
    store : the cache of saved runs
    case_lists : study name -> its CaseList (``reference/cases/<study>.toml``)
    figures_written : every figure PNG written so far (the report embeds and lists them)
    inputs : every saved file read so far (for the manifest)
    """

    reports_dir: Path
    store: Store
    case_lists: dict[str, CaseList]
    figures_written: list[Path] = field(default_factory=list)
    inputs: list[Path] = field(default_factory=list)

    def cases(self, study: str, **criteria) -> list[Case]:
        """The study's cases matching ``criteria`` (fields, options or labels; see Case.matches)."""
        if study not in self.case_lists:
            return []
        return find(self.case_lists[study].cases, **criteria)

    def has(self, case: Case) -> bool:
        return self.store.has(case)

    def load(self, case: Case) -> SimulationResult:
        """The saved result of a case (LookupError if it is missing or failed)."""
        result = self.store.load(case)
        self.inputs += [self.store.file(case, ".csv"), self.store.file(case, ".json")]
        return result

    def table(self, name: str, as_text: bool = False) -> pd.DataFrame | None:
        """``tables/<name>.csv`` (``timing/<name>.csv`` for names ending in ``_timing``), or None if absent.

        ``as_text=True`` keeps every cell as the saved string, so a number quoted from it has exactly
        the saved digits.
        """
        folder = "timing" if name.endswith("_timing") else "tables"
        path = self.reports_dir / folder / f"{name}.csv"
        if not path.exists():
            return None
        self.inputs.append(path)
        return pd.read_csv(path, dtype=str, keep_default_na=False) if as_text else pd.read_csv(path)

    def figure(self, fig: Figure, stem: str, alt: str) -> str:
        """Save ``fig`` as ``figures/<stem>.png`` and ``.svg``; returns the Markdown image line."""
        png = save_figure(fig, self.reports_dir / "figures", stem)
        self.figures_written.append(png)
        return f"![{alt}](figures/{png.name})"
