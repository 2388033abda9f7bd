"""Progress within a long run, at a count of steps: the same lines on any host.

:class:`ProgressPrinter` is a ``progress=`` callable (``simulate`` calls it with t after every accepted step of
the reference path). Every ``progress_steps`` steps (reference/tolerances.toml) it says one line: how far the run
is, the steps so far and the steps still to t_end at the pace of the last interval, so a run that will not finish
soon says so early. A run of fewer steps (most runs, under a second) says nothing.
"""

from __future__ import annotations

import sys
from typing import Callable

from study.reference_data import tolerance


def _stderr(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class ProgressPrinter:
    """``progress=`` for long runs: a line every ``progress_steps`` accepted steps, through ``say`` (stderr by
    default), each starting with ``label``."""

    def __init__(self, t_end: float, say: Callable[[str], None] | None = None, label: str = "",
                 every: int | None = None):
        self.t_end, self.say, self.label = float(t_end), say or _stderr, label
        self.every = int(tolerance("progress_steps")) if every is None else int(every)
        self.steps, self.t_last = 0, 0.0

    def __call__(self, t: float) -> None:
        self.steps += 1
        if self.steps % self.every or t >= self.t_end:   # not due, or the run is done
            return
        pace = (t - self.t_last) / self.every   # simulated seconds per step over the last interval
        self.t_last = t
        remaining = (self.t_end - t) / pace if pace > 0 else float("inf")
        self.say(f"{self.label}t = {t:.6g} of {self.t_end:g} s ({100 * t / self.t_end:.1f} %), {self.steps} steps; "
                 f"~{remaining:.3g} steps to t_end at the pace of the last {self.every}")
