"""Round three, group 'tables': see tests/round3/__init__.py.

Every table is read through one checked reader: the pipeline records each table's rows and SHA-256 when it writes it
(``checksums.json`` beside the tables); a table that differs (cut, edited, emptied, a column added or removed), a
table the record lists that is gone, a table no record lists, or a record that is missing or unreadable is refused,
naming the file and the command that rebuilds it. The report checks every table before it writes anything.
"""

from __future__ import annotations

import io
import shutil
from pathlib import Path

from round3 import OK, add

G = "tables"
REPO = Path(__file__).resolve().parents[2]
CHECKSUMS = "checksums.json"


def reports_copy(tmp: Path) -> Path:
    """The committed report's tables (tables/, timing/, benchmarks/ and the folder's marker) copied to tmp/reports."""
    dest = tmp / "reports"
    for folder in ("tables", "timing", "benchmarks"):
        shutil.copytree(REPO / "reports" / folder, dest / folder, ignore=shutil.ignore_patterns("*.svg"))
    for marker in (REPO / "reports").glob(".study-*"):
        shutil.copy(marker, dest / marker.name)
    return dest


def report_after(edit):
    """``report --out <copy>`` after ``edit(reports_folder)``."""
    def action(tmp):
        reports = reports_copy(tmp)
        edit(reports)
        return ["report", "--out", str(reports)]
    return action


def cut_at(name: str, size: int):
    def edit(reports):
        path = reports / "tables" / name
        path.write_bytes(path.read_bytes()[:size])
    return edit


def text_edit(rel: str, change):
    def edit(reports):
        path = reports / rel
        path.write_text(change(path.read_text()))
    return edit


def first_true_to_false(text: str) -> str:
    assert "True" in text
    return text.replace("True", "False", 1)


def add_column(text: str) -> str:
    lines = text.splitlines()
    return "\n".join([lines[0] + ",note"] + [line + ",x" for line in lines[1:]]) + "\n"


def drop_last_column(text: str) -> str:
    return "".join(",".join(line.split(",")[:-1]) + "\n" for line in text.splitlines())


def last_row_cut_mid_line(text: str) -> str:
    return text[:-(len(text.splitlines()[-1]) // 2 + 1)]


add(G, "report_table_cut_at_700_bytes", report_after(cut_at("slider_crank_summary.csv", 700)), 2,
    "slider_crank_summary.csv", "python -m study run slider_crank")
add(G, "report_claim_flipped", report_after(text_edit("tables/sliding_mode_claims.csv", first_true_to_false)), 2,
    "sliding_mode_claims.csv", "SHA-256", "python -m study run sliding_mode")
add(G, "report_table_extra_column", report_after(text_edit("tables/energy_balance.csv", add_column)), 2,
    "energy_balance.csv", "python -m study run")
add(G, "report_table_missing_column", report_after(text_edit("tables/work_precision.csv", drop_last_column)), 2,
    "work_precision.csv", "python -m study run work_precision")
add(G, "report_table_row_cut_mid_line", report_after(text_edit("tables/sensitivity.csv", last_row_cut_mid_line)), 2,
    "sensitivity.csv", "python -m study run sensitivity")
add(G, "report_table_emptied", report_after(text_edit("tables/andrews_orders.csv", lambda text: "")), 2,
    "andrews_orders.csv", "python -m study run andrews")
add(G, "report_initial_conditions_edited",
    report_after(text_edit("tables/initial_conditions.csv", lambda t: t.replace("0", "1", 1))), 2,
    "initial_conditions.csv", "python -m study initial")
add(G, "report_errata_markdown_edited", report_after(text_edit("tables/errata.md", lambda t: t + "\nan edit\n")), 2,
    "errata.md", "python -m study errata")
add(G, "report_timing_edited",
    report_after(text_edit("timing/sliding_mode_timing.csv", lambda t: t.replace("1", "2", 3))), 2, "sliding_mode_timing.csv", "python -m study run sliding_mode")


def remove(rel: str):
    return lambda reports: (reports / rel).unlink()


add(G, "report_table_missing", report_after(remove("tables/slider_crank_summary.csv")), 2,
    "slider_crank_summary.csv", "missing", "python -m study run slider_crank")
add(G, "report_checksums_missing", report_after(remove(f"tables/{CHECKSUMS}")), 2, CHECKSUMS, "missing")
add(G, "report_checksums_garbage", report_after(text_edit(f"tables/{CHECKSUMS}", lambda t: "{not json")), 2,
    CHECKSUMS, "not valid JSON")


def stray(reports):
    (reports / "tables" / "my_notes.csv").write_text("a,b\n1,2\n")


add(G, "report_table_no_record_lists", report_after(stray), 2, "my_notes.csv", CHECKSUMS)


def verify_after_edit(tmp):
    reports = reports_copy(tmp)
    text_edit("tables/sliding_mode_runs.csv", lambda t: t.replace("1", "2", 1))(reports)
    return ["verify", "sliding_mode", "--workers", "1", "--out", str(reports)]


add(G, "verify_snapshot_edited", verify_after_edit, 2, "sliding_mode_runs.csv", "python -m study run sliding_mode")


def read_cut_table(tmp):
    from study.pipeline import read_table

    reports = reports_copy(tmp)
    path = reports / "tables" / "a01_runs.csv"
    path.write_text(path.read_text()[:-40])
    read_table(path)


def _errors():
    from study.errors import ResultIntegrityError
    return ResultIntegrityError


add(G, "read_table_library_cut", read_cut_table, _errors(), "a01_runs.csv", "python -m study run a01")


def committed_tables_match_their_record(tmp):
    from study.pipeline import read_table

    for folder in ("tables", "timing", "benchmarks"):
        for path in sorted((REPO / "reports" / folder).glob("*.csv")):
            read_table(path)


add(G, "committed_snapshot_matches_its_record", committed_tables_match_their_record, OK)


def saved_run_edited(tmp):
    """A figure's input: a saved run of the pipeline edited after it was saved stops the report, naming the file."""
    from study import pipeline as pl
    from study.report.context import ReportContext

    folder = tmp / "cases"
    folder.mkdir()
    (folder / "sliding_mode.toml").write_text(
        '[study]\nsummary = "study.studies.sliding_mode"\n'
        '[[group]]\nname = "reference"\nmechanism = "quick_return"\nt_end = 0.1\n'
        'options = { integrator = "RK45", rtol = 1e-6, atol = 1e-8, output_step = 0.05 }\n')
    pl.run_pipeline(tmp / "reports", tmp / "cache", workers=1, folder=folder, stream=io.StringIO(),
                    record_root=tmp / "record")
    cl = pl.load_case_list(folder / "sliding_mode.toml")
    store = pl.Store(tmp / "cache" / "runs")
    case = cl.cases[0]
    csv = store.file(case, ".csv")
    csv.write_text(csv.read_text().replace("0", "1", 5))
    ReportContext(tmp / "reports", store, {cl.study: cl}).has(case)


add(G, "report_saved_run_edited", saved_run_edited, _errors(), ".csv", "SHA-256", "python -m study run sliding_mode")
