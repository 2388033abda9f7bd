"""The report's figures, drawn from saved results only (restyling never reruns a simulation).

Each ``*_figure`` function takes data that is already loaded (:class:`study.results.SimulationResult`
objects, the study's tables) and returns a :class:`matplotlib.figure.Figure` built without pyplot,
so no global backend or figure registry is touched; :func:`save_figure` writes it as PNG (Agg) and
SVG. Output is deterministic: fixed style, fixed SVG id salt, no date in the metadata.
One concept, drawing a figure from loaded data; the report's sections choose what to draw.
"""

from __future__ import annotations

import io
from contextlib import contextmanager
from pathlib import Path
from typing import Collection, Iterator, Mapping, Sequence

import matplotlib
import numpy as np
import pandas as pd
from matplotlib.colors import LogNorm, to_rgb
from matplotlib.ticker import NullFormatter
from PIL import Image
from matplotlib.figure import Figure

from study import mechanisms
from study.results import SimulationResult

DPI = 110
PNG_COLORS = 256

STYLE = {
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.35,
    "grid.linewidth": 0.5,
    "svg.fonttype": "none",  # text stays text: smaller, searchable SVG
    "svg.hashsalt": "study-report",  # fixed element ids: the same data gives the same SVG
    "path.simplify": True,
}

# Units of the saved quantities come from the mechanism's description (results do not record them).

# Stable colours per method so a method looks the same in every figure.
_FIXED_STYLES = {
    "reference": {"color": "0.2", "lw": 1.4, "ls": "-"},
    "none": {"color": "black", "lw": 1.3, "ls": "-"},
    "baumgarte": {"color": "tab:blue", "lw": 2.6, "ls": "-", "alpha": 0.55},
    "projection": {"color": "tab:green", "lw": 1.3, "ls": "-"},
}
_VARIANT_COLORS = {"baumgarte": "tab:cyan", "sliding_mode": "tab:olive"}  # other gains than the default
_SGN_COLORS = {"sign": "tab:red", "sat": "tab:orange", "tanh": "tab:purple", "arctan": "tab:brown",
               "sqrt": "tab:pink"}


def method_style(method: str) -> dict:
    """Line style of a method name as used in the study's tables.

    ``sliding_mode/<sgn>`` is dashed in the colour of its sgn approximation. A name with a gain
    suffix (``'baumgarte w=100'``) gets a dash-dot line in a colour of its own method family.
    """
    base, _, suffix = method.partition(" ")
    if base in _FIXED_STYLES:
        style = dict(_FIXED_STYLES[base])
    elif base.startswith("sliding_mode/"):
        style = {"color": _SGN_COLORS.get(base.split("/", 1)[1], "tab:gray"), "lw": 1.0, "ls": (0, (4, 2))}
    else:
        style = {"color": "tab:gray", "lw": 1.0, "ls": ":"}
    if suffix:
        style["color"] = _VARIANT_COLORS.get(base.split("/")[0], tuple(0.55 * c for c in to_rgb(style["color"])))
        style["ls"] = (0, (6, 2, 1.5, 2))
        style["lw"] = min(style["lw"], 1.6)
        style.pop("alpha", None)
    return style


def pretty_mechanism(meta: Mapping) -> str:
    """'quick-return (variant seed)' from a result's metadata."""
    name = str(meta.get("mechanism", "unknown mechanism")).replace("_", "-")
    return f"{name} (variant {meta.get('variant', '?')})"


@contextmanager
def _style() -> Iterator[None]:
    with matplotlib.rc_context(STYLE):
        yield


def save_figure(fig: Figure, folder: Path, stem: str, png: bool = True) -> Path:
    """Write ``<stem>.svg`` and then ``<stem>.png`` (dpi :data:`DPI`) into ``folder``; returns the PNG path.

    The PNG is reduced to a palette of :data:`PNG_COLORS` colours (no dithering): line plots of
    thousands of noisy samples stay sharp and the file stays small enough to embed. ``png=False`` writes the SVG
    only (the report keeps a PNG rendered from the same figure key, e.g. the committed one in a fresh clone, whose
    SVG is not committed). The SVG is drawn first in either case, so it is the same file either way: drawn after
    the PNG, it would not be (the layout engines lay out again, a 'best' legend can move by tens of px).
    """
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{stem}.png"
    buffer = io.BytesIO()
    with _style():
        fig.savefig(folder / f"{stem}.svg", format="svg", metadata={"Date": None, "Creator": None})
        if png:
            fig.savefig(buffer, dpi=DPI, format="png")
    if not png:
        return path
    buffer.seek(0)
    with Image.open(buffer) as image:
        paletted = image.convert("RGB").quantize(colors=PNG_COLORS, method=Image.Quantize.MEDIANCUT,
                                                 dither=Image.Dither.NONE)
    paletted.save(path, format="PNG", optimize=True)
    return path


def _positive(values: np.ndarray) -> np.ndarray:
    """Exact zeros cannot be drawn on a log axis; they become gaps (NaN)."""
    values = np.asarray(values, dtype=float).copy()
    values[values <= 0.0] = np.nan
    return values


def constraint_violation_figure(runs: Mapping[str, SimulationResult], setting: str,
                                quantity: str = "phi") -> Figure:
    """max_i |Phi_i(t)| (``quantity='phi'``) or max_i |Phidot_i(t)| (``'phidot'``) on a log axis.

    One line per method of ``runs`` (method name -> result), all at one integrator setting. These
    correspond to paper 001's figures H.6, H.8 and H.9.
    """
    if quantity not in ("phi", "phidot"):
        raise ValueError(f"quantity = {quantity!r}; expected 'phi' or 'phidot'")
    if not runs:
        raise ValueError(f"no runs to plot for setting {setting!r}")
    first = next(iter(runs.values()))
    unit = mechanisms.constraint_unit(first.meta["mechanism"]) if "mechanism" in first.meta else ""
    symbol = r"\Phi" if quantity == "phi" else r"\dot{\Phi}"
    unit_text = (unit if quantity == "phi" else f"{unit}/s") if unit else "as saved"
    with _style():
        fig = Figure(figsize=(8.6, 4.6))
        ax = fig.add_subplot()
        for method, result in runs.items():
            values = np.abs(getattr(result, quantity)).max(axis=1)
            ax.plot(result.t, _positive(values), label=method, **method_style(method))
        ax.set_yscale("log")
        ax.set_xlabel("time t [s]")
        ax.set_ylabel(rf"largest $|{symbol}_i(t)|$ over constraints i [{unit_text}]")
        what = "position" if quantity == "phi" else "velocity"
        ax.set_title(f"{pretty_mechanism(first.meta)}: {what} constraint violation\n"
                     f"integrator {setting}, every stabilization method")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), title="method", frameon=False)
        ax.set_xlim(float(first.t[0]), float(first.t[-1]))
        fig.set_layout_engine("tight")   # laid out when drawn: in the render worker, skipped when cached
    return fig


def trajectories_figure(reference: SimulationResult, runs: Mapping[str, SimulationResult],
                        setting: str) -> Figure:
    """Top row: each coordinate of the reference run against time. Bottom row: |q_i - q_i,ref| of
    every run in ``runs`` (method name -> result, one integrator setting) on a log axis."""
    names = reference.meta.get("coordinate_names") or [f"q{i + 1}" for i in range(reference.q.shape[1])]
    unit = mechanisms.coordinate_unit(reference.meta["mechanism"]) if "mechanism" in reference.meta else ""
    unit_text = f" [{unit}]" if unit else ""
    m = len(names)
    with _style():
        fig = Figure(figsize=(3.6 * m, 6.0), layout="constrained")
        axes = fig.subplots(2, m, sharex=True, squeeze=False)
        for i, name in enumerate(names):
            top, bottom = axes[0, i], axes[1, i]
            top.plot(reference.t, reference.q[:, i], **method_style("reference"))
            top.set_ylabel(f"{name}{unit_text}")
            top.set_title(f"{name}: reference run")
            for method, result in runs.items():
                q_ref = np.interp(result.t, reference.t, reference.q[:, i])
                bottom.plot(result.t, _positive(np.abs(result.q[:, i] - q_ref)), label=method,
                            **method_style(method))
            bottom.set_yscale("log")
            bottom.set_xlabel("time t [s]")
            bottom.set_ylabel(f"|{name} - {name},ref|{unit_text}")
            bottom.set_title(f"{name}: difference from the reference")
        ref = reference.meta
        ref_text = (f"reference: {ref.get('integrator')} rtol={ref.get('rtol')}, {ref.get('stabilization')}"
                    if ref else "reference")
        fig.suptitle(f"{pretty_mechanism(reference.meta)}: trajectories. Differences for integrator {setting}, "
                     f"every stabilization method ({ref_text})", fontsize=10)
        handles, labels = axes[1, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 5), frameon=False,
                   title="method")
    return fig


def heatmap_figure(table: pd.DataFrame, value: str, settings: Sequence[str], methods: Sequence[str],
                   title: str, colorbar_label: str, labels: pd.DataFrame | None = None,
                   expected: Collection[tuple[str, str]] = ()) -> Figure:
    """Method x integrator-setting heatmap of ``table[value]`` on a log colour scale.

    ``table`` has columns ``integrator_setting``, ``method`` and ``value``; ``labels`` (same keys,
    column ``value`` as text) gives the cell annotations, so they show the saved digits exactly.
    Combinations without a row are left blank and marked 'missing' if they are in ``expected``
    (setting, method) pairs, else 'not run'.
    """
    grid = np.full((len(methods), len(settings)), np.nan)
    text = [["missing" if (s, m) in expected else "not run" for s in settings] for m in methods]
    source = labels if labels is not None else table
    keyed = {(r.integrator_setting, r.method): r for r in table.itertuples(index=False)}
    keyed_text = {(r["integrator_setting"], r["method"]): r[value] for _, r in source.iterrows()}
    for i, method in enumerate(methods):
        for j, setting in enumerate(settings):
            if (setting, method) in keyed:
                grid[i, j] = float(getattr(keyed[(setting, method)], value))
                text[i][j] = str(keyed_text[(setting, method)])
    finite = grid[np.isfinite(grid) & (grid > 0)]
    norm = LogNorm(vmin=finite.min(), vmax=finite.max()) if finite.size else None
    with _style():
        fig = Figure(figsize=(1.45 * len(settings) + 3.2, 0.42 * len(methods) + 2.0))
        ax = fig.add_subplot()
        ax.grid(False)
        image = ax.imshow(np.where(grid > 0, grid, np.nan), cmap="viridis", norm=norm, aspect="auto")
        cmap = image.get_cmap()
        for i in range(len(methods)):
            for j in range(len(settings)):
                if np.isfinite(grid[i, j]) and grid[i, j] > 0 and norm is not None:
                    r, g, b, _ = cmap(norm(grid[i, j]))
                    color = "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.5 else "white"
                else:
                    color = "0.4"
                ax.text(j, i, text[i][j], ha="center", va="center", fontsize=7.5, color=color)
        ax.set_xticks(range(len(settings)), settings, rotation=20, ha="right")
        ax.set_yticks(range(len(methods)), methods)
        ax.set_xlabel("integrator setting")
        ax.set_ylabel("stabilization method")
        ax.set_title(title)
        fig.colorbar(image, ax=ax, label=colorbar_label)
        fig.set_layout_engine("tight")   # laid out when drawn: in the render worker, skipped when cached
    return fig


# --- figures of the slider-crank, sensitivity and work-precision studies -------------------------
# A series to draw: (legend label, x, y, line style keyword arguments for Axes.plot).
Series = tuple[str, np.ndarray, np.ndarray, dict]


def stacked_time_series_figure(panels: Sequence[tuple[str, Sequence[Series]]], title: str,
                               shaded: Sequence[tuple[float, float]] = (), shade_label: str = "",
                               xlabel: str = "time t [s]", figsize: tuple[float, float] | None = None) -> Figure:
    """Panels stacked over a shared time axis, each with its own y label (units included).

    ``panels``: (y label, series) per panel. ``shaded``: (start, end) intervals drawn as a grey band
    in every panel (e.g. stick phases), labelled ``shade_label`` once in the legend of the first panel.
    """
    if not panels:
        raise ValueError("no panels to draw")
    with _style():
        fig = Figure(figsize=figsize or (8.6, 2.3 * len(panels) + 0.8))
        axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
        for k, (ax, (ylabel, series)) in enumerate(zip(axes, panels)):
            for i, (a, b) in enumerate(shaded):
                ax.axvspan(a, b, color="0.85", lw=0, zorder=0,
                           label=shade_label if (k == 0 and i == 0 and shade_label) else None)
            for label, x, y, style in series:
                ax.plot(x, y, label=label, **style)
            ax.set_ylabel(ylabel)
            ax.legend(loc="best", frameon=False)
        axes[-1].set_xlabel(xlabel)
        axes[0].set_title(title)
        fig.set_layout_engine("tight")   # laid out when drawn: in the render worker, skipped when cached
    return fig


def log_lines_figure(panels: Sequence[Mapping], title: str, figsize: tuple[float, float] | None = None,
                     markers: bool = True) -> Figure:
    """Side-by-side panels of lines on log (or linear) axes, e.g. error against cost.

    Each panel is a mapping with ``xlabel``, ``ylabel``, ``series`` (sequence of :data:`Series`) and
    optionally ``title``, ``xscale`` and ``yscale`` (default 'log'), ``legend_title``, and ``hlines``:
    (y, label, style) reference levels. Non-positive values on a log axis are left out (gaps).
    """
    if not panels:
        raise ValueError("no panels to draw")
    with _style():
        fig = Figure(figsize=figsize or (4.6 * len(panels) + 0.6, 4.4))
        axes = fig.subplots(1, len(panels), squeeze=False)[0]
        for ax, panel in zip(axes, panels):
            xscale, yscale = panel.get("xscale", "log"), panel.get("yscale", "log")
            for label, x, y, style in panel["series"]:
                x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
                keep = np.isfinite(x) & np.isfinite(y)
                if xscale == "log":
                    keep &= x > 0
                if yscale == "log":
                    keep &= y > 0
                style = {"marker": "o", "ms": 3.5, **style} if markers else dict(style)
                ax.plot(x[keep], y[keep], label=label, **style)
            for y, label, style in panel.get("hlines", ()):
                ax.axhline(y, label=label, **{"color": "0.4", "ls": ":", "lw": 1.0, **style})
            ax.set_xscale(xscale)
            ax.set_yscale(yscale)
            for axis, scale in ((ax.xaxis, xscale), (ax.yaxis, yscale)):
                if scale == "log":  # decade labels only: minor labels overlap on short log ranges
                    axis.set_minor_formatter(NullFormatter())
            ax.set_xlabel(panel["xlabel"])
            ax.set_ylabel(panel["ylabel"])
            if panel.get("title"):
                ax.set_title(panel["title"])
            if panel.get("legend_loc") == "below":
                ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False,
                          title=panel.get("legend_title"))
            else:
                ax.legend(loc=panel.get("legend_loc", "best"), frameon=False, title=panel.get("legend_title"))
        fig.suptitle(title, fontsize=10)
        fig.set_layout_engine("tight")   # laid out when drawn: in the render worker, skipped when cached
    return fig


def grid_heatmaps_figure(panels: Sequence[Mapping], title: str, colorbar_label: str,
                         shared_scale: bool = True, ncols: int | None = None) -> Figure:
    """One annotated heatmap per panel on a log colour scale (shared across panels by default).

    Each panel is a mapping with ``title``, ``rows`` and ``cols`` (tick labels), ``row_label``,
    ``col_label``, ``values`` (2-D array, rows x cols; NaN or <= 0 cells are blank), ``text``
    (2-D array of cell annotations, e.g. the table's digits or 'failed') and, with
    ``shared_scale=False``, optionally its own ``colorbar_label``. Panels fill ``ncols`` columns
    (default: one row).
    """
    if not panels:
        raise ValueError("no panels to draw")
    ncols = ncols or len(panels)
    nrows = -(-len(panels) // ncols)
    grids = [np.asarray(p["values"], dtype=float) for p in panels]
    finite = np.concatenate([g[np.isfinite(g) & (g > 0)] for g in grids])

    def norm_for(g):
        vals = finite if shared_scale else g[np.isfinite(g) & (g > 0)]
        if not vals.size:
            return None
        lo, hi = vals.min(), vals.max()
        return LogNorm(vmin=lo, vmax=hi if hi > lo else lo * 10)

    with _style():
        width = max(1.0 * len(p["cols"]) + (2.4 if not shared_scale else 1.6) for p in panels) * ncols + 1.4
        height = (max(0.5 * len(p["rows"]) for p in panels) + 1.4) * nrows + 0.8
        fig = Figure(figsize=(max(width, 6.0), height), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
        for ax in axes[len(panels):]:
            ax.set_visible(False)
        image = None
        for ax, panel, grid in zip(axes, panels, grids):
            ax.grid(False)
            norm = norm_for(grid)
            image = ax.imshow(np.where(grid > 0, grid, np.nan), cmap="viridis", norm=norm, aspect="auto",
                              origin="lower")
            cmap = image.get_cmap()
            text = panel["text"]
            for i in range(grid.shape[0]):
                for j in range(grid.shape[1]):
                    if np.isfinite(grid[i, j]) and grid[i, j] > 0 and norm is not None:
                        r, g, b, _ = cmap(norm(grid[i, j]))
                        color = "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.5 else "white"
                    else:
                        color = "0.4"
                    ax.text(j, i, str(text[i][j]), ha="center", va="center", fontsize=7, color=color)
            ax.set_xticks(range(len(panel["cols"])), [str(c) for c in panel["cols"]])
            ax.set_yticks(range(len(panel["rows"])), [str(r) for r in panel["rows"]])
            ax.set_xlabel(panel["col_label"])
            ax.set_ylabel(panel["row_label"])
            ax.set_title(panel["title"])
            if not shared_scale:
                fig.colorbar(image, ax=ax, label=panel.get("colorbar_label", colorbar_label))
        if shared_scale and image is not None:
            fig.colorbar(image, ax=list(axes[:len(panels)]), label=colorbar_label)
        fig.suptitle(title, fontsize=10)
    return fig


# --- benchmark: work-precision of the in-house solver and Exudyn ---------------------------------
_BENCH_STYLES = {("in-house compiled", "DOP853"): {"color": "tab:blue", "marker": "o", "ls": "-"},
                 ("in-house compiled", "RK45"): {"color": "tab:green", "marker": "o", "ls": "-"},
                 ("in-house compiled", "RK4"): {"color": "tab:olive", "marker": "^", "ls": "-"},
                 ("in-house reference", "DOP853"): {"color": "0.45", "marker": "o", "ls": ":"},
                 ("Exudyn tuned", "index3"): {"color": "tab:red", "marker": "s", "ls": "--"},
                 ("Exudyn tuned", "index2"): {"color": "tab:purple", "marker": "D", "ls": "--"},
                 ("Exudyn (Python user functions)", "index3"): {"color": "tab:red", "marker": "s", "ls": ":",
                                                                "mfc": "none"},
                 ("Exudyn (Python user functions)", "index2"): {"color": "tab:purple", "marker": "D", "ls": ":",
                                                                "mfc": "none"}}


def benchmark_work_precision_figure(wp: pd.DataFrame, levels: Sequence[float] = (1e-4, 1e-6, 1e-8)) -> Figure:
    """Error against CPU time, one panel per mechanism, from the benchmark's ``work_precision.csv``.

    Parameters
    ----------
    wp : DataFrame
        Columns mechanism, variant, t_end, engine, method, setting, error, cpu_s (one row per run), and
        optionally friction (how the contacts' friction ran, e.g. 'regularized friction, ε = 0.001 m/s';
        shown in the panel's title). Runs with an error of exactly 0 or NaN are left out (log axes).
    levels : sequence of float
        Accuracy levels drawn as dotted horizontal lines [rad].
    """
    if wp.empty:
        raise ValueError("no benchmark runs to draw")
    panels = []
    for mech, g in wp.groupby("mechanism", sort=False):
        series = []
        for (engine, method), runs in g.groupby(["engine", "method"], sort=False):
            runs = runs[runs["error"].notna() & runs["cpu_s"].notna()].sort_values("setting", ascending=False)
            what = "h" if engine.startswith("Exudyn") or method == "RK4" else "rtol"
            label = f"{engine} {method} ({what} {runs['setting'].max():.3g} … {runs['setting'].min():.3g})"
            series.append((label, runs["cpu_s"], runs["error"],
                           {"ms": 4, "lw": 1.2, **_BENCH_STYLES.get((engine, method), {"color": "tab:gray"})}))
        described = g["friction"].dropna().iloc[0] if "friction" in g and g["friction"].notna().any() else ""
        friction = f" ({described})" if described else ""
        panels.append({"xlabel": "CPU time of the integration [s] (this machine)",
                       "ylabel": "max |q − q_ref| over samples and coordinates [rad]", "series": series,
                       "title": f"{mech.replace('_', '-')}: variant {g['variant'].iloc[0]}, "
                                f"{float(g['t_end'].iloc[0]):g} s{friction}",
                       "legend_title": "engine, method (settings)", "legend_loc": "below",
                       "hlines": [(lv, "accuracy levels" if k == 0 else None, {"color": "0.5", "lw": 0.8})
                                  for k, lv in enumerate(levels)]})
    return log_lines_figure(panels, "Work–precision: CPU time to reach an accuracy, in-house solver (compiled and "
                            "reference paths) vs Exudyn (fixed step h)", figsize=(5.8 * len(panels), 6.4))
