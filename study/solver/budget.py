"""A run's evaluation budget, projected from its recent pace: stop early a run that cannot finish.

``max_evaluations`` bounds a run's right-hand-side evaluations; reached, it stops the run. A run that
chatters (plain sgn friction under an adaptive integrator) or is far too stiff for its integrator reaches
it only after minutes to half an hour. :class:`Budget` measures how far t advanced over each window of
``budget_window_fraction * max_evaluations`` evaluations and projects the total at that pace; when
``budget_windows`` windows in a row each project more than ``max_evaluations``, the run is stopped then,
with the estimate (reference/tolerances.toml gives both numbers and their reasons).
"""

from __future__ import annotations

from study.errors import RunBoundError
from study.reference_data import tolerance


class Budget:
    def __init__(self, t_end: float, max_evaluations: float):
        self.t_end, self.max_evaluations = float(t_end), float(max_evaluations)
        self.window = max(1, int(tolerance("budget_window_fraction") * max_evaluations))
        self.windows = int(tolerance("budget_windows"))
        self.t_reached = self.t_start = 0.0
        self.over = 0     # consecutive windows whose pace projects more than max_evaluations
        self.first_over = (0, 0.0)   # (evaluations, t) where the first of them began

    def update(self, nfev: int, t: float, name: str, note: str = "") -> None:
        """Called with each evaluation's count and time; raises RunBoundError when the pace cannot finish."""
        if t > self.t_reached:
            self.t_reached = t
        if nfev == 0 or nfev % self.window:
            return
        advanced = self.t_reached - self.t_start
        projected = nfev + (self.t_end - self.t_reached) * self.window / max(advanced, 1e-300)
        self.over = self.over + 1 if projected > self.max_evaluations else 0
        if self.over == 1:
            self.first_over = (nfev - self.window, self.t_start)
        self.t_start = self.t_reached
        if self.over >= self.windows:
            n0, t0 = self.first_over
            span, advanced = nfev - n0, self.t_reached - t0
            estimate = nfev + (self.t_end - self.t_reached) * span / max(advanced, 1e-300)
            raise RunBoundError(
                f"{name}: stopped at t = {self.t_reached:.9g} s after {nfev} evaluations: the last {span} advanced t by "
                f"{advanced:.3g} s; at that pace reaching t_end = {self.t_end:g} s would take an estimated "
                f"{estimate:.3g} evaluations, above max_evaluations = {self.max_evaluations:g} (a chattering or far "
                f"too stiff run; max_evaluations= raises the bound)" + note, t=self.t_reached, quantity="evaluations",
                evaluations=nfev, estimate=estimate)
