"""The guarded reading of a joint reaction inside a user function, and the regularized guide friction built on it."""

from __future__ import annotations

import math
from typing import Callable

import exudyn as exu

from study.exudyn_models.building import Model
from study.exudyn_models.settings import SEED_MAX_ITERATIONS, SEED_TOLERANCE

OVT = exu.OutputVariableType


class ReactionGuard:
    """'Hybrid' reading of a joint reaction inside a load user function.

    ``read(mbs)`` returns the live value, i.e. the current Newton iterate of the multiplier. It is
    exactly 0 at the first Newton iteration of every step (the predictor resets the algebraic
    coordinates) and during the initial-acceleration solve. The guard then returns the value of the
    last accepted step instead (``accepted``, updated in a post-step function); otherwise it returns
    the live value, so the converged step uses the converged reaction (no lag).
    """

    def __init__(self, read: Callable[[exu.MainSystem], float]):
        self.read = read
        self.accepted: float | None = None
        self.calls = 0
        self.substitutions = 0

    def value(self, mbs) -> float:
        live = self.read(mbs)
        self.calls += 1
        if live == 0.0 and self.accepted is not None:
            self.substitutions += 1
            return self.accepted
        return live

    def accept(self, mbs, t=None) -> None:
        self.accepted = self.read(mbs)


class GuideFriction:
    """Regularized Coulomb friction plus constant resistance at a point sliding along a fixed axis.

    Tangential force on the slider at its point (along the unit ``axis``, global frame):
    ``coulomb = -mu |N| tanh(v/eps)``, ``resistance = -F tanh(v/eps)``, with v = axis . (velocity of
    the slider point, from the point's marker) and N the guide's normal reaction from ``guard``. The
    values of the last user-function call of each step (the converged residual evaluation) are recorded
    in ``history`` (one row per step plus the initial-acceleration solve at t = 0):
    [N used, v, coulomb, resistance].
    """

    def __init__(self, model: Model, marker: int, axis, guard: ReactionGuard, mu: float, resistance: float,
                 eps: float):
        self.marker = marker
        self.axis = (float(axis[0]), float(axis[1]))
        self.guard = guard
        self.mu, self.resistance, self.eps = float(mu), float(resistance), float(eps)
        self.last = (float("nan"),) * 4
        self.history: list[tuple[float, ...]] = []
        model.pre_step.append(self._pre_step)
        model.post_step.append(self._post_step)

    def __call__(self, mbs, t, load_vector):
        vel = mbs.GetMarkerOutput(self.marker, OVT.Velocity)
        v = self.axis[0] * vel[0] + self.axis[1] * vel[1]
        n = self.guard.value(mbs)
        s = math.tanh(v / self.eps)
        coulomb, resistance = -self.mu * abs(n) * s, -self.resistance * s
        self.last = (n, v, coulomb, resistance)
        f = coulomb + resistance
        return [f * self.axis[0], f * self.axis[1], 0.0]

    def _pre_step(self, mbs, t) -> None:
        if not self.history:           # before the first step: the initial-acceleration evaluation
            self.history.append(self.last)

    def _post_step(self, mbs, t) -> None:
        self.history.append(self.last)
        self.guard.accept(mbs)

    def reset(self) -> None:
        self.history.clear()
        self.last = (float("nan"),) * 4
        self.guard.calls = self.guard.substitutions = 0


def initialize(model: Model, settings: exu.SimulationSettings, read: Callable[[], object]):
    """Run only Exudyn's solver initialization at the initial state and return ``read()``.

    The initialization computes the initial accelerations and multipliers (with
    ``computeInitialAccelerations``) exactly as SolveDynamic does before its first step.
    """
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(model.mbs, settings)
    try:
        return read()
    finally:
        solver.FinalizeSolver(model.mbs, settings)


def seed_reaction_guards(model: Model, settings: exu.SimulationSettings, frictions: list[GuideFriction]) -> dict:
    """Make the initial-acceleration solve use the consistent normal force.

    At t = 0 Exudyn computes the initial accelerations with all multipliers 0, so a friction law
    reading the reaction would see N = 0 and the initial accelerations (and the generalized-alpha
    start) would miss the friction. This fixed-point iteration runs only Exudyn's solver
    initialization repeatedly, each time feeding the guards the normal forces of the previous
    initialization, until they no longer change. Purely Exudyn: no in-house quantity enters.

    Returns
    -------
    dict with 'seed_iterations' and 'seed_change' (last relative change of N); empty without friction.
    """
    if not frictions:
        return {}
    change = float("inf")
    it = 0
    for it in range(1, SEED_MAX_ITERATIONS + 1):
        new = initialize(model, settings, lambda: [f.guard.read(model.mbs) for f in frictions])
        change = max(abs(n - (f.guard.accepted if f.guard.accepted is not None else 0.0)) / max(abs(n), 1e-300)
                     for n, f in zip(new, frictions))
        for n, f in zip(new, frictions):
            f.guard.accepted = n
        if change <= SEED_TOLERANCE:
            break
    for f in frictions:
        f.reset()
    return {"seed_iterations": it, "seed_change": float(change)}
