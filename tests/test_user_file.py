"""A user's mechanism file fails in the user's terms (issue 37 item 6, issue 38 item 6): one line naming the file,
the function, the line and the cause, exit 2 and no traceback on the command line; the traceback, down to the user's
own line, with STUDY_TRACEBACK=1. (The catalogue of such files is tests/round3/user_file.py.)"""

from __future__ import annotations

import re
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


# --- a spatial user's file: describe(ps) returns a SpatialDescription, start(ps) the state by body --------------------
SPATIAL_TOML = """\
[meta]
mechanism = "{name}"
paper = "none: a spatial try"
description = "a ball on a rod from a fixed point, in 3D"

[parameters.m]
value = 1.0
unit = "kg"
source = "the try's own"
rule = "positive"
doc = "mass"

[variants.seed]
note = "the try's set"
"""
SPATIAL = """\
from study.spatial import GROUND, SpatialDescription


def describe(ps):
    d = SpatialDescription("ball")
    d.body("bob", ps.values.m, (1e-3, 1e-3, 1e-3), points={"top": (0, 0, 0.5)})
    d.spherical("pivot", ("bob", "top"), (GROUND, (0, 0, 0)))
    d.gravity((0, 0, -9.81))
    return d


def start(ps):
    return {"positions": {"bob": (0, 0, -0.5)}, "velocities": {"bob": (0.5, 0, 0)}}
"""


def _spatial_file(tmp_path, source=SPATIAL, name="ball"):
    (tmp_path / f"{name}.toml").write_text(SPATIAL_TOML.format(name=name))
    path = tmp_path / f"{name}.py"
    path.write_text(source)
    return path


def test_a_spatial_file_loads_as_a_spatial_mechanism_and_simulates(tmp_path, capsys):
    mech = study.load_mechanism(_spatial_file(tmp_path))
    assert mech.kind == "spatial" and mech.equations().coordinate_names[:3] == ("bob_x", "bob_y", "bob_z")
    assert main(["simulate", str(tmp_path / "ball.py"), "--t-end", "0.05", "--out", str(tmp_path / "x")]) == 0
    assert (tmp_path / "x.csv").exists()


def test_a_spatial_file_validates_against_exudyn(tmp_path):
    assert main(["validate", str(_spatial_file(tmp_path)), "--t-end", "0.1", "--out", str(tmp_path / "v")]) == 0
    assert (tmp_path / "v" / "report.md").exists()


@pytest.mark.parametrize("change, message", [
    (('"positions": {"bob": (0, 0, -0.5)}, ', ''), r"ball.py: start\(ps\) at line 12 gives no 'positions'"),
    (('"velocities"', '"speeds"'), r"ball.py: start\(ps\) at line 12 returned the unknown keys speeds"),
    (("(0, 0, -0.5)", "(0, -0.5)"), r"ball.py: start\(ps\) at line 12: .*has 2 entries"),
    (("return d", "return 1"), r"ball.py: describe\(ps\) at line 4 returned an int, not a "
                               r"study.spatial.SpatialDescription"),
])
def test_a_wrong_spatial_file_is_named(tmp_path, capsys, change, message):
    path = _spatial_file(tmp_path, SPATIAL.replace(*change))
    assert main(["simulate", str(path), "--t-end", "0.05", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ")
    assert re.search(message, err[0]), err[0]


def test_a_spatial_files_parameters_take_no_initial_conditions(tmp_path, capsys):
    path = _spatial_file(tmp_path)
    toml = tmp_path / "ball.toml"
    toml.write_text(toml.read_text() + '\n[initial_conditions.printed]\nq = [0.5]\nqd = [0.0]\nsource = "x"\n')
    assert main(["simulate", str(path), "--t-end", "0.05", "--out", str(tmp_path / "x")]) == 2
    assert "ball.toml (mechanism ball, variant seed): initial_conditions = ['printed']: not read: the start is ball.py's start(ps); remove the table" in capsys.readouterr().err
