"""The compiled sgn approximations, shared by the sliding-mode bias and the friction laws.

The same functions as ``study.solver.stabilization.SIGN_FUNCTIONS``, in its order (the index is
their id in the compiled options).
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def sign_function(kind, s, width):
    """SIGN_FUNCTIONS in order: 0 sign, 1 sat, 2 tanh, 3 arctan, 4 sqrt (width: eps or 1/c)."""
    if kind == 0:
        return 0.0 if s == 0.0 else (1.0 if s > 0.0 else -1.0)
    if kind == 1:
        return min(1.0, max(-1.0, s / width))
    if kind == 2:
        return math.tanh(s / width)
    if kind == 3:
        return (2.0 / math.pi) * math.atan(s / width)
    return s / math.sqrt(s * s + width * width)
