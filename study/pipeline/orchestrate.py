"""The pipeline run: every study's case list run through the store, then its tables written and recorded."""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path
from typing import Any, Iterable, Mapping

import pandas as pd

from study.integrity import atomic_write
from study.pipeline.cases import CASES_DIR, load_case_lists
from study.pipeline.execute import run_cases
from study.pipeline.executors import make_executor
from study.pipeline.store import Store
from study.pipeline.summaries import (backend_agreement, backend_cpu, energy_balance, energy_flags, failures_table,
                                      summarize, summary_function)
from study.output_folder import check_output_folder, claim_output_folder
from study.pipeline.tables import forget_table, read_table, record_tables, table_record, write_tables

PIPELINE_RECORD = "pipeline_record.json"  # what the last pipeline run did, in the cache root
CASE_SECONDS = "case_wall_timing"  # timing/<name>.csv: the wall seconds of each case when it last ran (queue order)


def case_seconds(reports_dir: Path, stream) -> dict[str, float]:
    """The wall seconds each case took when it last ran, by name, from ``timing/case_wall_timing.csv``."""
    path = Path(reports_dir) / "timing" / f"{CASE_SECONDS}.csv"
    if not path.exists():
        return {}
    try:
        frame = read_table(path)
        seconds = {str(k): float(v) for k, v in zip(frame["case"], frame["wall_s"])}
        bad = [k for k, v in seconds.items() if not (math.isfinite(v) and v >= 0)]
        if bad:
            raise ValueError(f"wall_s of {bad[0]!r} is {seconds[bad[0]]!r}, not a duration")
        return seconds
    except (ValueError, KeyError) as exc:   # ResultIntegrityError too: a table that fails its check
        print(f"{path} is unreadable ({type(exc).__name__}: {exc}): the cases are queued in list order", file=stream)
        return {}


def save_case_seconds(seconds: Mapping[str, float], reports_dir: Path, record_root: Path, command: str) -> None:
    """Write ``timing/case_wall_timing.csv`` and record it like a study's tables."""
    frame = pd.DataFrame({"case": list(seconds), "wall_s": list(seconds.values())})
    record_tables(record_root / "tables" / f"{CASE_SECONDS}.json",
                  write_tables({CASE_SECONDS: frame}, reports_dir, command))


def run_command(reports_dir: Path, study: str | None = None, folder: Path = CASES_DIR) -> str:
    """The command that writes a study's tables (or, without ``study``, the pipeline's own) into ``reports_dir``."""
    cases = "" if Path(folder).resolve() == CASES_DIR.resolve() else f" --cases {folder}"
    return f"python -m study run{'' if study is None else ' ' + study} --out {reports_dir}{cases}"


def run_pipeline(reports_dir: Path, cache_root: Path, studies: Iterable[str] | None = None, workers: int = 2,
                 scheduler: str | None = None, folder: Path = CASES_DIR, stream=None,
                 record_root: Path | None = None) -> dict[str, Any]:
    """Run every study's cases (cached ones are reused), then write their tables.

    Before any case runs, every case list is loaded and its summary module imported and checked.
    The record of the run (``pipeline_record.json``) and of the tables each study wrote (with their
    checksums, ``tables/<study>.json``) go to ``record_root`` (default: ``cache_root``); a run of another
    case folder must give its own, so the default record is never overwritten by it.

    Every saved friction run's energy balance goes to ``tables/energy_balance.csv``
    (:func:`study.pipeline.summaries.energy_check`); the runs it flags are printed and listed in the record under
    ``energy_balance_flags`` (the ``run`` command then exits 1).

    Returns a record with the wall time per stage, the counts and the failures (for the manifest).
    """
    stream = stream or sys.stderr
    studies = None if studies is None else list(studies)
    record_root = Path(cache_root if record_root is None else record_root)
    case_lists = load_case_lists(folder, studies)
    for cl in case_lists:
        summary_function(cl)
    check_output_folder(reports_dir)   # a user's own folder is refused before any case runs
    store = Store(Path(cache_root) / "runs")
    record: dict[str, Any] = {"stages": {}, "studies": {}, "case_keys": {}, "case_wall_seconds": {}}
    t0 = time.perf_counter()
    title = case_lists[0].study if len(case_lists) == 1 else f"cases of {len(case_lists)} studies"
    seconds = case_seconds(reports_dir, stream)
    with make_executor(workers, scheduler) as executor:   # one queue for every study: no worker waits for a
        claim_output_folder(reports_dir)
        run = run_cases([c for cl in case_lists for c in cl.all_cases], store, executor,   # study's last case
                        title=title, stream=stream, seconds=seconds)
    record["stages"]["run"] = time.perf_counter() - t0
    seconds.update(run.wall_seconds)
    if not studies:   # a run of every study: cases no longer in any list are dropped
        seconds = {c.name: seconds[c.name] for cl in case_lists for c in cl.all_cases if c.name in seconds}
    everything = run_command(reports_dir, folder=folder)
    save_case_seconds(seconds, reports_dir, record_root, everything)
    for cl in case_lists:
        _record_study(record, cl, run)
    for cl in case_lists:
        _summarize_study(cl, store, reports_dir, record_root, folder, record, stream)
    write_tables({"failed_cases": failures_table(case_lists, store)}, reports_dir, everything)
    if any(cl.samples for cl in case_lists):
        agreement = backend_agreement(case_lists, store)
        write_tables({"backend_agreement": agreement, "backend_cpu_timing": backend_cpu(case_lists, store)},
                     reports_dir, everything)
        for _, r in agreement[~agreement["agree"].astype(bool)].iterrows():   # a finding: said, never only tabulated
            print(f"compiled and reference path DISAGREE on {r['case']}: max|dq| {r['max_abs_dq']:.3g} rad > bound "
                  f"{r['bound']:.3g} ({r['rule']}); tables/backend_agreement.csv", file=stream)
    ts = time.perf_counter()
    balance = energy_balance(case_lists, store)
    write_tables({"energy_balance": balance}, reports_dir, everything)
    record["energy_balance_flags"] = energy_flags(balance)
    for name, why in record["energy_balance_flags"].items():
        print(f"ENERGY BALANCE of {name}: {why}; tables/energy_balance.csv", file=stream)
    record["stages"]["energy_balance"] = time.perf_counter() - ts
    save_record(record, record_root)
    return record


def _record_study(record: dict[str, Any], cl, run) -> None:
    """A study's counts in the run's record: cases cached, computed, failed, expected to fail; keys and wall times."""
    names = {c.name for c in cl.all_cases}
    mine = lambda d: {k: v for k, v in d.items() if k in names}  # noqa: E731
    walls = mine(run.wall_seconds)   # the cases computed in this run
    failed, expected = mine(run.failed), mine(run.expected)
    record["studies"][cl.study] = {"cases": len(cl.cases), "reference_samples": len(cl.samples),
                                   "cached": len(names) - len(walls) - len(failed) - len(expected),
                                   "computed": len(walls), "failed": failed, "expected_failures": expected,
                                   "rejected": mine(run.rejected)}
    # the wall seconds of its computed cases, summed over the workers (they ran among other studies' cases)
    record["stages"][f"cases:{cl.study}"] = sum(walls.values())
    record["case_keys"][cl.study] = {c.name: c.key() for c in cl.all_cases}
    record["case_wall_seconds"][cl.study] = walls


def _summarize_study(cl, store: Store, reports_dir: Path, record_root: Path, folder: Path, record: dict[str, Any],
                     stream) -> None:
    """A study's tables from its saved runs, written and recorded; a summary that fails forgets the study's old
    tables (no stale table may pass for a current one) and is named in the record."""
    ts = time.perf_counter()
    written = record_root / "tables" / f"{cl.study}.json"  # the tables this study wrote last time
    try:
        tables = summarize(cl, store)
    except Exception as exc:  # noqa: BLE001 - a case it needs failed or is missing, or the summary broke
        print(f"{cl.study}: summary skipped: {type(exc).__name__}: {exc}", file=stream)
        record["studies"][cl.study]["summary_error"] = f"{type(exc).__name__}: {exc}"
        for path in table_record(written):
            forget_table(Path(path))
        written.unlink(missing_ok=True)
        return
    paths = write_tables(tables, reports_dir, run_command(reports_dir, cl.study, folder))
    for path in paths:
        print(f"wrote {path}", file=stream)
    record_tables(written, paths)
    record["stages"][f"summarize:{cl.study}"] = time.perf_counter() - ts


def save_record(record: Mapping[str, Any], cache_root: Path) -> Path:
    """Write the pipeline record (stage wall times, counts, failures) to ``<cache_root>/pipeline_record.json``."""
    path = Path(cache_root) / PIPELINE_RECORD
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, json.dumps(record, indent=1, sort_keys=True))
    return path
