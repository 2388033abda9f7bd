"""Event location: the first time within a step at which a switching function leaves the side of the mode.

:func:`crossing_finder` gives the law for a switching function g(t, *args) on a step's interpolant. The compiled loop
(``study.fast.loop``) compiles it for its compiled g (``internal()(crossing_finder(g))``: g is then a constant of the
compiled code, called directly, so the loop stays cacheable, which a function passed as an argument would not); the
reference loop (``study.solver.integrate``) runs it as Python with a closure over scipy's dense output. Brent's method
in it is scipy's ``brentq`` algorithm (``scipy/optimize/Zeros/brentq.c``), line for line, with the same tolerances,
so both loops locate a switch at the same root.
"""

from __future__ import annotations

import numpy as np

# Brent's root finder locates a switch to xtol + rtol |t| (scipy's brentq with its finest rtol).
BRENT_XTOL, BRENT_RTOL = 1e-14, 4 * np.finfo(float).eps
BRENT_MAXITER = 100   # scipy's brentq default: Brent converges in far fewer at these tolerances
SCAN_POINTS = 16      # interpolant samples that find the return to the mode's side (see crossing_finder)


def crossing_finder(g):
    """The law of event location for the switching function g(t, *args): the function ``first_crossing(sign, t_lo,
    t_hi, *args)`` below, with g fixed (compile it with ``study.kernels.cache.internal`` for a compiled g)."""

    def first_crossing(sign, t_lo, t_hi, *args):
        """The first time in [t_lo, t_hi] at which g(t, *args) leaves the side ``sign`` (g(t_hi) * sign < 0), or NaN.

        Normally g(t_lo) is on the side ``sign`` and Brent's method brackets [t_lo, t_hi]. The step can also start on
        the far side: right after a located switch g(t_lo) is zero up to round-off and may carry the old sign, and a
        post-step projection moves the state (a position by ~1e-6 m at rtol 1e-4) and can take it back across the
        switching surface. Then g is sampled at ``SCAN_POINTS`` points t_lo + (t_hi - t_lo) k / SCAN_POINTS:

        * if it comes back to the side ``sign`` and leaves it again within the step (a second crossing, seen at loose
          tolerances where a step spans a reversal), that later crossing is bracketed;
        * if it stays on the far side throughout, the switch is at t_lo: the state the step starts from is already
          across, so the mode flips there.

        NaN means the crossing cannot be located: g comes back to the side ``sign`` and stays there, the bracket shows
        no sign change, g is NaN, or Brent's method does not converge in ``BRENT_MAXITER`` iterations (where scipy's
        brentq raises).
        """
        xpre, xcur = t_lo, t_hi
        if g(t_lo, *args) * sign < 0:
            back, leave = 0, 0
            for k in range(1, SCAN_POINTS + 1):
                side = g(t_lo + (t_hi - t_lo) * k / SCAN_POINTS, *args) * sign
                if back == 0 and side >= 0:     # back on the side sign
                    back = k
                elif back > 0 and side < 0:     # and away from it again
                    leave = k
                    break
            if back == 0:
                return t_lo
            if leave == 0:
                return np.nan
            xpre, xcur = t_lo + (t_hi - t_lo) * (leave - 1) / SCAN_POINTS, t_lo + (t_hi - t_lo) * leave / SCAN_POINTS
        # Brent's method on [xpre, xcur] (scipy's brentq)
        xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
        fpre, fcur = g(xpre, *args), g(xcur, *args)
        if np.isnan(fpre) or np.isnan(fcur):
            return np.nan
        if fpre == 0.0:
            return xpre
        if fcur == 0.0:
            return xcur
        if np.signbit(fpre) == np.signbit(fcur):
            return np.nan
        for _ in range(BRENT_MAXITER):
            if fpre != 0.0 and fcur != 0.0 and (np.signbit(fpre) != np.signbit(fcur)):
                xblk, fblk = xpre, fpre
                spre = scur = xcur - xpre
            if abs(fblk) < abs(fcur):
                xpre, xcur, xblk = xcur, xblk, xcur
                fpre, fcur, fblk = fcur, fblk, fcur
            delta = (BRENT_XTOL + BRENT_RTOL * abs(xcur)) / 2
            sbis = (xblk - xcur) / 2
            if fcur == 0.0 or abs(sbis) < delta:
                return xcur
            if abs(spre) > delta and abs(fcur) < abs(fpre):
                if xpre == xblk:
                    stry = -fcur * (xcur - xpre) / (fcur - fpre)
                else:
                    dpre, dblk = (fpre - fcur) / (xpre - xcur), (fblk - fcur) / (xblk - xcur)
                    stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
                if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                    spre, scur = scur, stry
                else:
                    spre, scur = sbis, sbis
            else:
                spre, scur = sbis, sbis
            xpre, fpre = xcur, fcur
            xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
            fcur = g(xcur, *args)
            if np.isnan(fcur):
                return np.nan
        return np.nan

    return first_crossing
