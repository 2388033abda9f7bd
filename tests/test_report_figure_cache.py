"""Figures are cached by the hash of what they draw, and rendered in worker processes."""

from __future__ import annotations

import pandas as pd

from study.report.context import FIGURE_KEYS, ReportContext, figure_key
from study.report.figures import benchmark_work_precision_figure


def _wp(scale=1.0):
    rows = [{"mechanism": "m", "variant": "v", "t_end": 1.0, "engine": "in-house compiled", "method": "DOP853",
             "setting": s, "error": e * scale, "cpu_s": c} for s, e, c in ((1e-6, 1e-4, 0.01), (1e-9, 1e-7, 0.02))]
    return pd.DataFrame(rows)


def test_key_follows_the_drawn_content():
    assert figure_key(benchmark_work_precision_figure(_wp())) == figure_key(benchmark_work_precision_figure(_wp()))
    assert figure_key(benchmark_work_precision_figure(_wp())) != figure_key(benchmark_work_precision_figure(_wp(1.01)))


def test_second_build_reuses_and_a_change_rerenders(tmp_path):
    def build(scale, workers):
        ctx = ReportContext(tmp_path, store=None, case_lists={}, render_workers=workers)
        line = ctx.figure(benchmark_work_precision_figure(_wp(scale)), "wp", "alt")
        ctx.finish_figures()
        return ctx, line

    ctx, line = build(1.0, 2)                                  # rendered in a worker process
    png = tmp_path / "figures" / "wp.png"
    assert line == "![alt](figures/wp.png)" and png.exists() and png.with_suffix(".svg").exists()
    assert ctx.figure_stats == {"rendered": 1, "svg only": 0, "cached": 0} and (tmp_path / "figures" / FIGURE_KEYS).exists()
    stamp = png.stat().st_mtime_ns
    ctx, _ = build(1.0, 1)
    assert ctx.figure_stats == {"rendered": 0, "svg only": 0, "cached": 1} and png.stat().st_mtime_ns == stamp
    ctx, _ = build(2.0, 1)
    assert ctx.figure_stats == {"rendered": 1, "svg only": 0, "cached": 0} and png.stat().st_mtime_ns != stamp
    png.unlink()                                               # a missing file is rendered again
    ctx, _ = build(2.0, 1)
    assert ctx.figure_stats["rendered"] == 1 and png.exists()


def test_a_kept_png_without_its_svg_draws_the_svg_only(tmp_path):
    """A fresh clone has the committed PNGs and figure keys but no SVGs: the SVG is drawn, the PNG kept, and the SVG
    is the file a full render writes."""
    def build(workers):
        ctx = ReportContext(tmp_path, store=None, case_lists={}, render_workers=workers)
        ctx.figure(benchmark_work_precision_figure(_wp()), "wp", "alt")
        ctx.finish_figures()
        return ctx

    build(1)
    png, svg = tmp_path / "figures" / "wp.png", tmp_path / "figures" / "wp.svg"
    full_svg, stamp = svg.read_bytes(), png.stat().st_mtime_ns
    svg.unlink()
    ctx = build(2)
    assert ctx.figure_stats == {"rendered": 0, "svg only": 1, "cached": 0}
    assert png.stat().st_mtime_ns == stamp and svg.read_bytes() == full_svg
