"""Figures as drawn, not only as files: no figure title runs through a panel (checked on the rendered extents)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from study.report.sections import moving_friction

TABLES = Path(__file__).resolve().parents[1] / "reports" / "tables"


def title_overlaps(fig: Figure) -> list[int]:
    """Indices of the axes whose drawn extent (labels and ticks included) meets the figure's suptitle."""
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    title = fig._suptitle.get_window_extent(renderer)
    return [k for k, ax in enumerate(fig.axes) if ax.get_tightbbox(renderer).overlaps(title)]


def test_the_checker_sees_a_title_drawn_over_a_panel():
    fig = Figure(figsize=(4, 3))
    ax = fig.add_axes((0.1, 0.1, 0.8, 0.88))
    ax.set_title("a panel title")
    fig.suptitle("a figure title")
    assert title_overlaps(fig) == [0]


def test_tall_friction_figures_keep_their_title_above_the_first_panel():
    forces, phases = (pd.read_csv(TABLES / f"moving_friction_{n}.csv") for n in ("forces", "phases"))
    sets = list(dict.fromkeys(forces["set"]))
    assert sets
    for key in sets:
        fig = moving_friction.forces_figure(forces[forces["set"] == key], phases[phases["set"] == key], key)
        assert title_overlaps(fig) == [], key
