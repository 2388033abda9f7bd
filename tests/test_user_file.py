"""A user's mechanism file fails in the user's terms (issue 37 item 6, issue 38 item 6): one line naming the file,
the function, the line and the cause, exit 2 and no traceback on the command line; the traceback, down to the user's
own line, with STUDY_TRACEBACK=1. (The catalogue of such files is tests/round3/user_file.py.)"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

import study
from study.cli import main
from study.errors import UserFileError

sys.path.insert(0, str(Path(__file__).parent))
from round3.user_file import write  # noqa: E402

RAISES = """\
import study


def describe(ps):
    return 1 / 0
"""


@pytest.fixture
def user_file(tmp_path):
    """bar.py whose describe(ps) raises at line 5, and its parameter file (the catalogue's template)."""
    return write(tmp_path, RAISES, name="bar")


def test_the_command_line_prints_one_line_without_a_traceback(user_file, tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("STUDY_TRACEBACK", raising=False)
    assert main(["simulate", str(user_file), "--t-end", "0.1", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: {user_file}: describe(ps) raised ZeroDivisionError at line 5: division by zero"]
    assert not (tmp_path / "x.csv").exists()


def test_the_traceback_reaches_the_users_line_with_study_traceback(user_file, tmp_path, monkeypatch):
    monkeypatch.setenv("STUDY_TRACEBACK", "1")
    with pytest.raises(UserFileError) as info:
        main(["validate", str(user_file), "--out", str(tmp_path / "v")])
    cause = info.value.__cause__
    assert isinstance(cause, ZeroDivisionError)
    frames = [(f.tb_frame.f_code.co_filename, f.tb_lineno) for f in _frames(cause.__traceback__)]
    assert (str(user_file), 5) in frames


def _frames(tb):
    while tb is not None:
        yield tb
        tb = tb.tb_next


def test_a_ground_point_defined_twice_is_refused_by_name():
    d = study.Description("two", ["th"], {})
    d.ground("O", 0, 0)
    with pytest.raises(study.DescriptionError, match=r"ground point 'O' is defined twice \(at \(0, 0\) and at \(1, 0\)\)"):
        d.ground("O", 1, 0)
    assert d.ground_points == {"O": (0, 0)}
