"""The first-order ODE of a constrained mechanism: state y = [q, qd, W], W the work of each load.

``Dynamics`` joins an EquationsOfMotion, an acceleration solver and a stabilization method:

    qdd, lambda = solve(M, Q, Phi_q, gamma + b(Phi, Phidot)),    dW_i/dt = Q_i . qd

and counts right-hand-side evaluations. Discontinuous loads are evaluated in a frozen ``mode``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from study.model.eom import EquationsOfMotion
from study.solver.accelerations import AccelerationSolver
from study.solver.stabilization import Stabilization

Array = np.ndarray


@dataclass
class Dynamics:
    eom: EquationsOfMotion
    accelerations: AccelerationSolver
    stabilization: Stabilization
    work_names: tuple[str, ...] = ()
    nfev: int = 0
    _modal: bool = field(init=False, default=False)

    def __post_init__(self) -> None:
        self._modal = self.eom.indicators is not None

    @property
    def m(self) -> int:
        return self.eom.n_coordinates

    def split(self, y: Array) -> tuple[Array, Array, Array]:
        m = self.m
        return y[:m], y[m:2 * m], y[2 * m:]

    def _forces(self, t, q, qd, mode):
        return self.eom.forces(t, q, qd, mode=mode) if self._modal else self.eom.forces(t, q, qd)

    def _applied(self, t, q, qd, mode):
        return self.eom.applied_forces(t, q, qd, mode=mode) if self._modal else self.eom.applied_forces(t, q, qd)

    def evaluate(self, t: float, q: Array, qd: Array, mode=None) -> tuple[Array, Array]:
        """Accelerations and multipliers at one state."""
        eom = self.eom
        J = eom.phi_q(q)
        c = eom.gamma(q, qd) + self.stabilization.bias(eom.phi(q), J @ qd)
        return self.accelerations.solve(eom.mass(q), self._forces(t, q, qd, mode), J, c)

    def powers(self, t: float, q: Array, qd: Array, mode=None) -> Array:
        if not self.work_names:
            return np.zeros(0)
        applied = self._applied(t, q, qd, mode)
        return np.array([applied[name] @ qd for name in self.work_names])

    def rhs(self, t: float, y: Array, mode=None) -> Array:
        self.nfev += 1
        q, qd, _ = self.split(y)
        qdd, _ = self.evaluate(t, q, qd, mode)
        return np.concatenate([qd, qdd, self.powers(t, q, qd, mode)])
