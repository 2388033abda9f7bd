"""Reliability, round three: at least 60 tries in six groups (tests/round3/), each graded good, weak or bad.

Tries that expect an error are graded by the probe's ``judge`` (test_reliability_probe.py). Tries that expect
success (``OK``) are good when the call succeeds and their ``then`` check holds, bad otherwise.
``python tests/test_reliability_round3.py [name-fragment]`` prints the tally; the test requires every try good.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
import traceback
from collections import Counter
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
import round3  # noqa: E402
from round3 import GROUPS, OK, TRIES  # noqa: E402
from round3 import caches, defaults, folders, tables, user_file, work_bounds  # noqa: E402,F401
from test_reliability_probe import isolate, judge  # noqa: E402
from study.cli import main  # noqa: E402


def grade(t: round3.Try, tmp: Path) -> tuple[str, str]:
    """('good' | 'weak' | 'bad', what happened) for one try run in ``tmp``."""
    if t.expect != OK:
        return judge(t, tmp)
    stderr = io.StringIO()
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            if t.cli:
                code = main(t.action(tmp))
                if code != 0:
                    return "bad", f"exit {code}: {stderr.getvalue().strip()[-300:]}"
            else:
                t.action(tmp)
        if t.then is not None:
            t.then(tmp)
    except AssertionError as exc:
        return "bad", f"check failed: {exc}"[:300]
    except Exception as exc:  # noqa: BLE001 - graded
        return "bad", f"{type(exc).__name__}: {exc}".splitlines()[0][:300]
    return "good", "succeeded and checked"


@pytest.fixture
def isolated(tmp_path, monkeypatch):
    monkeypatch.setenv("STUDY_CACHE_DIR", "")
    monkeypatch.chdir(tmp_path)
    isolate(tmp_path)
    return tmp_path


def test_round_three_has_at_least_60_tries_in_six_groups():
    names = [(t.group, t.name) for t in TRIES]
    assert len(names) >= 60, len(names)
    assert len(set(names)) == len(names)
    assert {t.group for t in TRIES} == set(GROUPS)


@pytest.mark.parametrize("attempt", [pytest.param(t, marks=pytest.mark.slow) if t.slow else t for t in TRIES],
                         ids=[f"{t.group}:{t.name}" for t in TRIES])
def test_every_try_is_good(attempt, isolated):
    verdict, what = grade(attempt, isolated)
    assert verdict == "good", what


if __name__ == "__main__":
    os.environ.pop("STUDY_TRACEBACK", None)
    chosen = [t for t in TRIES if len(sys.argv) < 2 or sys.argv[1] in t.name or sys.argv[1] == t.group]
    tally: Counter = Counter()
    for t in chosen:
        with tempfile.TemporaryDirectory() as d:
            cwd, env = os.getcwd(), os.environ.get("STUDY_CACHE_DIR")
            isolate(Path(d))
            try:
                verdict, what = grade(t, Path(d))
            except Exception:  # noqa: BLE001
                verdict, what = "bad", traceback.format_exc().splitlines()[-1]
            finally:
                os.chdir(cwd)
                os.environ.pop("STUDY_CACHE_DIR") if env is None else os.environ.update(STUDY_CACHE_DIR=env)
        tally[verdict] += 1
        tally[(t.group, verdict)] += 1
        print(f"{verdict:4} {t.group:28} {t.name:44} {what}", flush=True)
    print({k: v for k, v in tally.items() if isinstance(k, str)}, len(chosen))
    for group in dict.fromkeys(t.group for t in chosen):
        print(f"  {group:28}", {v: tally[(group, v)] for v in ("good", "weak", "bad")})
