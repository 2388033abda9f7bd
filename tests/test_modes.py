"""The mode switch (study.laws.modes): the mode at t0, the mode after a crossing, the bound on switches."""

from __future__ import annotations

import numpy as np
import pytest

from study.laws.modes import LOOKAHEAD, MAX_EVENTS, flip, initial_mode, settle_zeros, signs, switch


def test_signs_and_flip():
    assert signs(np.array([2.0, 0.0, -1e-300, -3.0])).tolist() == [1, 1, -1, -1]
    mode = np.array([1, -1, 1], dtype=np.int64)
    assert flip(mode, 1).tolist() == [1, 1, 1]
    assert mode.tolist() == [1, -1, 1]   # a copy: the old mode is kept


def test_a_zero_takes_the_sign_it_has_just_after_t0():
    """Entries zero at t0 take the sign of g_ahead; the others, and the entries past g0 (friction), stay."""
    mode = np.array([1, 1, -1, 1, -1], dtype=np.int64)
    out = settle_zeros(mode, np.array([0.0, 2.0, 0.0]), np.array([-1e-9, -5.0, 3e-9]))
    assert out.tolist() == [-1, 1, 1, 1, -1]


def test_initial_mode_looks_ahead_along_the_solution():
    """g = (y0, t - 1, y1): y0 is zero at t0 = 0 and y0' = -2 (so it is negative just after), t - 1 < 0, y1 > 0.
    The look-ahead evaluates rhs once, at (t0, y0) in the mode of the plain signs, and g at t0 + LOOKAHEAD."""
    calls = []

    def rhs(t, y, mode):
        calls.append((t, tuple(y), mode))
        return np.array([-2.0, 0.0])

    def indicators(t, y):
        return np.array([y[0], t - 1.0, y[1]])
    assert initial_mode(indicators, 0.0, np.array([0.0, 1.0]), rhs) == (-1, -1, 1)
    assert calls == [(0.0, (0.0, 1.0), (1, -1, 1))]
    assert initial_mode(indicators, 0.0, np.array([0.5, 1.0]), rhs) == (1, -1, 1) and len(calls) == 1
    assert initial_mode(None, 0.0, np.array([0.0, 1.0]), rhs) is None
    assert 0 < LOOKAHEAD < 1e-6


class Rule:
    """A switching rule that records its calls and sets every entry to -1."""

    def __init__(self):
        self.calls = []

    def on_event(self, t, y, mode, i):
        self.calls.append((t, i, mode))
        return tuple(-1 for _ in mode)


def test_switch_flips_the_crossing_entry_or_asks_the_rule():
    events = []
    assert switch(None, 0.5, np.zeros(2), (1, -1, 1), 2, events) == (1, -1, -1)
    assert events == [{"t": 0.5, "indicator": 2, "new_sign": -1}]
    rule = Rule()
    assert switch(rule, 0.75, np.zeros(2), (1, 1), 0, events) == (-1, -1)
    assert rule.calls == [(0.75, 0, (1, 1))] and events[-1] == {"t": 0.75, "indicator": 0, "new_sign": -1}


def test_more_than_max_events_switches_is_chattering():
    events = [{}] * (MAX_EVENTS - 1)
    switch(None, 1.0, np.zeros(1), (1,), 0, events)   # the MAX_EVENTS-th switch is allowed
    with pytest.raises(RuntimeError, match=rf"more than {MAX_EVENTS} switches by t = 2: .* switching function 0"):
        switch(None, 2.0, np.zeros(1), (-1,), 0, events)
