"""The sgn approximations of 001 (after eq. 17) by name, each written once for both backends.

``SIGN_FUNCTIONS[name]`` is a numba function f(s, width) (signature ``study.kernels.signatures.SIGN``) whose
body is NumPy: the compiled laws (the sliding-mode bias, the friction treatments' slip factors) call it
on scalars through :func:`sign_function`, and the reference path runs the same source on arrays with
NumPy (:func:`apply`). Each path keeps its own elementary functions: libm's tanh and arctan compiled,
NumPy's on arrays (they agree to round-off, not bit for bit). The width is eps for sat and sqrt and 1/c
for tanh(c s) and arctan(c s).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from study.kernels.cache import kernel
from study.kernels.signatures import SIGN


@kernel(SIGN)
def _sign(s, width):
    return np.sign(s)


@kernel(SIGN)
def _sat(s, width):
    return np.minimum(np.maximum(s / width, -1.0), 1.0)


@kernel(SIGN)
def _tanh(s, width):
    return np.tanh(s / width)


@kernel(SIGN)
def _arctan(s, width):
    return (2.0 / math.pi) * np.arctan(s / width)


@kernel(SIGN)
def _sqrt(s, width):
    return s / np.sqrt(s * s + width * width)


SIGN_FUNCTIONS = {"sign": _sign, "sat": _sat, "tanh": _tanh, "arctan": _arctan, "sqrt": _sqrt}
#: name -> the number by which the compiled laws receive an approximation in their float options: its place in
#: SIGN_FUNCTIONS, where sign_function finds it
SIGN_IDS = {name: i for i, name in enumerate(SIGN_FUNCTIONS)}


def _chain(functions: tuple, first: int = 0):
    """The compiled ``kind -> functions[kind](s, width)`` for kind >= first, one branch per function."""
    f = functions[first]
    if first == len(functions) - 1:
        return njit(lambda kind, s, width: f(s, width))
    rest = _chain(functions, first + 1)
    return njit(lambda kind, s, width: f(s, width) if kind == first else rest(kind, s, width))


#: sign_function(SIGN_IDS[name], s, width) = SIGN_FUNCTIONS[name](s, width), in compiled code; built from
#: SIGN_FUNCTIONS itself. Not cached itself: the cached laws that call it contain it.
sign_function = _chain(tuple(SIGN_FUNCTIONS.values()))


def apply(name: str, s, width: float):
    """``SIGN_FUNCTIONS[name]`` on the array ``s`` (any shape), for the reference path: the function's own Python
    source run by NumPy (``py_func``)."""
    return SIGN_FUNCTIONS[name].py_func(np.asarray(s, dtype=float), width)
