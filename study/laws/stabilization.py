"""The stabilization biases b(Phi, Phidot): the desired Phi_ddot added to gamma, one law per method.

Each law is a numba function of signature ``study.kernels.signatures.BIAS``, ``law(phi, phidot, cf, offset, out)``,
reading its parameters at ``cf[offset:]`` in the layout its ``*_parameters`` function below writes. The compiled
loop calls it natively (its parameters packed into the run's options); the reference path calls the same compiled
function from Python through :func:`apply_bias` (``study.solver.stabilization``, one class per method).

- ``zero_bias``:         b = 0 (no stabilization; projection, whose correction is ``study.laws.projection``).
- ``baumgarte_bias``:    b = -2 d w Phidot - w^2 Phi (001 eq. 11).
- ``sliding_mode_bias``: s = Phidot + Lambda Phi, b = -Lambda Phidot - K s - k sgn(s) (001 eqs. 14-17), sgn one of
  ``study.kernels.signs.SIGN_FUNCTIONS``.
"""

from __future__ import annotations

import numpy as np

from study.kernels.cache import kernel
from study.kernels.signatures import BIAS
from study.kernels.signs import SIGN_IDS, sign_function


@kernel(BIAS)
def zero_bias(phi, phidot, cf, off, out):
    for i in range(phi.size):
        out[i] = 0.0


@kernel(BIAS)
def baumgarte_bias(phi, phidot, cf, off, out):
    for i in range(phi.size):   # cf[off:] = baumgarte_parameters(d, omega)
        out[i] = -cf[off] * phidot[i] - cf[off + 1] * phi[i]


@kernel(BIAS)
def sliding_mode_bias(phi, phidot, cf, off, out):
    r = phi.size   # cf[off:] = sliding_mode_parameters(...): SIGN_IDS[sgn], width, Lambda (r), K (r), k (r)
    kind, width = int(cf[off]), cf[off + 1]
    for i in range(r):
        lam, K, k = cf[off + 2 + i], cf[off + 2 + r + i], cf[off + 2 + 2 * r + i]
        s = phidot[i] + lam * phi[i]
        out[i] = -lam * phidot[i] - K * s - k * sign_function(kind, s, width)


def baumgarte_parameters(d: float, omega: float) -> list[float]:
    """The numbers ``baumgarte_bias`` reads: 2 d w, w^2."""
    return [2.0 * d * omega, omega ** 2]


def sliding_mode_parameters(Lambda, K, k, sgn: str, width: float, r: int) -> np.ndarray:
    """The numbers ``sliding_mode_bias`` reads for r constraints: the sgn approximation's id, its width, then
    Lambda, K and k (each a scalar or one value per constraint) broadcast to r values each."""
    cf = np.empty(2 + 3 * r)
    cf[0], cf[1] = SIGN_IDS[sgn], width
    for i, v in enumerate((Lambda, K, k)):
        cf[2 + i * r:2 + (i + 1) * r] = v
    return cf


def apply_bias(law, parameters: list[float], phi, phidot) -> np.ndarray:
    """b = ``law``(phi, phidot) with its ``parameters``: the compiled law called from Python (the reference path)."""
    phi = np.ascontiguousarray(phi, dtype=float)
    out = np.empty(phi.size)
    law(phi, np.ascontiguousarray(phidot, dtype=float), np.asarray(parameters, dtype=float), 0, out)
    return out
