"""The kinematics of a description, bound to its parameter values: body poses from the relative coordinates q, and
the map from Exudyn's body poses back to q (one per mechanism).

* The Exudyn model's initial state (:func:`body_states`): the in-house consistent (q, qd) mapped through the
  description's kinematics (COM position from the generated point function ``eom.points['<body>.com']``, angle
  from the description's angle expression, rates from their Jacobians).
* Back to q (:class:`Kinematics`): where the body angles are linear in q with full rank, theta = A q + c and
  q = q0 + A^+ (theta - theta0) with A^+ the exact pseudo-inverse; otherwise (a translation coordinate) q solves
  pose(q) = Exudyn's body poses (x, y, theta of every body) by Gauss-Newton, and qd, qdd follow through the pose
  Jacobian (:meth:`Kinematics.coordinates`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from study.exudyn_models.building import BodyState
from study.mechanisms import as_mechanism
from study.model import Mechanism
from study.model.coordinates import poses
from study.model.joints import Description
from study.params import ParameterSet

Array = np.ndarray


@dataclass
class Kinematics:
    """Body poses of the relative coordinates, and the map from Exudyn's body poses back to q.

    ``pinv`` is set when the body angles alone determine q (linear in q with full rank): q - q0 = pinv @
    (theta - theta0). Otherwise (a translation coordinate of a prismatic tree joint) q is recovered from every
    body's pose (x, y, theta) by Gauss-Newton (:meth:`coordinates`)."""

    d: Description
    subs: dict
    angle: dict           # body -> f(q) -> float
    angle_grad: dict      # body -> f(q) -> (m,) gradient
    com_jac: dict         # body -> f(q) -> (2, m)
    pinv: Array | None    # (m, n_bodies), or None
    pose: object = None        # f(q) -> (3 n_bodies,) [x, y, theta of every body]
    pose_jac: object = None    # f(q) -> (3 n_bodies, m)
    pose_bias: object = None   # f(q, qd) -> (3 n_bodies,) d(J)/dt qd, so that acc = J qdd + bias

    def coordinates(self, q0: Array, poses: Array, rates: Array, accelerations: Array) -> tuple[Array, Array, Array]:
        """q, qd, qdd at every sample from the bodies' (n, 3 n_bodies) poses, rates and accelerations.

        q: Gauss-Newton on pose(q) = pose, from the previous sample's q (q0 first); stopped at a step
        <= POSE_TOL (1 + |q|), or refused (ValueError) after POSE_MAX_ITER iterations. qd, qdd: least squares
        through the pose Jacobian, which has full column rank on a description whose bodies place q."""
        n = len(poses)
        q, qd, qdd = np.empty((n, len(q0))), np.empty((n, len(q0))), np.empty((n, len(q0)))
        qk = np.array(q0, dtype=float)
        for k in range(n):
            for _ in range(POSE_MAX_ITER):
                J = np.asarray(self.pose_jac(qk), dtype=float)
                step = np.linalg.lstsq(J, poses[k] - np.asarray(self.pose(qk), dtype=float).ravel(), rcond=None)[0]
                qk = qk + step
                if np.abs(step).max() <= POSE_TOL * (1 + np.abs(qk).max()):
                    break
            else:
                raise ValueError(f"{self.d.name}: q cannot be recovered from Exudyn's body poses at sample {k} "
                                 f"(Gauss-Newton did not converge in {POSE_MAX_ITER} iterations; last step "
                                 f"{np.abs(step).max():.3g}, q = {qk})")
            q[k] = qk
            qd[k], qdd[k] = self.rates(qk, rates[k], accelerations[k])
        return q, qd, qdd

    def rates(self, q: Array, pose_rates: Array, pose_accelerations: Array) -> tuple[Array, Array]:
        """qd, qdd at q from the bodies' pose rates and accelerations: pose' = J qd, pose'' = J qdd + dJ/dt qd."""
        J = np.asarray(self.pose_jac(q), dtype=float)
        qd = np.linalg.lstsq(J, pose_rates, rcond=None)[0]
        bias = np.asarray(self.pose_bias(q, qd), dtype=float).ravel()
        return qd, np.linalg.lstsq(J, pose_accelerations - bias, rcond=None)[0]


POSE_TOL, POSE_MAX_ITER = 1e-13, 30
_KINEMATICS: dict[Mechanism, Kinematics] = {}


def kinematics(mech: Mechanism) -> Kinematics:
    """The description of ``mech`` and its bound kinematics (kept per mechanism)."""
    if mech not in _KINEMATICS:
        _KINEMATICS[mech] = _make_kinematics(mech.description)
    return _KINEMATICS[mech]


def _make_kinematics(d: Description) -> Kinematics:
    subs = {getattr(d.p, k): sp.Float(v) for k, v in d.values.items()}
    q = list(d.q)
    _, _, placed, _ = poses(d, "relative")
    angle, grad, jac, rows, pose = {}, {}, {}, [], []
    for b in d.bodies:
        r, th = placed[b]
        th = sp.sympify(th).xreplace(subs)
        g = sp.Matrix([th]).jacobian(q)
        angle[b] = sp.lambdify([q], th, "math")
        grad[b] = sp.lambdify([q], g, "numpy")
        jac[b] = sp.lambdify([q], r.xreplace(subs).jacobian(q), "numpy")
        rows.append(g)
        pose += [*r.xreplace(subs), th]
    a = sp.Matrix.vstack(*rows)
    if not a.free_symbols & set(q) and a.rank() == len(q):
        return Kinematics(d, subs, angle, grad, jac, np.array(a.pinv().evalf(), dtype=float))
    qd = sp.symbols(f"qd0:{len(q)}")
    P = sp.Matrix(pose)
    JP = P.jacobian(q)
    bias = (JP * sp.Matrix(qd)).jacobian(q) * sp.Matrix(qd)
    if JP.subs({s: 0.1 * (i + 1) for i, s in enumerate(q)}).rank() != len(q):
        raise ValueError(f"mechanism {d.name!r}: the bodies' poses do not determine its coordinates (pose Jacobian "
                         f"of rank < {len(q)}), so an Exudyn result cannot be mapped back to them")
    return Kinematics(d, subs, angle, grad, jac, None, sp.lambdify([q], P, "numpy"), sp.lambdify([q], JP, "numpy"),
                      sp.lambdify([q, qd], bias, "numpy"))


def body_states(mech: Mechanism | ParameterSet, q, qd) -> dict[str, BodyState]:
    """COM position, angle and their rates of every body at (q, qd) through the description's kinematics."""
    mech = as_mechanism(mech)
    k = kinematics(mech)
    eom = mech.equations()
    q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
    out = {}
    for b in k.d.bodies:
        pos = np.asarray(eom.points[f"{b}.com"](q), dtype=float).ravel()
        vel = np.asarray(k.com_jac[b](q), dtype=float) @ qd
        omega = float(np.asarray(k.angle_grad[b](q), dtype=float).ravel() @ qd)
        out[b] = BodyState((float(pos[0]), float(pos[1])), float(k.angle[b](q)), (float(vel[0]), float(vel[1])),
                           omega)
    return out



def rotation(a) -> Array:
    """The 2 x 2 rotation matrix of the angle a."""
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s], [s, c]])
