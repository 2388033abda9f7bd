"""The automated report, built from saved results only: it never runs a simulation.

:func:`build_report` gives every section (``study/report/sections/<name>.py``, in the order of
:func:`report_sections`: the fixed ones and those the case lists name) a
:class:`~study.report.context.ReportContext` over the saved tables (``reports/tables``,
``reports/timing``) and the pipeline's saved runs, and writes

- ``reports/figures/*.png`` and ``*.svg``;
- ``reports/index.md``: the report, readable on a code host (figures numbered, formulas as ``$...$``);
- ``reports/report.html``: the same text as one self-contained page (figures as base64 PNG, formulas
  as MathML, a table of contents; no JavaScript, nothing fetched);
- ``reports/manifest.json``: package versions, Python version, git commit, platform, the input hash
  of every case, the wall time of every stage of the last pipeline run, and every input and output
  file with its SHA-256.

Every number in the text is read from a saved file. Iteration follows the case lists' fixed order
or is sorted, floats have fixed formats and nothing carries a date, so the same inputs give the
same files.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import json
import subprocess
import time
from pathlib import Path
from typing import Iterable

import pandas as pd

from study.integrity import atomic_write
from study.output_folder import check_output_folder, claim_output_folder
from study.pipeline import (CASES_DIR, PIPELINE_RECORD, CaseList, CaseListError, Store, check_tables, load_case_lists,
                            read_table, write_table)
from study.report.context import ReportContext, default_render_workers
from study.report.sections import findings
from study.report.render import markdown_to_html, md_table, number_figures, png_data_uri
from study.results import package_versions

__all__ = ["FIXED_SECTIONS", "build_report", "report_sections"]

# The sections that no case list names (modules of study.report.sections), with their place in the
# report. Every other section is named by a case list ([study] section, section_order), so a new
# study is a case list plus a section module.
# The folders of tables a report reads, each checked against its record (checksums.json) before any work.
TABLE_FOLDERS = ("tables", "timing", "benchmarks")
FIXED_SECTIONS = {"claims": 10.0, "initial": 20.0, "errata": 30.0, "benchmarks": 90.0, "backends": 105.0,
                  "energy_balance": 107.0, "reproducibility": 110.0}


def section_module(name: str) -> str:
    """The module of a report section: a study section by its name (``study.report.sections.<name>``), or any
    importable module by its dotted name (a user's own section beside their case lists)."""
    return name if "." in name else f"study.report.sections.{name}"


def report_sections(case_lists: Iterable[CaseList]) -> tuple[str, ...]:
    """The report's sections in order: :data:`FIXED_SECTIONS` and every section a case list names.

    Raises
    ------
    CaseListError
        A section has two places (two case lists, or a case list and FIXED_SECTIONS, disagree), or
        names no module (:func:`section_module`).
    """
    place, named_by = dict(FIXED_SECTIONS), {name: "study.report.FIXED_SECTIONS" for name in FIXED_SECTIONS}
    for cl in case_lists:
        if cl.section is None:
            continue
        if cl.section in place and place[cl.section] != cl.section_order:
            raise CaseListError(f"{cl.path.name}: [study] section {cl.section!r} at section_order = "
                                f"{cl.section_order:g}, but {named_by[cl.section]} places it at {place[cl.section]:g}")
        try:
            found = importlib.util.find_spec(section_module(cl.section)) is not None
        except ModuleNotFoundError:   # a dotted name whose package does not exist
            found = False
        if not found:
            raise CaseListError(f"{cl.path.name}: [study] section = {cl.section!r}: no module "
                                f"{section_module(cl.section)} can be imported")
        place[cl.section], named_by[cl.section] = cl.section_order, cl.path.name
    return tuple(sorted(place, key=lambda name: (place[name], name)))


def _other_tables_section(tables_dir: Path, shown: set[str]) -> list[str]:
    lines = ["## All tables", ""]
    files = sorted(tables_dir.glob("*.csv")) if tables_dir.is_dir() else []
    if not files:
        return lines + [f"No tables found in `{tables_dir.name}/`.", ""]
    rows = []
    for path in files:
        frame = read_table(path, dtype=str, keep_default_na=False)
        rows.append([f"[`tables/{path.name}`](tables/{path.name})", str(len(frame)), str(len(frame.columns)),
                     "above" if path.name in shown else "linked only"])
    return lines + [md_table(["file", "rows", "columns", "shown"], rows, [False, True, True, False]), ""]


def _provenance_section(manifest: dict) -> list[str]:
    rows = [[k, v] for k, v in sorted(manifest["package_versions"].items())]
    return ["## Provenance", "",
            f"Git commit `{manifest['git_commit']}` (uncommitted changes are not detected); "
            f"{len(manifest['inputs'])} input files with their SHA-256, the key of every case and the wall "
            "time of every pipeline stage are listed in "
            "[`manifest.json`](manifest.json).", "",
            md_table(["package", "version"], rows), ""]


# --- manifest ----------------------------------------------------------------------------------
def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _git_commit(where: Path) -> str:
    try:
        proc = subprocess.run(["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True,
                              timeout=10, check=False)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return proc.stdout.strip() if proc.returncode == 0 and proc.stdout.strip() else "unknown"


def _display_path(path: Path, root: Path) -> str:
    path = path.resolve()
    try:
        return path.relative_to(root.resolve()).as_posix()
    except ValueError:
        return path.as_posix()


def _file_list(paths: list[Path], root: Path) -> list[dict]:
    unique = sorted({p.resolve() for p in paths})
    return [{"path": _display_path(p, root), "sha256": _sha256(p)} for p in unique]


# --- entry point -------------------------------------------------------------------------------
def build_report(reports_dir: Path, cache_dir: Path, cases_dir: Path = CASES_DIR) -> Path:
    """Write the report from saved results only; returns the path of ``index.md``.

    Parameters
    ----------
    reports_dir : the report folder; tables are read from ``tables/`` and ``timing/``, and
        ``figures/``, ``index.md``, ``report.html`` and ``manifest.json`` are written into it.
    cache_dir : the cache root holding the pipeline's saved runs (``<cache>/runs``).
    cases_dir : the folder of case lists (default ``reference/cases``).
    """
    reports_dir, cache_dir = Path(reports_dir), Path(cache_dir)
    check_output_folder(reports_dir)   # a user's own folder is refused, and every table checked, before any work
    for folder in TABLE_FOLDERS:
        check_tables(reports_dir / folder)
    claim_output_folder(reports_dir)
    root = reports_dir.resolve().parent
    store = Store(cache_dir / "runs")
    case_lists = {cl.study: cl for cl in load_case_lists(cases_dir)}
    ctx = ReportContext(reports_dir, store, case_lists, render_workers=default_render_workers())
    figures_dir = reports_dir / "figures"
    figures_dir.mkdir(parents=True, exist_ok=True)

    lines = ["# Validation study: report", ""] + findings.section(ctx) + [
             "Generated by `study.report.build_report` from saved results only: building it never runs a "
             "simulation. Every number below is read from a saved file (the tables in `tables/` and the "
             "saved runs); the inputs and their SHA-256 are listed in [`manifest.json`](manifest.json). "
             "The same content as one self-contained page is [`report.html`](report.html).", ""]
    stages = {}
    try:
        for name in report_sections(case_lists.values()):
            ts = time.perf_counter()
            lines += importlib.import_module(section_module(name)).section(ctx)
            stages[f"report:{name}"] = time.perf_counter() - ts
    finally:
        ts = time.perf_counter()
        ctx.finish_figures()
        stages["report:render figures (waiting for the workers)"] = time.perf_counter() - ts
    # the report's own stage times and figure counts change from build to build: timing/, not the manifest
    timing = pd.DataFrame([{"stage": k, "wall_s": v} for k, v in stages.items()] +
                          [{"stage": f"figures {k}", "wall_s": float(v)} for k, v in ctx.figure_stats.items()] +
                          [{"stage": "figure render workers", "wall_s": float(ctx.render_workers)}])
    write_table(reports_dir / "timing" / "report_timing.csv", timing.to_csv(index=False, lineterminator="\n"),
                f"python -m study report --out {reports_dir}")
    ctx.remove_stale_figures()
    written = {p.name for p in ctx.figures_written} | {p.with_suffix(".svg").name for p in ctx.figures_written}

    record_path = cache_dir / PIPELINE_RECORD
    record = json.loads(record_path.read_text()) if record_path.exists() else {}
    versions = package_versions()
    manifest = {
        "generator": "study.report.build_report",
        "git_commit": _git_commit(Path(__file__).resolve().parent),
        "platform": versions["platform"],
        "python": versions["python"],
        "package_versions": {k: v for k, v in versions.items() if k not in ("platform", "python")},
        "cases": {study: {c.name: {"key": c.key(), "saved": store.has(c)} for c in cl.cases}
                  for study, cl in case_lists.items()},
        "stage_wall_seconds": record.get("stages", {}),
        "inputs": _file_list(ctx.inputs, root),
    }
    lines += _failed_section(ctx)
    lines += _other_tables_section(reports_dir / "tables", {p.name for p in ctx.inputs})
    lines += _provenance_section(manifest)
    markdown = number_figures("\n".join(lines).rstrip() + "\n")

    index = reports_dir / "index.md"
    atomic_write(index, markdown)
    html_text = markdown_to_html(markdown, lambda src: png_data_uri(reports_dir / src), "Validation study: report",
                                 toc_after=findings.ANCHOR)
    atomic_write(reports_dir / "report.html", html_text)

    outputs = [index, reports_dir / "report.html"] + sorted(figures_dir / n for n in written)
    manifest["outputs"] = _file_list(outputs, root)
    atomic_write(reports_dir / "manifest.json", json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return index


def _failed_section(ctx: ReportContext) -> list[str]:
    """Cases whose last attempt failed (``tables/failed_cases.csv``), with their errors."""
    table = ctx.table("failed_cases", as_text=True)
    if table is None or table.empty:
        return []
    expected = table["expected"] == "True" if "expected" in table else pd.Series(False, index=table.index)
    rows = [[r.study, r.case, r.error] for r in table[~expected].itertuples(index=False)]
    lines = []
    if rows:
        lines += ["## Failed cases", "",
                  f"{len(rows)} cases failed; the sections above show what could be computed without them. "
                  "Each failure's traceback is saved next to where its result would be (`*.failed.json`).", "",
                  md_table(["study", "case", "error"], rows), ""]
    if expected.any():
        lines += ["## Expected stops", "",
                  f"{int(expected.sum())} cases stopped with the error their case list expects (`expect_error`: a "
                  "method that cannot pass a singular position, for example); their stop is their result, shown "
                  "in their study's section. A case that finished instead would be listed above as failed.", ""]
    return lines
