"""Friction levels, phases and switching functions: the size of a Coulomb force or torque, a pin's smooth reaction
norm, the stick flags and slip factors of each friction treatment (paper 000 eqs. 3, 32; SPEC sec. 1), and the exact
treatment's switching functions of an entry (its margin to the static limit while stuck, its velocity while sliding).

Every function is compiled (``study.kernels.cache.kernel``). The compiled loop calls them natively; the reference
path calls the same compiled functions (``study.solver.friction``), and the Exudyn user functions run
:func:`friction_level` and :func:`pin_norm` as their Python source (``py_func``), on scalars or arrays.

The phases functions have the signature ``study.kernels.signatures.PHASES``: (mode, n_load_modes, v_t, cf, offset,
stick, s) fills the stick flags and slip factors s (f = -s (R + mu_k |N|) in slip) of the contacts, then the pins,
reading the treatment's numbers at ``cf[offset:]``. The treatments that name them are the classes of
``study.solver.friction.laws``. :func:`switching_pair` has the signature :data:`SWITCHING`, so the reference's rule
(``study.solver.friction.switching``) calls the compiled function that the compiled loop (``study.fast.loop``) links.
"""

from __future__ import annotations

import numpy as np
from numba import types

from study.kernels.cache import kernel
from study.kernels.signatures import PHASES, V1, f8, i8
from study.kernels.signs import sign_function


@kernel()
def friction_level(coefficient, normal, constant):
    """The size of a Coulomb force or torque, constant + coefficient |normal|: a contact's R + mu |N| [N], a pin's
    T0 + mu r |R|_delta [N m]; with the static coefficient, the limit a stuck entry holds. Scalars (compiled) or
    arrays (``.py_func``)."""
    return constant + coefficient * np.abs(normal)


@kernel()
def pin_norm(rx, ry, delta):
    """|R|_delta = sqrt(Rx^2 + Ry^2 + delta^2) of a pin's reaction (delta: ``pin_friction_norm_width``), the smooth
    norm that replaces |R|'s kink at R = 0 in the pin's friction torque. Scalars or arrays (``.py_func``)."""
    return np.sqrt(rx * rx + ry * ry + delta * delta)


@kernel(PHASES)
def mode_phases(mode, nlm, vt, cf, off, stick, s):
    """The exact treatment: the mode holds the loads' nlm entries, then per entry (+1 stick / -1 slip, the frozen
    sliding direction); a stuck entry has s = 0, a sliding one its direction. No parameters (``vt``: only its size)."""
    for j in range(vt.size):
        stick[j] = mode[nlm + 2 * j] > 0
        s[j] = 0.0 if stick[j] else float(mode[nlm + 2 * j + 1])


@kernel(PHASES)
def slip_phases(mode, nlm, vt, cf, off, stick, s):
    """A treatment without a true stick ('regularized', 'sign'): nothing sticks, s = sgn_approx(v_t, eps) with
    cf[off:] = (``study.kernels.signs.SIGN_IDS`` of the approximation, eps). ``mode`` is not read."""
    kind, eps = int(cf[off]), cf[off + 1]
    for j in range(vt.size):
        stick[j] = False
        s[j] = sign_function(kind, vt[j], eps)


@kernel()
def stuck_margin(level, force):
    """How far a stuck entry is from slipping: level - |force|, its static limit (:func:`friction_level` with the
    static coefficient) less the force (torque) holding it; >= 0 while it holds. Scalars or arrays (``.py_func``)."""
    return level - np.abs(force)


#: switching_pair(stuck, level, force, direction, velocity, out, at)
SWITCHING = types.void(types.boolean, f8, f8, f8, f8, V1, i8)


@kernel(SWITCHING)
def switching_pair(stuck, level, force, direction, velocity, out, at):
    """An entry's two switching functions of the exact treatment, whose signs are its mode entries (+1 stick / -1
    slip, the sliding direction +-1) while the mode holds, to out[at] and out[at + 1]: stuck, the margin
    :func:`stuck_margin` (crosses zero when the static limit is reached), sliding, -direction * velocity (crosses zero
    when the entry comes to rest); then the constant direction, which never crosses. ``level`` is read only when stuck
    (a contact's c R + mu_s |N|, a pin's T0 + mu_s r |R|_delta), ``velocity`` (v_t, a pin's omega) only when sliding."""
    out[at] = stuck_margin(level, force) if stuck else -direction * velocity
    out[at + 1] = direction
