"""The guarded reading of a joint reaction inside a user function, and the regularized friction laws built on it:
along a guide (:class:`GuideFriction`) and in a revolute joint (:class:`PinFrictionTorque`).

The law itself is not written here: the friction level is :func:`study.laws.friction.friction_level` (and a
pin's |R|_delta :func:`study.laws.friction.pin_norm`), run as their Python source (``py_func``) on Exudyn's scalars,
and the regularized sign tanh(v/eps) is ``study.kernels.signs.SIGN_FUNCTIONS['tanh']``, the
compiled function itself (libm's tanh, as the compiled loop; its ``py_func`` would run NumPy's tanh, which differs
from libm's by one unit in the last place at about one argument in ten).
"""

from __future__ import annotations

import math
from typing import Callable

import exudyn as exu

from study.exudyn_models.building import Model
from study.exudyn_models.settings import SEED_MAX_ITERATIONS, SEED_TOLERANCE
from study.kernels.signs import SIGN_FUNCTIONS
from study.laws.friction import friction_level, pin_norm

OVT = exu.OutputVariableType
# the output types the user functions read at every call, looked up once
_POSITION, _VELOCITY, _COORDINATES, _ANGULAR_VELOCITY = OVT.Position, OVT.Velocity, OVT.Coordinates, OVT.AngularVelocity
#: the friction laws' one home (see the module docstring)
LEVEL, NORM, SLIP = friction_level.py_func, pin_norm.py_func, SIGN_FUNCTIONS["tanh"]


def joint_friction(coefficient: float, reaction: float, delta: float, resistance: float, rate: float,
                   eps: float) -> float:
    """The regularized friction of a joint whose reaction scales it (a pin's torque, a spatial joint's torque or
    force): ``-(coefficient |R|_delta + resistance) tanh(rate / eps)``, the laws above."""
    return -LEVEL(coefficient, NORM(reaction, 0.0, delta), resistance) * SLIP(rate, eps)


def reaction_norm(obj: int, output=OVT.Force):
    """The reader of a joint's transverse reaction magnitude |R| = hypot(R_x, R_y) in ``obj``'s ``output`` (the
    planar revolute's global 'Force'; a spatial joint's 'ForceLocal', its joint frame)."""
    def read(mbs) -> float:
        f = mbs.GetObjectOutput(obj, output).tolist()
        return math.hypot(f[0], f[1])
    return read


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

    def peek(self, mbs) -> float:
        """The value :meth:`value` returns, without counting the call (a second load reading the same reaction)."""
        live = self.read(mbs)
        return self.accepted if live == 0.0 and self.accepted is not None else live

    def accept(self, mbs, t=None) -> None:
        self.accepted = self.read(mbs)


class RecordedFriction:
    """What the friction laws share: their guard, and the record of the law's values at every step.

    ``last`` holds the values of the recording user-function call; the last one of each step (the converged
    residual evaluation) is appended to ``history`` in a post-step function, which also accepts the guard's
    reaction; before the first step the initial-acceleration evaluation is recorded (t = 0).
    """

    def __init__(self, model: Model, guard: ReactionGuard, width: int):
        self.guard = guard
        self.width = width
        self.last = (float("nan"),) * width
        self.history: list[tuple[float, ...]] = []
        model.pre_step.append(self._pre_step)
        model.post_step.append(self._post_step)

    def _pre_step(self, mbs, t) -> None:
        if not self.history:           # before the first step: the initial-acceleration evaluation
            self.history.append(self.last)

    def _post_step(self, mbs, t) -> None:
        self.history.append(self.last)
        self.guard.accept(mbs)

    def reset(self) -> None:
        self.history.clear()
        self.last = (float("nan"),) * self.width
        self.guard.calls = self.guard.substitutions = 0


class GuideFriction(RecordedFriction):
    """Regularized Coulomb friction plus constant resistance at a point sliding along a guide's axis.

    Tangential force on the slider at its point (along the unit axis, global frame):
    ``coulomb = -mu |N| tanh(v/eps)``, ``resistance = -F tanh(v/eps)``, with N the guide's normal reaction from
    ``guard`` and v the sliding velocity along the axis. A guide fixed in ground (``guide`` None): ``axis`` is
    global and v = axis . (velocity of the slider point, from the point's marker). A moving guide, ``guide`` =
    (node, reference angle, marker at its centre of mass): ``axis`` is in the guide's frame and turns with it,
    v = axis . (v_S - v_G*) with v_G* = v_G + omega k x (r_S - r_G) the velocity of the guide's material point
    at the slider point, and the guide carries the opposite force at that point, applied as the force
    :meth:`guide_force` at its centre of mass and the torque :meth:`guide_torque` of its lever (the same load on
    a rigid body). The values of the last slider user-function call of each step (the converged residual
    evaluation) are recorded in ``history`` (one row per step plus the initial-acceleration solve at t = 0):
    [N used, v, coulomb, resistance].
    """

    def __init__(self, model: Model, marker: int, axis, guard: ReactionGuard, mu: float, resistance: float,
                 eps: float, guide: tuple[int, float, int] | None = None):
        super().__init__(model, guard, 4)
        self.marker = marker
        self.axis = (float(axis[0]), float(axis[1]))
        self.mu, self.resistance, self.eps = float(mu), float(resistance), float(eps)
        self._resistance_level = LEVEL(0.0, 0.0, self.resistance)
        self.guide = guide

    def __call__(self, mbs, t, load_vector):
        if self.guide is not None:
            f, axis, _ = self._moving(mbs, record=True)
            return [f * axis[0], f * axis[1], 0.0]
        vx, vy, _ = mbs.GetMarkerOutput(self.marker, _VELOCITY).tolist()
        ax, ay = self.axis
        v = ax * vx + ay * vy
        n = self.guard.value(mbs)
        coulomb, resistance = self.law(n, v)
        self.last = (n, v, coulomb, resistance)
        f = coulomb + resistance
        return [f * ax, f * ay, 0.0]

    def law(self, n: float, v: float) -> tuple[float, float]:
        """(Coulomb part, resistance) of the tangential force at normal force n and sliding velocity v: the level
        mu |N| and the level R (constant: evaluated once, in ``__init__``), each times -tanh(v/eps)."""
        s = SLIP(v, self.eps)
        return -LEVEL(self.mu, n, 0.0) * s, -self._resistance_level * s

    def _moving(self, mbs, record: bool):
        """(tangential force f on the slider, global axis, lever r_S - r_G) at the current state, moving guide."""
        node, reference, com = self.guide
        angle = reference + mbs.GetNodeOutput(node, _COORDINATES).tolist()[2]
        omega = mbs.GetNodeOutput(node, _ANGULAR_VELOCITY).tolist()[2]
        c, s_ = math.cos(angle), math.sin(angle)
        ax, ay = self.axis
        axis = (c * ax - s_ * ay, s_ * ax + c * ay)
        get = mbs.GetMarkerOutput
        rs, vs = get(self.marker, _POSITION).tolist(), get(self.marker, _VELOCITY).tolist()
        rg, vg = get(com, _POSITION).tolist(), get(com, _VELOCITY).tolist()
        lever = (rs[0] - rg[0], rs[1] - rg[1])
        v = axis[0] * (vs[0] - vg[0] + omega * lever[1]) + axis[1] * (vs[1] - vg[1] - omega * lever[0])
        n = self.guard.value(mbs) if record else self.guard.peek(mbs)
        coulomb, resistance = self.law(n, v)
        if record:
            self.last = (n, v, coulomb, resistance)
        return coulomb + resistance, axis, lever

    def guide_force(self, mbs, t, load_vector):
        """The reaction on a moving guide at its centre of mass: minus the slider's force (global frame)."""
        f, axis, _ = self._moving(mbs, record=False)
        return [-f * axis[0], -f * axis[1], 0.0]

    def guide_torque(self, mbs, t, load_vector):
        """The moment of the reaction about the guide's centre of mass: (r_S - r_G) x (-f axis)."""
        f, axis, lever = self._moving(mbs, record=False)
        return [0.0, 0.0, -f * (lever[0] * axis[1] - lever[1] * axis[0])]


class PinFrictionTorque(RecordedFriction):
    """Regularized Coulomb friction of a revolute joint between bodies a and b (either may be ground).

    Torque on body a (and its opposite on body b): ``tau = -(mu r |R|_delta + T0) tanh(omega_rel / eps)``,
    ``|R|_delta = sqrt(|R|^2 + delta^2)``, with |R| the magnitude of the joint's reaction from ``guard`` and
    ``omega_rel = theta_a' - theta_b'`` from the nodes' angular velocities (``nodes`` = (node of a, node of b), None
    for ground, whose rate is 0). ``coefficient`` = mu r [m], ``resistance`` = T0 [N m], ``eps`` [rad/s], ``delta``
    [N]. :meth:`load` gives the load user function of either body; ``history`` rows: [|R| used, omega_rel, tau].
    """

    def __init__(self, model: Model, nodes: tuple[int | None, int | None], guard: ReactionGuard, coefficient: float,
                 resistance: float, eps: float, delta: float):
        super().__init__(model, guard, 3)
        self.nodes = nodes
        self.coefficient, self.resistance = float(coefficient), float(resistance)
        self.eps, self.delta = float(eps), float(delta)

    def torque(self, mbs, record: bool) -> float:
        """tau (the torque on body a) at the current state; ``record``: count the guard's call and keep ``last``."""
        a, b = self.nodes
        omega = ((0.0 if a is None else mbs.GetNodeOutput(a, _ANGULAR_VELOCITY).tolist()[2])
                 - (0.0 if b is None else mbs.GetNodeOutput(b, _ANGULAR_VELOCITY).tolist()[2]))
        r = self.guard.value(mbs) if record else self.guard.peek(mbs)
        tau = joint_friction(self.coefficient, r, self.delta, self.resistance, omega, self.eps)
        if record:
            self.last = (r, omega, tau)
        return tau

    def load(self, side: int, record: bool) -> Callable:
        """The LoadTorqueVector user function of body a (``side`` 0: tau) or body b (``side`` 1: -tau). One load of
        the joint records (``record``); the other evaluates the same state and reaction without counting."""
        sign = 1.0 if side == 0 else -1.0

        def user(mbs, t, load_vector):
            return [0.0, 0.0, sign * self.torque(mbs, record)]
        return user


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


def seed_reaction_guards(model: Model, settings: exu.SimulationSettings, frictions: list[RecordedFriction]) -> dict:
    """Make the initial-acceleration solve use the consistent reactions (a guide's normal force, a pin's |R|).

    At t = 0 Exudyn computes the initial accelerations with all multipliers 0, so a friction law
    reading the reaction would see 0 and the initial accelerations (and the generalized-alpha
    start) would miss the friction. This fixed-point iteration runs only Exudyn's solver
    initialization repeatedly, each time feeding the guards the reactions of the previous
    initialization, until they no longer change. Purely Exudyn: no in-house quantity enters.

    Returns
    -------
    dict with 'seed_iterations' and 'seed_change' (last relative change of a reaction); empty without friction.
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
