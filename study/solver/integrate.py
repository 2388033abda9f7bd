"""Time integration: scipy's OdeSolver methods and a fixed-step RK4, with located switches.

One stepping loop serves every method (``INTEGRATORS``). After each accepted step it

1. checks the switching functions; if one left its mode's side, the crossing is located on the
   step's dense output (``study.laws.events.crossing_finder``: a scan, then Brent's method, run as
   Python), the solution is cut there, the mode switches (``study.laws.modes.switch``) and the
   integrator restarts from the event (so the switch is located, not smeared);
2. applies the post-step correction (projection), if the stabilization has one;
3. samples the requested output times from the step's dense output.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.integrate import DOP853, LSODA, RK23, RK45, DenseOutput, OdeSolver, Radau

from study.errors import RunBoundError
from study.laws.events import crossing_finder
from study.laws.modes import as_mode, initial_mode, switch
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
    if switching is not None and indicators is not None:
        raise ValueError("give either indicators or switching, not both (a switching rule has its own indicators)")
    options = {"rtol": rtol, "atol": atol} if method != "RK4" else {}
    if step is not None:
        options["first_step"] = step
    run = _Run(rhs, method, options, np.asarray(t_out, dtype=float), post_step, monitor, progress, min_step, describe)
    run.start(float(t0), np.array(y0, dtype=float), indicators, switching)
    return run.until(t_end)


class _Run:
    """One call of :func:`integrate`: the loop's state (time, state, mode, samples, counts) and its steps."""

    def __init__(self, rhs, method, options, t_out, post_step, monitor, progress, min_step, describe):
        self.rhs, self.method, self.options, self.t_out = rhs, method, options, t_out
        self.post_step, self.monitor, self.progress, self.describe = post_step, monitor, progress, describe
        self.min_step, self.small_run, self.small_limit = min_step, 0, int(tolerance("min_step_run"))
        self.samples_t, self.samples_y, self.modes, self.k_out = [], [], [], 0
        self.traj = Trajectory(np.empty(0), np.empty((0, 0)), [])

    def start(self, t0: float, y0: Array, indicators, switching) -> None:
        """The state and mode at t0 (the switching rule's, else the indicators' signs), checked and sampled."""
        self.t, self.y, self.switching = t0, y0, switching
        if switching is not None:
            self.mode = as_mode(switching.initial_mode(t0, y0.copy()))

            def indicators(tt, yy):  # the current mode is read when called, so it follows every switch
                return switching.indicators(tt, yy, self.mode)
        else:
            self.mode = initial_mode(indicators, t0, y0, self.rhs)
        self.indicators = indicators
        if self.monitor is not None:
            self.monitor(self.t, self.y)
        self.sample(None, self.t, self.t, True)

    def until(self, t_end: float) -> Trajectory:
        """Integrate to t_end, restarting the integrator at every located switch."""
        while self.t < t_end:
            solver = INTEGRATORS[self.method](lambda tt, yy: self.rhs(tt, yy, self.mode), self.t, self.y, t_end,
                                              **self.options)
            self.traj.restarts += 1
            if not self.segment(solver):
                break
        if self.k_out < len(self.t_out):  # the last output time equals t_end
            self.sample(None, self.t, self.t + 1e-300, True)
        traj = self.traj
        traj.t, traj.y, traj.modes = np.asarray(self.samples_t), np.asarray(self.samples_y), self.modes
        return traj

    def segment(self, solver: OdeSolver) -> bool:
        """Step ``solver`` to its end (False) or to the first located switch (True: restart from there)."""
        while solver.status == "running":
            t_old = solver.t
            self.step(solver)
            dense = solver.dense_output()
            if self.indicators is not None and self.switched(solver, t_old, dense):
                return True
            self.sample(dense, t_old, solver.t, False)
            if self.post_step is not None:
                y_new, changed = self.post_step(solver.y)
                if changed:
                    self.traj.projections += 1
                    solver.y = y_new
                    solver.f = solver.fun(solver.t, y_new)
            self.t, self.y = solver.t, solver.y
            if self.monitor is not None:
                self.monitor(self.t, self.y)
            if self.progress is not None:
                self.progress(self.t)
        return False

    def step(self, solver: OdeSolver) -> None:
        """One accepted step of ``solver``; a failed step or a stall (``min_step``) stops the run."""
        t_old = solver.t
        message = solver.step()
        if solver.status == "failed":
            raise self.stop(f"{message} (step size collapsed)", t_old, solver.y, getattr(solver, "h_abs", 0.0))
        h_taken = solver.t - t_old
        self.traj.steps += 1
        small = (self.min_step is not None and solver.status == "running" and self.method != "RK4"
                 and h_taken < self.min_step)
        self.small_run = self.small_run + 1 if small else 0
        if self.small_run >= self.small_limit:
            raise self.stop(f"{self.small_run} steps in a row below min_step = {self.min_step:.3g} s (the last h = "
                            f"{h_taken:.3g} s; a stall: the solution is near a singularity or a discontinuity; "
                            f"min_step= overrides)", solver.t, solver.y, h_taken)

    def switched(self, solver: OdeSolver, t_old: float, dense) -> bool:
        """Whether a switching function left its mode's side in the step; if so, the earliest crossing is located
        on the step's dense output (``study.laws.events.crossing_finder``), the samples before it are taken, and
        the run moves to it in the new mode (``study.laws.modes.switch``)."""
        mode = self.mode
        g_new = np.asarray(self.indicators(solver.t, solver.y))
        flipped = [i for i, g in enumerate(g_new) if g * mode[i] < 0]
        if not flipped:
            return False
        roots = [(float(crossing_finder(lambda s, i=i: self.indicators(s, dense(s))[i])(mode[i], t_old, solver.t)), i)
                 for i in flipped]
        lost = [i for root, i in roots if np.isnan(root)]
        if lost:  # no sign change on the step's interpolant: it is not resolved
            raise self.stop(f"the switch of switching function(s) {lost} cannot be located within the step from "
                            f"t = {t_old:.9g} s (its interpolant returns to the side it started on and stays there, "
                            f"or shows no sign change): the step h = {solver.t - t_old:.3g} s is too large for the "
                            f"solution (use a smaller step or an adaptive integrator)",
                            solver.t, solver.y, solver.t - t_old)
        t_e, i_e = min(roots)
        self.sample(dense, t_old, t_e, False)
        self.t, self.y = t_e, dense(t_e)
        self.mode = switch(self.switching, t_e, self.y, mode, i_e, self.traj.events)
        return True

    def sample(self, dense, t_lo: float, t_hi: float, inclusive_lo: bool) -> None:
        """The output times up to t_hi (from t_lo, or after it) from ``dense``, or the current state (None)."""
        t_out = self.t_out
        while self.k_out < len(t_out) and (t_out[self.k_out] < t_hi or np.isclose(
                t_out[self.k_out], t_hi, rtol=0, atol=1e-12 * max(1, abs(t_hi)))):
            tk = t_out[self.k_out]
            self.k_out += 1
            if tk < t_lo and not inclusive_lo:
                continue
            yk = dense(tk) if dense is not None else self.y
            if self.post_step is not None:
                yk = self.post_step(yk)[0]
            self.samples_t.append(tk)
            self.samples_y.append(yk)
            self.modes.append(self.mode)

    def stop(self, reason: str, t_now: float, y_now: Array, h: float) -> RunBoundError:
        """The error that ends the run at t_now: ``reason``, with ``describe``'s note on the state."""
        extra = self.describe(t_now, y_now) if self.describe is not None else ""
        return RunBoundError(f"{self.method} stopped at t = {t_now:.9g} s after {self.traj.steps} steps: {reason}"
                             f"{'; ' + extra if extra else ''}", t=float(t_now), quantity="step", step=h,
                             steps=self.traj.steps)
