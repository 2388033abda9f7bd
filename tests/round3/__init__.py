"""Reliability, round three: tries a demanding user makes, in six groups (one module each), none of them in
test_reliability_catalogue.py or test_reliability_probe.py.

Each module registers its tries with :func:`add`. A try states the outcome a user expects:

- an exception class (library call) or an exit code (command line), with fragments of the message that
  name the value, where it came from and why it is wrong (graded by the probe's ``judge``: good, weak, bad);
- or ``OK``: the call must succeed (exit 0 for the command line), and ``then(tmp)`` checks what it did
  (the physics that ran, the files that survived). A failed check or an exception is bad.

``python tests/test_reliability_round3.py [fragment]`` prints the tally per group.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

OK = "ok"   # the try must succeed; its ``then`` checks the outcome

GROUPS = ("defaults and silent physics", "folders and saves", "work bounds", "caches", "tables", "a user's file")


@dataclass
class Try:
    name: str
    group: str
    action: Callable[[Path], object]   # (tmp) -> argv list (command line), or the library call itself
    expect: type | int | str           # exception class, exit code, or OK
    fragments: tuple[str, ...]
    writes: bool = False               # the try may write files; ``then`` checks them
    then: Callable[[Path], None] | None = None
    slow: bool = False                 # in the slow suite (make verify)
    cli: bool = False                  # OK tries: the action returns argv for the command line


TRIES: list[Try] = []


def add(group, name, action, expect, *fragments, writes=False, then=None, slow=False, cli=False):
    assert group in GROUPS, group
    TRIES.append(Try(name, group, action, expect, fragments, writes or expect == OK, then, slow, cli))
