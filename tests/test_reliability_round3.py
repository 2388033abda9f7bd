"""Reliability, round three: at least 60 tries in six groups (tests/round3/), each graded good, weak or bad.

Tries that expect an error are graded by the probe's ``judge`` (test_reliability_probe.py). Tries that expect
success (``OK``) are good when the call succeeds and their ``then`` check holds, bad otherwise.
``python tests/test_reliability_round3.py [name-fragment]`` prints the tally; the test requires every try good.
"""

from __future__ import annotations

import contextlib
import io
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
import round3  # noqa: E402
from round3 import GROUPS, OK, TRIES  # noqa: E402
from round3 import caches, defaults, folders, tables, user_file, work_bounds  # noqa: E402,F401
from test_reliability_probe import isolated, judge, print_tally  # noqa: E402,F401 (isolated: a fixture)
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


def test_round_three_has_at_least_60_tries_in_six_groups():
    names = [(t.group, t.name) for t in TRIES]
    assert len(names) >= 60, len(names)
    assert len(set(names)) == len(names)
    assert {t.group for t in TRIES} == set(GROUPS)


@pytest.mark.parametrize("attempt", [pytest.param(t, marks=pytest.mark.slow) if t.slow else t for t in TRIES],
                         ids=[f"{t.group}:{t.name}" for t in TRIES])
def test_every_try_is_good(attempt, isolated):  # noqa: F811 - the probe's fixture
    verdict, what = grade(attempt, isolated)
    assert verdict == "good", what


if __name__ == "__main__":
    print_tally([t for t in TRIES if len(sys.argv) < 2 or sys.argv[1] in t.name or sys.argv[1] == t.group], grade)
