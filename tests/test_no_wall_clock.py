"""No test judges the host's speed: no test in tests/ reads a clock, sets a time limit or asserts seconds.

A run bound is tested by what stopped it (its reason and its counts: evaluations, steps), never by the seconds it
took; a host twice as slow must pass the same tests (issue 37). :func:`wall_clock_lines` greps the test sources for

- clock reads (``time.time()``, ``perf_counter``, ``monotonic``, ``process_time``, ``datetime.now()``, ``timeit``);
- time limits (``timeout=``, ``signal.alarm``, ``SIGALRM``, ``setitimer``, ``pytest.mark.timeout``);
- assertions that compare a time (``cpu_seconds``, ``wall``, ``elapsed``, ``seconds``, ``duration``) with ``<``.

A line may carry the marker ``# hang guard:`` with its reason: a bound far from any normal run that only keeps a
stuck subprocess or browser from hanging the suite (it stops a hang, it does not judge a pace).
"""

from __future__ import annotations

import re
import tokenize
from pathlib import Path

TESTS = Path(__file__).resolve().parent
MARKER = "# hang guard:"
PATTERNS = {
    "a clock read": re.compile(r"\btime\.(time|perf_counter|monotonic|process_time|thread_time)(_ns)?\s*\(|"
                               r"\b(perf_counter|monotonic|process_time)(_ns)?\s*\(|datetime\.now\s*\(|\btimeit\b"),
    "a time limit": re.compile(r"\btimeout\s*=|\bsignal\.alarm\s*\(|\bSIGALRM\b|\bsetitimer\b|mark\.timeout\b"),
    "an assertion on seconds": re.compile(r"^\s*assert\b.*\b(cpu_seconds|cpu_s|wall\w*|elapsed\w*|seconds|duration)\b"
                                          r".*<|^\s*assert\b.*<.*\b(cpu_seconds|wall\w*|elapsed\w*|seconds|duration)\b"),
}


PROSE = {tokenize.COMMENT, tokenize.STRING, *(getattr(tokenize, name) for name in ("FSTRING_MIDDLE",)
                                               if hasattr(tokenize, name))}


def _code_lines(path: Path, prose: set) -> dict[int, str]:
    """The code of each line of a Python file: the line with its tokens of the kinds ``prose`` blanked out
    (comments, strings and docstrings may speak of time; only code can read a clock)."""
    lines = [list(line) for line in path.read_text().splitlines()]
    with open(path, "rb") as fh:
        for token in tokenize.tokenize(fh.readline):
            if token.type not in prose:
                continue
            (row, col), (end_row, end_col) = token.start, token.end
            for r in range(row, end_row + 1):
                line = lines[r - 1]
                line[col if r == row else 0:end_col if r == end_row else len(line)] = \
                    " " * ((end_col if r == end_row else len(line)) - (col if r == row else 0))
    return {number: "".join(chars) for number, chars in enumerate(lines, 1)}


def wall_clock_lines(root: Path) -> list[str]:
    """'file:line: what: text' for every line of a .py file under root whose code reads a clock, sets a time limit
    or asserts seconds, unless the line carries the hang-guard marker."""
    found = []
    for path in sorted(root.rglob("*.py")):
        text = path.read_text().splitlines()
        code, with_strings = _code_lines(path, PROSE), _code_lines(path, {tokenize.COMMENT})
        for number in code:
            if MARKER in text[number - 1]:
                continue
            for what, pattern in PATTERNS.items():   # a time is often a table's column: keep strings for those
                if pattern.search((with_strings if what == "an assertion on seconds" else code)[number]):
                    found.append(f"{path.relative_to(root)}:{number}: {what}: {text[number - 1].strip()}")
    return found


def test_no_test_reads_a_clock_or_sets_a_time_limit():
    found = wall_clock_lines(TESTS)
    assert found == [], "tests that judge the host's speed (use counts, or mark a hang guard):\n" + "\n".join(found)


PLANTED = {
    "alarm.py": "import signal\nsignal.alarm(90)\n",
    "clock.py": "import time\nt0 = time.perf_counter()\n",
    "monotonic.py": "from time import monotonic\nstart = monotonic()\n",
    "limit.py": "import subprocess\nsubprocess.run(['x'], timeout=120)\n",
    "seconds.py": "def test(r):\n    assert r.stats['cpu_seconds'] < 5.0\n",
    "wall.py": "def test(wall_s):\n    assert 2.0 > wall_s or wall_s < 60\n",
    "marker.py": "import pytest\n\n@pytest.mark.timeout(60)\ndef test():\n    pass\n",
}


def test_the_grep_catches_each_planted_example(tmp_path):
    """The check can fail: each kind of wall-clock judgement planted in a file is found; a marked hang guard, a
    count bound and a comment are not."""
    for name, text in PLANTED.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "fine.py").write_text(
        "import subprocess\n"
        "subprocess.run(['x'], timeout=600)  # hang guard: a normal run ends in 1 s\n"
        "def test(r):\n    assert r.stats['nfev'] <= 5e6  # the budget, a count; timeout= would be a time\n"
        "    # a comment may say time.perf_counter() without being code\n"
        "    print('nor is time.monotonic() in a string')\n")
    found = wall_clock_lines(tmp_path)
    assert sorted({line.split(":")[0] for line in found}) == sorted(PLANTED), found
