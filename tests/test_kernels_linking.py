"""Helpers compiled for linking only (study.kernels.linking): same results as numba's own compile, one compile per
signature whatever constants the callers pass, nothing on disk."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from study.kernels.linking import LinkOnlyLibrary, link_only


def _body(x, k):
    acc = 0.0
    for i in range(x.size):
        acc += math.sin(x[i]) * k + x[i] ** 3 / (1.0 + abs(x[i]))
    return acc


linked = link_only(_body)
plain = njit(_body)


@njit
def _through_linked(x, k):
    return linked(x, 2) + linked(x, k)


@njit
def _through_plain(x, k):
    return plain(x, 2) + plain(x, k)


def test_linked_helper_gives_the_plain_compile_bit_for_bit():
    x = np.linspace(-3.0, 7.0, 101)
    assert _through_linked(x, 5) == _through_plain(x, 5)   # exact: the same operations, in the same order


def test_a_constant_argument_does_not_compile_the_helper_again():
    _through_linked(np.ones(3), 3)
    assert len(linked.signatures) == 1            # linked(x, 2) and linked(x, k) share the int64 compile
    library = linked.overloads[linked.signatures[0]].library
    assert isinstance(library, LinkOnlyLibrary)
    assert linked._cache.__class__.__name__ == "NullCache"   # never saved: its code is in its callers' entries
