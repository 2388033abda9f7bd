"""Output folders, saved pairs and checked tables: nothing a user made is overwritten, a saved pair is replaced only
as a whole, and the report checks every table against what its writer recorded."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from study.cli import main
from study.errors import ResultIntegrityError
from study.output_folder import MARKER, OutputFolderError, check_output_folder, claim_output_folder
from study.pipeline.tables import CHECKSUMS, check_tables, read_table, write_table
from study.results import SimulationResult

REPO = Path(__file__).resolve().parents[1]


def result(n: int) -> SimulationResult:
    t = np.linspace(0.0, 1.0, n)
    q = np.column_stack([np.sin(t), np.cos(t)])
    return SimulationResult(t, q, q, q, t[:, None], 0 * t[:, None], 0 * t[:, None], {"kinetic": t}, {}, {"n": n}, {})


def replaces_in_a_save(tmp_path: Path) -> int:
    """How many os.replace calls one save over an existing pair makes (staging and committing)."""
    result(3).save(tmp_path / "count" / "run")
    calls = []
    real = os.replace
    try:
        os.replace = lambda *a, **k: calls.append(a) or real(*a, **k)
        result(4).save(tmp_path / "count" / "run")
    finally:
        os.replace = real
    return len(calls)


@pytest.mark.parametrize("failure", [OSError(28, "No space left on device"), KeyboardInterrupt()],
                         ids=["oserror", "interrupt"])
def test_a_save_failing_at_any_rename_keeps_the_previous_pair(tmp_path, monkeypatch, failure):
    steps = replaces_in_a_save(tmp_path)
    assert steps == 4   # two staged files written, two renamed into place
    for k in range(1, steps + 1):
        base = tmp_path / f"step{k}" / "run"
        result(5).save(base)
        calls = []
        real = os.replace

        def failing(src, dst, *args, **kwargs):
            calls.append(dst)
            if len(calls) == k:
                raise failure
            return real(src, dst, *args, **kwargs)
        monkeypatch.setattr(os, "replace", failing)
        with pytest.raises(type(failure)):
            result(9).save(base)
        monkeypatch.setattr(os, "replace", real)
        again = SimulationResult.load(base)   # the previous pair, whole and checked
        assert len(again.t) == 5 and again.stats == {"n": 5}, f"failure at rename {k} of {steps}"
        assert sorted(p.name for p in base.parent.iterdir()) == ["run.csv", "run.json"], "staging files left behind"


def test_a_save_replaces_both_files(tmp_path):
    result(5).save(tmp_path / "run")
    result(7).save(tmp_path / "run")
    assert len(SimulationResult.load(tmp_path / "run").t) == 7


def test_a_users_folder_is_refused_and_an_empty_one_marked(tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine\n")
    with pytest.raises(OutputFolderError, match="mine.*notes.txt.*no .study-output marker"):
        check_output_folder(mine)
    empty = tmp_path / "empty"
    empty.mkdir()
    assert (claim_output_folder(empty) / MARKER).is_file()
    (empty / "tables").mkdir()
    assert check_output_folder(empty) == empty   # marked: used again
    with pytest.raises(OutputFolderError, match="not a folder"):
        check_output_folder(mine / "notes.txt" / "sub")


def test_the_committed_snapshot_matches_its_records():
    for folder in ("tables", "timing", "benchmarks"):
        assert check_tables(REPO / "reports" / folder) > 0
    assert (REPO / "reports" / MARKER).is_file() and (REPO / "reports" / "benchmarks" / MARKER).is_file()


def test_an_edited_claim_stops_the_report(tmp_path, capsys):
    """Issue 37: one True changed to False in sliding_mode_claims.csv; the report refuses, naming the table and the
    command that rebuilds it, before it writes anything."""
    reports = tmp_path / "reports"
    for folder in ("tables", "timing", "benchmarks"):
        shutil.copytree(REPO / "reports" / folder, reports / folder)
    shutil.copy(REPO / "reports" / MARKER, reports / MARKER)
    claims = reports / "tables" / "sliding_mode_claims.csv"
    claims.write_text(claims.read_text().replace("True", "False", 1))
    assert main(["report", "--out", str(reports)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "sliding_mode_claims.csv" in err
    assert "python -m study run sliding_mode" in err
    assert not (reports / "figures").exists() and not (reports / "index.md").exists()


def test_the_one_reader_refuses_what_its_record_does_not_say(tmp_path):
    path = write_table(tmp_path / "tables" / "t.csv", "a,b\n1,2\n3,4\n", "python -m study run t")
    assert read_table(path).shape == (2, 2)
    path.write_text("a,b\n1,2\n3,")   # a row cut mid-line
    with pytest.raises(ResultIntegrityError, match=r"t\.csv.*python -m study run t"):
        read_table(path)
    (tmp_path / "tables" / CHECKSUMS).unlink()
    with pytest.raises(ResultIntegrityError, match="checksums.json: missing"):
        read_table(path)
