"""Paper 000's own method for the slider-crank with Coulomb friction, with its misprints corrected.

:func:`paper_method`: multipliers eliminated with D = [1, d12] (eqs. 24-25), the acceleration
constraint (eq. 28, corrected to y_B'' = 0), and N from the moment balance of rod + slider about A
(eqs. 31/34, corrected), with F_fr = -f |N| sgn(x_B') - F sgn(x_B'). It is a pure function of the
parameters, the state and the sign hypotheses, independent of the builder and the solver, and the
tests check it against the multiplier-based contact of ``study.solver.friction``. The holding
forces and break-away torques at a pose (:func:`holding_forces`, :func:`breakaway_torque`) and the
slider's kinematics follow from the same hand derivation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

Array = np.ndarray


@dataclass(frozen=True)
class PaperSolution:
    """Result of :func:`paper_method` for one sign hypothesis.

    qdd : (2,) accelerations; normal : N, the guide's force on the slider along +y [N];
    friction : F_fr, the guide's tangential force on the slider along +x, resistance F included [N];
    consistent : whether sigma * N >= 0 (the assumed sign of N holds).
    """

    qdd: Array
    normal: float
    friction: float
    consistent: bool


def _paper_terms(v, q, qd):
    q1, q2 = float(q[0]), float(q[1])
    w1, w2 = float(qd[0]), float(qd[1])
    th, wth = q1 + q2, w1 + w2
    s1, c1, sth, cth, s2, cq2 = math.sin(q1), math.cos(q1), math.sin(th), math.cos(th), math.sin(q2), math.cos(q2)
    # eq. (14), corrected: a22 = J2 + m2 c2^2 + m3 l2^2 (printed m2 c2 l1), a12 ends in J2 (printed J3)
    a11 = v.J1 + v.J2 + v.m2 * (v.l1**2 + v.c2**2 - 2 * v.l1 * v.c2 * cq2) + v.m3 * (v.l1**2 + v.l2**2 - 2 * v.l1 * v.l2 * cq2)
    a12 = v.J2 + v.m2 * (v.c2**2 - v.l1 * v.c2 * cq2) + v.m3 * (v.l2**2 - v.l1 * v.l2 * cq2)
    a22 = v.J2 + v.m2 * v.c2**2 + v.m3 * v.l2**2
    A = np.array([[a11, a12], [a12, a22]])
    # eq. (27), corrected: Q1^qt = -k sin q2 (2 q1' q2' + q2'^2) (printed q1'^2 + 2 q1' q2')
    k = (v.m2 * v.c2 + v.m3 * v.l2) * v.l1
    Qqt = np.array([-k * s2 * (2 * w1 * w2 + w2**2), k * s2 * w1**2])
    # eq. (18): pi = m2 g y_C2 (+ alpha q1^2 / 2 for the spring reading of '-alpha q1')
    grad_pi = np.array([v.m2 * v.g * (v.l1 * c1 - v.c2 * cth), -v.m2 * v.g * v.c2 * cth])
    Q = np.array([v.M, 0.0]) - grad_pi + Qqt
    Q[0] -= v.alpha * (q1 if v.alpha_law == "spring" else w1)
    # eq. (19): dx_B/dq; the slider's horizontal force F_fr has generalized force F_fr * dx_B/dq
    # (eq. 20 and the separate '-F' in Q2 of eq. 26 are replaced by this: F is part of F_fr)
    dxB = np.array([v.l2 * sth - v.l1 * s1, v.l2 * sth])
    d12 = v.l1 * c1 / (v.l2 * cth) - 1.0  # eq. (24)
    return dict(q1=q1, w1=w1, th=th, wth=wth, s1=s1, c1=c1, sth=sth, cth=cth, A=A, Q=Q, dxB=dxB,
                D=np.array([1.0, d12]))


def paper_method(v, q, qd, s: float, sigma: float) -> PaperSolution:
    """000's method for the slider-crank (eqs. 24-34, corrected), one sign hypothesis.

    Unknowns qdd1, qdd2 and N, from three equations linear in them once s = sgn(x_B') and
    sigma = sgn(N) are assumed, with F_fr = -s (F + f sigma N) (eq. 32 with the resistance F):

    - eq. (25):  D (A qdd - Q - F_fr dx_B/dq) = 0, D = [1, d12]  (the ideal N drops out: D dy_B/dq = 0);
    - eq. (28), corrected to the constraint's second derivative, y_B'' = 0 (the printed one is x_B'');
    - eqs. (31)/(34), corrected: moments about A of rod + slider, with the inertial forces of the rod
      at C2 (-m2 a_C2, -J2 eps2), the rod's weight at C2, and at B the slider's weight, inertia
      -m3 a_B, N and F_fr, each with its own lever arm (the printed eq. 31 uses B's arm for the rod's
      inertial force and omits the rod's weight).

    Parameters
    ----------
    v : the slider-crank parameter values (``ps.values``)
    q, qd : (2,) state on the constraint manifold
    s : sliding direction, +-1 (0: no friction or resistance)
    sigma : assumed sign of N, +-1
    """
    T = _paper_terms(v, q, qd)
    l1, l2, c2 = v.l1, v.l2, v.c2

    def residual(x):
        qdd, N = x[:2], x[2]
        F_fr = -s * (v.F + v.mu * sigma * N)
        r25 = T["D"] @ (T["A"] @ qdd - T["Q"] - F_fr * T["dxB"])
        th_dd = qdd[0] + qdd[1]
        r28 = ((l1 * T["c1"] - l2 * T["cth"]) * qdd[0] - l2 * T["cth"] * qdd[1]
               - l1 * T["s1"] * T["w1"] ** 2 + l2 * T["sth"] * T["wth"] ** 2)

        def accel(length):  # acceleration of the rod point at distance `length` from A (eq. 30)
            ax = (-l1 * T["s1"] + length * T["sth"]) * qdd[0] + length * T["sth"] * qdd[1] \
                - l1 * T["c1"] * T["w1"] ** 2 + length * T["cth"] * T["wth"] ** 2
            ay = (l1 * T["c1"] - length * T["cth"]) * qdd[0] - length * T["cth"] * qdd[1] \
                - l1 * T["s1"] * T["w1"] ** 2 + length * T["sth"] * T["wth"] ** 2
            return ax, ay

        def moment(arm, fx, fy):  # z-moment about A of a force at A + arm * (-cos th, -sin th)
            rx, ry = -arm * T["cth"], -arm * T["sth"]
            return rx * fy - ry * fx

        axC, ayC = accel(c2)
        axB, ayB = accel(l2)
        r31 = (-v.J2 * th_dd
               + moment(c2, -v.m2 * axC, -v.m2 * ayC - v.m2 * v.g)
               + moment(l2, F_fr - v.m3 * axB, N - v.m3 * v.g - v.m3 * ayB))
        return np.array([r25, r28, r31])

    r0 = residual(np.zeros(3))
    K = np.column_stack([residual(e) - r0 for e in np.eye(3)])  # the residuals are affine in x
    x = np.linalg.solve(K, -r0)
    N = float(x[2])
    return PaperSolution(x[:2], N, float(-s * (v.F + v.mu * sigma * N)), bool(sigma * N >= 0))


def holding_forces(v, q) -> dict[str, float]:
    """Static balance of the stuck mechanism at q (qd = 0), from 000's D = [1, d12].

    Each load's generalized force along the motion, R^T Q with R = [1, d12]^T, is a torque about
    the crank axis [N m]; the guide must supply f_req = -(sum) / (R^T dx_B/dq) along +x [N].
    """
    T = _paper_terms(v, q, np.zeros(2))
    R = T["D"]
    grad_rod = np.array([v.m2 * v.g * (v.l1 * T["c1"] - v.c2 * T["cth"]), -v.m2 * v.g * v.c2 * T["cth"]])
    terms = {"drive_M": v.M, "alpha_term": -v.alpha * T["q1"] if v.alpha_law == "spring" else 0.0,
             "rod_weight": float(-R @ grad_rod), "slider_weight": 0.0}
    lever = float(R @ T["dxB"])
    total = sum(terms.values())
    f_req = -total / lever
    return {**{f"torque_{k}": val for k, val in terms.items()}, "torque_sum": total,
            "lever_dxB_dq1": lever, "f_required": f_req}


def breakaway_torque(v, q, reading: str | None = None) -> dict[str, float]:
    """Drive torque M at which the mechanism, stuck at q (qd = 0), breaks away from the guide.

    ``reading`` ('holds' or 'sliding_only'; default: the parameter set's ``resistance_reading``) says
    whether the resistance F counts in the static limit (F + mu|N|) or not (mu|N|), the open
    assumption of paper 000 (``study.solver.friction.RESISTANCE_READINGS``).

    The holding force is affine in M, f_req = -(M + T_other) / lever (:func:`holding_forces`), and at
    rest the moment balance of rod + slider about A (000 eq. 31/34, corrected, with zero inertial
    terms) gives the normal force as an affine function of the tangential force f on the slider:
    N = m3 g + (m2 g c2 cos th + l2 sin th f) / (l2 cos th), th = q1 + q2. The slider stays stuck while
    |f| <= c F + mu |N| (c = 1 or 0 by ``reading``); breakaway is where equality holds, on the side
    f_req is already pushing.

    Returns
    -------
    dict with ``breakaway_M`` [N m] (NaN if no consistent solution), ``breakaway_f`` [N] and
    ``breakaway_normal`` [N] at that torque.
    """
    c = static_resistance_fraction(v, reading)
    held = holding_forces(v, q)
    th = float(q[0] + q[1])
    a = v.m3 * v.g + v.m2 * v.g * v.c2 / v.l2  # N at f = 0
    b = math.tan(th)  # dN/df
    s = 1.0 if held["f_required"] >= 0 else -1.0
    t_other = held["torque_sum"] - held["torque_drive_M"]
    for sigma in (1.0, -1.0):
        f = (c * v.F + v.mu * sigma * a) / (s - v.mu * sigma * b)
        normal = a + b * f
        if s * f > 0 and sigma * normal >= 0:
            return {"breakaway_M": -f * held["lever_dxB_dq1"] - t_other, "breakaway_f": f, "breakaway_normal": normal}
    return {"breakaway_M": float("nan"), "breakaway_f": float("nan"), "breakaway_normal": float("nan")}


# The fraction of F in the static limit for each reading of paper 000's resistance (typed here again on purpose:
# this module is the paper's method written out independently of the solver, which has RESISTANCE_READINGS).
STATIC_FRACTION = {"holds": 1.0, "sliding_only": 0.0}


def static_resistance_fraction(v, reading: str | None = None) -> float:
    """1 if F holds a stuck slider (reading 'holds'), 0 if it acts only while sliding ('sliding_only')."""
    reading = v.resistance_reading if reading is None else reading
    if reading not in STATIC_FRACTION:
        raise ValueError(f"reading = {reading!r}; valid choices: {', '.join(STATIC_FRACTION)}")
    return STATIC_FRACTION[reading]


def breakaway_readings(v, q) -> pd.DataFrame:
    """The breakaway torque of the pose q under each reading of F (table ``seed_breakaway_readings``)."""
    rows = []
    held = holding_forces(v, q)
    for reading in STATIC_FRACTION:
        b = breakaway_torque(v, q, reading)
        rows.append({"reading": reading, "static_limit_rule": "F + mu|N|" if STATIC_FRACTION[reading] else "mu|N|",
                     "parameter_file": reading == v.resistance_reading, "q1": float(q[0]), "q2": float(q[1]),
                     "M_seed": v.M, "f_required_at_M_seed": held["f_required"], **b,
                     "breakaway_over_M_seed": b["breakaway_M"] / v.M})
    return pd.DataFrame(rows)


def slider_position(v, q: Array) -> Array:
    """x_B = l1 cos q1 - l2 cos(q1 + q2) [m] for (N, 2) samples q."""
    q = np.atleast_2d(q)
    return v.l1 * np.cos(q[:, 0]) - v.l2 * np.cos(q[:, 0] + q[:, 1])


def slider_velocity(v, q: Array, qd: Array) -> Array:
    """x_B' = -l1 sin q1 q1' + l2 sin(q1 + q2) (q1' + q2') [m/s] for (N, 2) samples q, qd."""
    q, qd = np.atleast_2d(q), np.atleast_2d(qd)
    th = q[:, 0] + q[:, 1]
    return -v.l1 * np.sin(q[:, 0]) * qd[:, 0] + v.l2 * np.sin(th) * (qd[:, 0] + qd[:, 1])
