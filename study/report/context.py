"""What a report section sees: the saved tables, the saved runs of every study, and a figure writer.

A section is a module ``study/report/sections/<name>.py`` with ``section(ctx) -> list[str]``: the
Markdown lines of its part of the report, starting with a ``## `` heading. It reads numbers only
from ``ctx.table(...)`` and ``ctx.load(case)`` (never runs a simulation), and writes each figure
with ``ctx.figure(fig, stem, alt)``, which saves PNG + SVG and returns the Markdown image line.
"""

from __future__ import annotations

import hashlib
import json
import os
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from study.integrity import atomic_write
from study.errors import ResultIntegrityError
from study.pipeline import Case, CaseList, Store, find, read_table
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
    render_workers: int = 0                # > 1: figures are rendered in that many processes
    figure_stats: dict = field(default_factory=lambda: {"rendered": 0, "svg only": 0, "cached": 0})
    _pending: list = field(default_factory=list)
    _pool: Executor | None = None
    _keys: dict | None = None

    def cases(self, study: str, **criteria) -> list[Case]:
        """The study's cases matching ``criteria`` (fields, options or labels; see Case.matches)."""
        if study not in self.case_lists:
            return []
        return find(self.case_lists[study].cases, **criteria)

    def has(self, case: Case) -> bool:
        """Whether the case has a saved result. One that fails its check (edited, cut) stops the report: a figure
        is never drawn without it in silence. ResultIntegrityError names the file and the command that rebuilds it."""
        why = self.store.problem(case)
        if why not in (None, "not saved"):
            raise ResultIntegrityError(f"{why}; the saved run of case {case.name} fails its check: rebuild it with "
                                       f"`python -m study run {case.study}`")
        return why is None

    def load(self, case: Case) -> SimulationResult:
        """The saved result of a case (LookupError if it is missing or failed; ResultIntegrityError, as
        :meth:`has`, if it fails its check)."""
        self.has(case)
        result = self.store.load(case)
        self.inputs += [self.store.file(case, ".csv"), self.store.file(case, ".json")]
        return result

    def table(self, name: str, as_text: bool = False) -> pd.DataFrame | None:
        """``tables/<name>.csv`` (``timing/<name>.csv`` for names ending in ``_timing``), or None if absent.

        ``as_text=True`` keeps every cell as the saved string, so a number quoted from it has exactly
        the saved digits.
        """
        folder = "timing" if name.endswith("_timing") else "tables"
        return self.read(f"{folder}/{name}.csv", **({"dtype": str, "keep_default_na": False} if as_text else {}))

    def read(self, relative: str, **read_csv) -> pd.DataFrame | None:
        """A table of the report folder (``tables/<name>.csv``, ``benchmarks/<name>.csv`` ...) through the one checked
        reader (:func:`study.pipeline.read_table`), or None if it is neither there nor recorded (its study did not
        run). A table that fails its check, or that its record lists and is gone, stops the report."""
        path = self.reports_dir / relative
        frame = read_table(path, missing_ok=True, **read_csv)
        if frame is not None:
            self.inputs.append(path)
        return frame

    def figure(self, fig: Figure, stem: str, alt: str) -> str:
        """Save ``fig`` as ``figures/<stem>.png`` and ``.svg``; returns the Markdown image line.

        Cached by the hash of the figure's content (:func:`figure_key`): when ``figures/<stem>.png``
        and ``.svg`` exist and were rendered from the same key (``figures/figure_keys.json``), they are
        kept as they are; when only the PNG is there (a fresh clone: the SVGs are not committed), only the SVG is
        drawn. Otherwise the figure is rendered, in a worker process when
        ``render_workers > 1`` (call :meth:`finish_figures` before reading the files).
        """
        import matplotlib.pyplot as plt

        folder = self.reports_dir / "figures"
        png = folder / f"{stem}.png"
        self.figures_written.append(png)
        key = figure_key(fig)
        keys = self._figure_keys()
        png_kept = keys.get(stem) == key and png.exists()   # rendered from this key (a fresh clone has no SVGs)
        if png_kept and png.with_suffix(".svg").exists():
            self.figure_stats["cached"] += 1
            plt.close(fig)
            return f"![{alt}](figures/{png.name})"
        keys.pop(stem, None)
        self.figure_stats["svg only" if png_kept else "rendered"] += 1
        if self.render_workers > 1:
            if self._pool is None:
                self._pool = ProcessPoolExecutor(self.render_workers)
            self._pending.append((stem, key, self._pool.submit(save_figure, fig, folder, stem, not png_kept)))
        else:
            save_figure(fig, folder, stem, not png_kept)
            keys[stem] = key
        plt.close(fig)
        return f"![{alt}](figures/{png.name})"

    def _figure_keys(self) -> dict:
        if self._keys is None:
            path = self.reports_dir / "figures" / FIGURE_KEYS
            self._keys = json.loads(path.read_text()) if path.exists() else {}
        return self._keys

    def finish_figures(self) -> None:
        """Wait for the figures rendered in worker processes, then save the figure keys."""
        keys = self._figure_keys()
        try:
            for stem, key, future in self._pending:
                future.result()
                keys[stem] = key
        finally:
            self._pending.clear()
            if self._pool is not None:
                self._pool.shutdown()
                self._pool = None
            folder = self.reports_dir / "figures"
            folder.mkdir(parents=True, exist_ok=True)
            atomic_write(folder / FIGURE_KEYS, json.dumps(dict(sorted(keys.items())), indent=1) + "\n")


    def remove_stale_figures(self) -> None:
        """Remove the figures an earlier report rendered (listed in ``figures/figure_keys.json``) that this one did
        not write; nothing else in ``figures/`` is touched."""
        keys = self._figure_keys()
        folder = self.reports_dir / "figures"
        now = {p.stem for p in self.figures_written}
        stale = sorted(set(keys) - now)
        for stem in stale:
            for suffix in (".png", ".svg"):
                (folder / f"{stem}{suffix}").unlink(missing_ok=True)
            keys.pop(stem)
        if stale:
            atomic_write(folder / FIGURE_KEYS, json.dumps(dict(sorted(keys.items())), indent=1) + "\n")


FIGURE_KEYS = "figure_keys.json"
# What a figure's pixels depend on besides its artists: the drawing and saving code (style, DPI, palette).
_FIGURE_CODE = hashlib.sha256((Path(__file__).resolve().parent / "figures.py").read_bytes()).hexdigest()
_GETTERS = ("get_xydata", "get_offsets", "get_array", "get_text", "get_color", "get_facecolor", "get_edgecolor",
            "get_linestyle", "get_linewidth", "get_marker", "get_markersize", "get_markerfacecolor", "get_label",
            "get_visible", "get_zorder", "get_alpha", "get_xlim", "get_ylim", "get_xscale", "get_yscale",
            "get_position", "get_fontsize", "get_size_inches", "get_sizes", "get_hatch", "get_fillstyle", "get_ha",
            "get_va", "get_rotation", "get_width", "get_height", "get_xy", "get_paths")


def figure_key(fig: Figure) -> str:
    """SHA-256 of what a figure draws: every artist's type, data and appearance (the getters in
    ``_GETTERS``), and the source of :mod:`study.report.figures` (styles, DPI, palette).

    Two figures built from the same saved inputs get the same key (tested); any change of a plotted
    value, label, limit, colour or of the drawing code changes it.
    """
    h = hashlib.sha256(_FIGURE_CODE.encode())
    for artist in fig.findobj():
        h.update(type(artist).__name__.encode())
        for name in _GETTERS:
            getter = getattr(artist, name, None)
            if getter is None:
                continue
            try:
                value = getter()
            except (TypeError, ValueError, AttributeError, NotImplementedError):
                continue   # a getter that needs arguments or does not apply to this artist
            if value is None:
                continue
            if hasattr(value, "get_points"):
                value = value.get_points()
            if name == "get_paths":
                value = [p.vertices for p in value]
                h.update(name.encode() + b"".join(np.ascontiguousarray(v, dtype=float).tobytes() for v in value))
                continue
            try:
                arr = np.asarray(value)
            except (TypeError, ValueError):
                arr = None
            if arr is not None and arr.dtype.kind in "fiub":
                h.update(name.encode() + np.ascontiguousarray(arr, dtype=float).tobytes())
            else:
                h.update(name.encode() + repr(value).encode())
    return h.hexdigest()


def default_render_workers() -> int:
    """Processes for rendering figures: $STUDY_RENDER_WORKERS, else the CPUs available (at most 4)."""
    value = os.environ.get("STUDY_RENDER_WORKERS")
    if value is not None:
        if not value.isdigit() or int(value) < 1:
            raise ValueError(f"STUDY_RENDER_WORKERS = {value!r} must be a whole number >= 1")
        return int(value)
    return min(4, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))
