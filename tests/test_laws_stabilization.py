"""The stabilization bias laws (study.laws.stabilization) against the formulas of 001 typed here by hand, read at
an offset as the compiled loop reads them, and called from Python by the reference classes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from study.laws.stabilization import (apply_bias, baumgarte_bias, baumgarte_parameters, sliding_mode_bias,
                                      sliding_mode_parameters, zero_bias)
from study.reference_data import tolerance
from study.solver.stabilization import Baumgarte, NoStabilization, Projection, SlidingMode

PHI = np.array([1e-3, -2e-4, 5e-9])
PHIDOT = np.array([-3e-2, 4e-3, -1e-8])

#: the sgn approximations of 001 (after eq. 17), typed from their definitions
SGN = {"sign": lambda s, w: float(np.sign(s)), "sat": lambda s, w: min(max(s / w, -1.0), 1.0),
       "tanh": lambda s, w: math.tanh(s / w), "arctan": lambda s, w: 2.0 / math.pi * math.atan(s / w),
       "sqrt": lambda s, w: s / math.sqrt(s * s + w * w)}


def at_offset(law, parameters, offset: int = 3) -> np.ndarray:
    """The law as the compiled loop calls it: its parameters at ``offset`` in a longer option array."""
    cf = np.concatenate([np.full(offset, np.nan), np.asarray(parameters, dtype=float), [np.nan]])
    out = np.full(PHI.size, np.nan)
    law(PHI, PHIDOT, cf, offset, out)
    return out


def test_zero_bias_writes_zeros():
    assert np.array_equal(at_offset(zero_bias, []), np.zeros(PHI.size))
    assert np.array_equal(NoStabilization().bias(PHI, PHIDOT), np.zeros(PHI.size))
    assert np.array_equal(Projection().bias(PHI, PHIDOT), np.zeros(PHI.size))


@pytest.mark.parametrize("d, omega", [(1.0, 10.0), (0.3, 47.0)])
def test_baumgarte_bias_is_eq_11(d, omega):
    expected = -2.0 * d * omega * PHIDOT - omega ** 2 * PHI
    tol = tolerance("round_off") * np.abs(expected).max()
    assert np.abs(at_offset(baumgarte_bias, baumgarte_parameters(d, omega)) - expected).max() <= tol
    assert np.abs(Baumgarte(d=d, omega=omega).bias(PHI, PHIDOT) - expected).max() <= tol
    assert np.abs(Baumgarte.from_alpha_beta(d * omega, omega).bias(PHI, PHIDOT) - expected).max() <= tol


@pytest.mark.parametrize("sgn", sorted(SGN))
def test_sliding_mode_bias_is_eqs_14_to_17(sgn):
    """Per-constraint Lambda and K, a scalar k: b = -Lambda Phidot - K s - k sgn(s) with s = Phidot + Lambda Phi."""
    lam, K, k, width = (2.0, 30.0, 0.5), (7.0, 1.0, 12.0), 3e-3, 1e-8
    s = [PHIDOT[i] + lam[i] * PHI[i] for i in range(PHI.size)]
    expected = np.array([-lam[i] * PHIDOT[i] - K[i] * s[i] - k * SGN[sgn](s[i], width) for i in range(PHI.size)])
    tol = tolerance("round_off") * np.abs(expected).max()
    compiled = at_offset(sliding_mode_bias, sliding_mode_parameters(lam, K, k, sgn, width, PHI.size))
    assert np.abs(compiled - expected).max() <= tol
    reference = SlidingMode(Lambda=lam, K=K, k=k, sgn=sgn, width=width).bias(PHI, PHIDOT)
    assert np.abs(reference - expected).max() <= tol


def test_apply_bias_takes_lists_and_strided_arrays():
    """The reference path hands the law what the equations return (a list, a strided view): converted, not refused."""
    wide = np.zeros((PHI.size, 2))
    wide[:, 0] = PHIDOT
    b = apply_bias(baumgarte_bias, baumgarte_parameters(1.0, 10.0), list(PHI), wide[:, 0])
    assert np.abs(b - (-20.0 * PHIDOT - 100.0 * PHI)).max() <= tolerance("round_off") * np.abs(b).max()
