"""The benchmark's own work-precision figure (``work_precision.png/.svg`` next to its tables)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from study.bench.settings import LEVELS


def save_work_precision_figure(wp: pd.DataFrame, out: Path) -> Path:
    """Draw the work-precision figure from the runs' table and save ``out/work_precision.png/.svg``."""
    from study.report.figures import benchmark_work_precision_figure, save_figure

    return save_figure(benchmark_work_precision_figure(wp, LEVELS), out, "work_precision")
