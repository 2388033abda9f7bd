"""The mode switch: the mode a run starts in, and the mode after a located crossing, at most MAX_EVENTS per run.

A mode is one sign (+-1) per switching function, frozen between located crossings. Without a switching rule of its
own (loads alone) the mode is the switching functions' signs: it starts as their signs at t0 (a zero takes the sign
it has ``LOOKAHEAD`` later along the solution, :func:`initial_mode`), and a crossing of function i flips entry i
(:func:`flip`). A rule whose modes are more than the signs (stick/slip friction,
``study.solver.friction.StickSlipSwitching``) decides the new mode itself (its ``on_event``) and settles its load
entries with :func:`signs` and :func:`settle_zeros`.

Both loops return to Python at a located crossing (the compiled loop ends its segment there), so both call
:func:`switch`, which applies the rule and bounds the number of switches. The rules on numbers (:func:`signs`,
:func:`settle_zeros`, :func:`flip`) are sign tests and copies that only Python calls, once per crossing: they are
plain NumPy, not compiled kernels (compiling them cost a cold first run more CPU than all their calls take).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

MAX_EVENTS = 100_000  # more switches than this in one run means chattering on a switching surface
LOOKAHEAD = 1e-9      # [s] a switching function zero at t0 takes the sign it has this much later


def signs(g):
    """(k,) int64: +1 where g >= 0, else -1 (the mode of switching functions g)."""
    out = np.empty(g.size, dtype=np.int64)
    for i in range(g.size):
        out[i] = 1 if g[i] >= 0 else -1
    return out


def settle_zeros(mode, g0, g_ahead):
    """A copy of ``mode`` whose entries i < g0.size with g0[i] == 0 take the sign of g_ahead[i] (the switching
    functions ``LOOKAHEAD`` after t0)."""
    out = mode.copy()
    for i in range(g0.size):
        if g0[i] == 0:
            out[i] = 1 if g_ahead[i] >= 0 else -1
    return out


def flip(mode, i):
    """A copy of ``mode`` with entry i flipped: the mode after switching function i crossed zero."""
    out = mode.copy()
    out[i] = -out[i]
    return out


def as_mode(entries) -> tuple:
    """A mode as the loops pass it on: a tuple of Python ints."""
    return tuple(int(s) for s in entries)


def initial_mode(indicators: Callable | None, t0: float, y0: np.ndarray, rhs: Callable) -> tuple | None:
    """Signs of the switching functions ``indicators(t, y)`` at t0; a zero takes the sign it has ``LOOKAHEAD``
    later along ``rhs(t, y, mode)``. None without switching functions."""
    if indicators is None:
        return None
    g = np.asarray(indicators(t0, y0), dtype=float)
    mode = signs(g)
    if np.any(g == 0):
        y_ahead = y0 + LOOKAHEAD * rhs(t0, y0, as_mode(mode))
        mode = settle_zeros(mode, g, np.asarray(indicators(t0 + LOOKAHEAD, y_ahead), dtype=float))
    return as_mode(mode)


def switch(rule, t: float, y: np.ndarray, mode: tuple, i: int, events: list) -> tuple:
    """The mode after switching function i crossed zero at (t, y), the event appended to ``events``.

    ``rule``: a switching rule with ``on_event(t, y, mode, i) -> mode`` (stick/slip friction), or None (entry i
    flips). Raises RuntimeError after ``MAX_EVENTS`` switches: the solution chatters on a switching surface.
    """
    if rule is not None:
        new = as_mode(rule.on_event(t, y, mode, i))
    else:
        new = as_mode(flip(np.asarray(mode, dtype=np.int64), i))
    events.append({"t": t, "indicator": i, "new_sign": new[i]})
    if len(events) > MAX_EVENTS:
        raise RuntimeError(f"more than {MAX_EVENTS} switches by t = {t:.9g}: the solution chatters on switching "
                           f"function {i}")
    return new
