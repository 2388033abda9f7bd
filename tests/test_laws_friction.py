"""The exact treatment's switching functions (study.laws.friction.switching_pair, stuck_margin) against values worked
by hand, as the compiled loop and the reference rule call them: an entry's pair written at an offset of a longer
array. The numbers are exact binary fractions, so each expected value is exact and compared with ==."""

from __future__ import annotations

import numpy as np
import pytest

from study.laws.friction import friction_level, stuck_margin, switching_pair


def pair(stuck, level, force, direction, velocity, at=3):
    """The pair as the callers write it: at ``at`` of an array whose other entries must stay untouched."""
    out = np.full(at + 4, np.nan)
    switching_pair(stuck, level, force, direction, velocity, out, at)
    assert np.isnan(out[:at]).all() and np.isnan(out[at + 2:]).all()
    return out[at:at + 2]


def test_a_stuck_contact_reads_its_margin_to_the_static_limit():
    """R = 0.5 N, mu_s = 0.25, N = -4 N: the limit R + mu_s |N| = 1.5 N; holding f = -1.25 N leaves 0.25 N."""
    level = friction_level(0.25, -4.0, 0.5)
    assert level == 1.5
    assert list(pair(True, level, -1.25, -1.0, 7.0)) == [0.25, -1.0]   # the velocity is not read in stick
    assert list(pair(True, level, 1.75, 1.0, 0.0)) == [-0.25, 1.0]     # past the limit: the margin crossed zero


def test_a_stuck_pin_reads_its_margin_to_the_static_torque():
    """T0 = 0.125 N m, mu_s r = 0.0625 m, |R|_delta = 10 N: the limit 0.75 N m; holding tau = 0.5 N m leaves 0.25."""
    level = friction_level(0.0625, 10.0, 0.125)
    assert level == 0.75
    assert list(pair(True, level, 0.5, 1.0, -3.0)) == [0.25, 1.0]


@pytest.mark.parametrize("direction, velocity, expected", [(1.0, 0.5, -0.5), (1.0, -0.5, 0.5), (-1.0, -2.0, -2.0),
                                                           (-1.0, 0.75, 0.75)])
def test_a_sliding_entry_reads_minus_its_direction_times_its_velocity(direction, velocity, expected):
    """Sliding, the value is -direction v: negative while the entry moves in its direction (the mode's -1), zero at
    rest. The level and force are not read (NaN here)."""
    assert list(pair(False, np.nan, np.nan, direction, velocity)) == [expected, direction]


def test_the_margin_takes_arrays_through_its_source():
    """The reference's contact solve computes every entry's margin at once (``.py_func`` on arrays)."""
    margins = stuck_margin.py_func(np.array([1.5, 0.75, 2.0]), np.array([-1.25, 0.5, -2.5]))
    assert list(margins) == [0.25, 0.25, -0.5]
