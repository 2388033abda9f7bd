"""Time integration: scipy's OdeSolver methods and a fixed-step RK4, with located switches.

One stepping loop serves every method (``INTEGRATORS``). After each accepted step it

1. checks the switching functions of discontinuous loads; if one changed sign, the crossing is
   located on the step's dense output (Brent), the solution is cut there, the load's mode is
   flipped and the integrator restarts from the event (so the switch is located, not smeared);
2. applies the post-step correction (projection), if the stabilization has one;
3. samples the requested output times from the step's dense output.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.integrate import DOP853, LSODA, RK23, RK45, DenseOutput, OdeSolver, Radau
from scipy.optimize import brentq

from study.errors import RunBoundError
from study.reference_data import tolerance

Array = np.ndarray


class HermiteDense(DenseOutput):
    """Cubic Hermite interpolant on one step from y and f at both ends."""

    def __init__(self, t_old, t, y_old, y, f_old, f):
        super().__init__(t_old, t)
        self.h = t - t_old
        self.y_old, self.y, self.f_old, self.f = y_old, y, f_old, f

    def _call_impl(self, t):
        s = (np.atleast_1d(t) - self.t_old) / self.h
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        out = (np.outer(self.y_old, h00) + np.outer(self.f_old * self.h, h10)
               + np.outer(self.y, h01) + np.outer(self.f * self.h, h11))
        return out if np.ndim(t) else out[:, 0]


class RK4(OdeSolver):
    """Classical fixed-step fourth-order Runge-Kutta (what the papers' MATLAB runs likely used).

    ``first_step`` is the fixed step h; the last step is shortened to hit ``t_bound``.
    """

    A = (0.5, 0.5, 1.0)
    B = np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6])

    def __init__(self, fun, t0, y0, t_bound, first_step=None, vectorized=False, **extraneous):
        super().__init__(fun, t0, y0, t_bound, vectorized, support_complex=False)
        if first_step is None or not first_step > 0:
            raise ValueError(f"RK4 needs a fixed step h > 0 (first_step), got {first_step!r}")
        self.h = float(first_step)
        self.f = self.fun(self.t, self.y)
        self._old = None

    def _step_impl(self):
        t, y, f = self.t, self.y, self.f
        h = min(self.h, self.t_bound - t) if self.direction > 0 else self.h
        k1 = f
        k2 = self.fun(t + 0.5 * h, y + 0.5 * h * k1)
        k3 = self.fun(t + 0.5 * h, y + 0.5 * h * k2)
        k4 = self.fun(t + h, y + h * k3)
        y_new = y + h * (self.B[0] * k1 + self.B[1] * k2 + self.B[2] * k3 + self.B[3] * k4)
        self._old = (t, y, f)
        self.t, self.y = t + h, y_new
        self.f = self.fun(self.t, y_new)  # first stage of the next step, reused
        return True, None

    def _dense_output_impl(self):
        t_old, y_old, f_old = self._old
        return HermiteDense(t_old, self.t, y_old, self.y, f_old, self.f)


INTEGRATORS: dict[str, type[OdeSolver]] = {
    "RK45": RK45,
    "DOP853": DOP853,
    "RK23": RK23,
    "Radau": Radau,
    "LSODA": LSODA,
    "RK4": RK4,
}
# Methods whose state may be replaced between steps (projection): y plus the cached first stage f.
PROJECTABLE = ("RK45", "DOP853", "RK23", "RK4")
# Brent's root finder locates a switch to xtol + rtol |t| (scipy's brentq with its finest rtol).
BRENT_XTOL, BRENT_RTOL = 1e-14, 4 * np.finfo(float).eps
MAX_EVENTS = 100_000  # more switches than this in one run means chattering on a switching surface


SCAN_POINTS = 16  # interpolant samples that find the return to the mode's side (see _first_crossing)


def _first_crossing(g: Callable[[float], float], sign: int, t_lo: float, t_hi: float) -> float:
    """The first time in [t_lo, t_hi] at which g leaves the side ``sign`` (g(t_hi) * sign < 0).

    Normally g(t_lo) is on the side ``sign`` and Brent's method brackets [t_lo, t_hi]. The step can
    also start on the far side: right after a located switch g(t_lo) is zero up to round-off and may
    carry the old sign, and a post-step projection moves the state (a position by ~1e-6 m at rtol 1e-4) and
    can take it back across the switching surface. Then g is sampled at ``SCAN_POINTS`` points:

    * if it comes back to the side ``sign`` and leaves it again within the step (a second crossing,
      seen at loose tolerances where a step spans a reversal), that later crossing is bracketed;
    * if it stays on the far side throughout, the switch is at t_lo: the state the step starts from
      is already across, so the mode flips there.

    Raises ValueError (from brentq) only if no bracket exists at all.
    """
    if g(t_lo) * sign >= 0:
        return brentq(g, t_lo, t_hi, xtol=BRENT_XTOL, rtol=BRENT_RTOL)
    ts = np.linspace(t_lo, t_hi, SCAN_POINTS + 1)
    side = np.array([g(s) * sign for s in ts])
    back = np.flatnonzero(side[1:] >= 0)
    if back.size == 0:
        return t_lo
    j = back[0] + 1
    away = np.flatnonzero(side[j:] < 0)
    if away.size == 0:
        raise ValueError(f"the interpolant returns to the side {sign:+d} at t = {ts[j]:.9g} s and stays there")
    leave = j + away[0]
    return brentq(g, ts[leave - 1], ts[leave], xtol=BRENT_XTOL, rtol=BRENT_RTOL)


@dataclass
class Trajectory:
    """Raw integrator output: samples, the mode at each sample, events and statistics."""

    t: Array
    y: Array
    modes: list
    events: list = field(default_factory=list)
    steps: int = 0
    restarts: int = 0
    projections: int = 0


def initial_mode(indicators: Callable[[float, Array], Array] | None, t0: float, y0: Array,
                 rhs: Callable) -> tuple | None:
    """Signs of the switching functions at t0; a zero takes the sign it has just after t0."""
    if indicators is None:
        return None
    g = np.asarray(indicators(t0, y0))
    mode = np.where(g >= 0, 1, -1)
    if np.any(g == 0):
        dt = 1e-9
        g_ahead = np.asarray(indicators(t0 + dt, y0 + dt * rhs(t0, y0, tuple(mode))))
        mode = np.where(g == 0, np.where(g_ahead >= 0, 1, -1), mode)
    return tuple(int(s) for s in mode)


def integrate(
    rhs: Callable[[float, Array, tuple | None], Array],
    t0: float,
    y0: Array,
    t_end: float,
    t_out: Array,
    method: str = "RK45",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    step: float | None = None,
    indicators: Callable[[float, Array], Array] | None = None,
    post_step: Callable[[Array], tuple[Array, bool]] | None = None,
    progress: Callable[[float], None] | None = None,
    switching=None,
    monitor: Callable[[float, Array], None] | None = None,
    min_step: float | None = None,
    describe: Callable[[float, Array], str] | None = None,
) -> Trajectory:
    """Integrate y' = rhs(t, y, mode) from t0 to t_end and sample it at ``t_out``.

    Parameters
    ----------
    method : str
        A key of ``INTEGRATORS``. 'RK4' needs ``step``; the others use rtol/atol (``step``, if
        given, is their first step).
    indicators : callable (t, y) -> (k,), optional
        Switching functions; the mode passed to ``rhs`` is the tuple of their signs, frozen
        between located zero crossings.
    post_step : callable y -> (y, changed), optional
        Correction after every accepted step (projection). Only for methods in ``PROJECTABLE``.
    switching : object, optional
        A switching rule whose modes are more than the indicators' signs (stick/slip friction,
        ``study.solver.friction.StickSlipSwitching``); use it instead of ``indicators``. It provides

        1. ``initial_mode(t0, y0) -> tuple`` of +-1;
        2. ``indicators(t, y, mode) -> (k,)`` whose signs equal ``mode`` while that mode holds;
        3. ``on_event(t, y, mode, i) -> tuple``, the mode after indicator ``i`` crossed zero at (t, y).

        Without it, the mode is the indicators' signs and a crossing flips the crossing entry.
    monitor : callable (t, y) -> None, optional
        Called at t0 and after every accepted step; it raises to stop the run (singular pose).
    min_step : float, optional
        Smallest step an adaptive method may keep taking before the end of the run: ``min_step_run``
        (reference/tolerances.toml) accepted steps in a row below it stop the run with a
        :class:`study.errors.RunBoundError` (a stall near a singularity). Single small steps are
        normal: LSODA starts (and restarts after a switch) with steps of ~1e-12 s.
    describe : callable (t, y) -> str, optional
        Extra text for the error of a failed step (e.g. the singularity measure at that pose).
    """
    if method not in INTEGRATORS:
        raise ValueError(f"unknown integrator {method!r}; valid choices: {', '.join(INTEGRATORS)}")
    if post_step is not None and method not in PROJECTABLE:
        raise ValueError(f"post-step projection needs an integrator whose state can be replaced between steps "
                         f"({', '.join(PROJECTABLE)}); got {method!r}")
    cls = INTEGRATORS[method]
    if switching is not None:
        if indicators is not None:
            raise ValueError("give either indicators or switching, not both (a switching rule has its own indicators)")
        mode = tuple(switching.initial_mode(t0, np.array(y0, dtype=float)))

        def indicators(tt, yy):  # the current mode is read when called, so it follows every switch
            return switching.indicators(tt, yy, mode)
    else:
        mode = initial_mode(indicators, t0, y0, rhs)
    t_out = np.asarray(t_out, dtype=float)
    samples_t, samples_y, modes = [], [], []
    k_out = 0
    traj = Trajectory(np.empty(0), np.empty((0, len(y0))), [])

    def sample(dense, t_lo, t_hi, inclusive_lo):
        nonlocal k_out
        while k_out < len(t_out) and (t_out[k_out] < t_hi or np.isclose(t_out[k_out], t_hi, rtol=0, atol=1e-12 * max(1, abs(t_hi)))):
            tk = t_out[k_out]
            if tk < t_lo and not inclusive_lo:
                k_out += 1
                continue
            yk = dense(tk) if dense is not None else y_cur
            if post_step is not None:
                yk = post_step(yk)[0]
            samples_t.append(tk)
            samples_y.append(yk)
            modes.append(mode)
            k_out += 1

    t, y_cur = float(t0), np.array(y0, dtype=float)
    if monitor is not None:
        monitor(t, y_cur)
    sample(None, t, t, True)

    def stop(reason: str, t_now: float, y_now: Array, h: float) -> RunBoundError:
        extra = describe(t_now, y_now) if describe is not None else ""
        return RunBoundError(f"{method} stopped at t = {t_now:.9g} s after {traj.steps} steps: {reason}"
                             f"{'; ' + extra if extra else ''}", t=float(t_now), quantity="step", step=h, steps=traj.steps)
    options = {"rtol": rtol, "atol": atol} if method != "RK4" else {}
    if step is not None:
        options["first_step"] = step
    small_run, small_limit = 0, int(tolerance("min_step_run"))
    while t < t_end:
        solver = cls(lambda tt, yy: rhs(tt, yy, mode), t, y_cur, t_end, **options)
        traj.restarts += 1
        event_hit = False
        while solver.status == "running":
            t_old = solver.t
            message = solver.step()
            if solver.status == "failed":
                raise stop(f"{message} (step size collapsed)", t_old, solver.y, getattr(solver, "h_abs", 0.0))
            h_taken = solver.t - t_old
            traj.steps += 1
            small = min_step is not None and solver.status == "running" and method != "RK4" and h_taken < min_step
            small_run = small_run + 1 if small else 0
            if small_run >= small_limit:
                raise stop(f"{small_run} steps in a row below min_step = {min_step:.3g} s (the last h = {h_taken:.3g} s; "
                           f"a stall: the solution is near a singularity or a discontinuity; min_step= overrides)",
                           solver.t, solver.y, h_taken)
            dense = solver.dense_output()
            if indicators is not None:
                g_new = np.asarray(indicators(solver.t, solver.y))
                flipped = [i for i, g in enumerate(g_new) if g * mode[i] < 0]
                if flipped:
                    try:
                        roots = [(_first_crossing(lambda s, i=i: indicators(s, dense(s))[i], mode[i], t_old,
                                                  solver.t), i) for i in flipped]
                    except ValueError as exc:  # no sign change on the step's interpolant: it is not resolved
                        raise stop(f"the switch of switching function(s) {flipped} cannot be located within the "
                                   f"step from t = {t_old:.9g} s ({exc}): the step h = {solver.t - t_old:.3g} s is too "
                                   f"large for the solution (use a smaller step or an adaptive integrator)",
                                   solver.t, solver.y, solver.t - t_old) from None
                    t_e, i_e = min(roots)
                    sample(dense, t_old, t_e, False)
                    y_cur = dense(t_e)
                    t = t_e
                    if switching is not None:
                        mode = tuple(switching.on_event(t_e, y_cur, mode, i_e))
                    else:
                        new_mode = list(mode)
                        new_mode[i_e] = -new_mode[i_e]
                        mode = tuple(new_mode)
                    traj.events.append({"t": t_e, "indicator": i_e, "new_sign": mode[i_e]})
                    if len(traj.events) > MAX_EVENTS:
                        raise RuntimeError(f"more than {MAX_EVENTS} switches by t = {t_e:.9g}: the solution chatters "
                                           f"on switching function {i_e}")
                    event_hit = True
                    break
            sample(dense, t_old, solver.t, False)
            if post_step is not None:
                y_new, changed = post_step(solver.y)
                if changed:
                    traj.projections += 1
                    solver.y = y_new
                    solver.f = solver.fun(solver.t, y_new)
            t, y_cur = solver.t, solver.y
            if monitor is not None:
                monitor(t, y_cur)
            if progress is not None:
                progress(t)
        if not event_hit:
            break
    if k_out < len(t_out):  # the last output time equals t_end
        sample(None, t, t + 1e-300, True)
    traj.t = np.asarray(samples_t)
    traj.y = np.asarray(samples_y)
    traj.modes = modes
    return traj
