"""Explicit Runge-Kutta steps of the compiled path: scipy's RK23/RK45/DOP853 and a fixed-step RK4.

The adaptive methods use scipy's own tableaus (``scipy.integrate.RK23/RK45/DOP853`` class data,
passed in as the tuple ``tab``), its error norms (RMS of err / (atol + max(|y|, |y_new|) rtol);
DOP853's combined 5th/3rd-order estimate) and its step-size rule (safety 0.9, factors 0.2..10,
no growth right after a rejection), so a compiled run takes the same steps as the reference run
up to round-off. RK4 is ``study.solver.integrate.RK4`` (cubic Hermite dense output).

Dense output is built only for steps that need it (an output time or a switch inside the step),
unlike the reference loop, which builds it for every step (3 extra evaluations per DOP853 step).

The steps work on the segment's integration state ``st`` (``study.fast.loop.integration_state``: the tableau, the
stages K, the interpolant D, the step's y, y_new, f, f_new and the evaluation workspace), one pointer per call.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import DOP853, RK23, RK45
from scipy.integrate._ivp import dop853_coefficients as _dop

from study.kernels.cache import internal
from study.fast.dynamics import rhs
from study.fast.support import METHOD_IDS

RK23_ID, RK45_ID, DOP853_ID, RK4_ID = (METHOD_IDS[k] for k in ("RK23", "RK45", "DOP853", "RK4"))
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0  # scipy.integrate._ivp.rk


def tableau(method: str) -> tuple:
    """(A, B, C, E, E3, E5, P or D, n_stages, error_estimator_order, dense rows) of a method."""
    e = np.zeros(1)
    if method in ("RK23", "RK45"):
        cls = RK23 if method == "RK23" else RK45
        arrays = (cls.A, cls.B, cls.C, cls.E, e, e, cls.P)
        return tuple(np.ascontiguousarray(a, dtype=float) for a in arrays) + (
            cls.n_stages, cls.error_estimator_order, cls.P.shape[1])
    if method == "DOP853":
        arrays = (_dop.A, _dop.B, _dop.C, e, _dop.E3, _dop.E5, _dop.D)
        return tuple(np.ascontiguousarray(a, dtype=float) for a in arrays) + (
            DOP853.n_stages, DOP853.error_estimator_order, _dop.INTERPOLATOR_POWER)
    if method == "RK4":
        A = np.zeros((4, 4))
        A[1, 0], A[2, 1], A[3, 2] = 0.5, 0.5, 1.0
        return (A, np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6]), np.array([0.0, 0.5, 0.5, 1.0]), e, e, e,
                np.zeros((1, 1)), 4, 3, 4)
    raise ValueError(f"no compiled integrator {method!r}")


@internal()
def select_initial_step(evaluate, bias, phases, t0, t_bound, order, st):
    """scipy.integrate._ivp.common.select_initial_step (Hairer, Norsett & Wanner II.4) from (t0, st.y) with
    f0 = st.f; st.tmp and st.f_new are overwritten."""
    y0, f0, tmp, f1, rtol, atol = st.y, st.f, st.tmp, st.f_new, st.rtol, st.atol
    n = y0.size
    interval = abs(t_bound - t0)
    if interval == 0.0:
        return 0.0, 0
    d0, d1 = 0.0, 0.0
    for i in range(n):
        sc = atol + abs(y0[i]) * rtol
        d0 += (y0[i] / sc) ** 2
        d1 += (f0[i] / sc) ** 2
    d0, d1 = math.sqrt(d0 / n), math.sqrt(d1 / n)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, interval)
    for i in range(n):
        tmp[i] = y0[i] + h0 * f0[i]
    status = rhs(evaluate, bias, phases, t0 + h0, tmp, st.ws, f1)
    d2 = 0.0
    for i in range(n):
        sc = atol + abs(y0[i]) * rtol
        d2 += ((f1[i] - f0[i]) / sc) ** 2
    d2 = math.sqrt(d2 / n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100 * h0, h1, interval), status


@internal()
def stages(evaluate, bias, phases, t, h, first, last, st):
    """st.K[s] = f(t + C[s] h, y + h sum_j A[s, j] K[j]) for s in first..last-1, y = st.y; returns a status."""
    A, C, K, y, tmp, ws = st.ta, st.tc, st.K, st.y, st.tmp, st.ws
    n = y.size
    for s in range(first, last):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += A[s, j] * K[j, i]
            tmp[i] = y[i] + h * acc
        status = rhs(evaluate, bias, phases, t + C[s] * h, tmp, ws, K[s])
        if status != 0:
            return status
    return 0


@internal()
def error_norm(h, st):
    """scipy's error norm of an embedded pair (DOP853: its combined 5th/3rd-order estimate) of the step from st.y
    to st.y_new."""
    K, y, y_new, rtol, atol, n_stages = st.K, st.y, st.y_new, st.rtol, st.atol, st.n_stages
    n = y.size
    if st.method == DOP853_ID:
        E3, E5 = st.te3, st.te5
        e5, e3 = 0.0, 0.0
        for i in range(n):
            sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
            a5, a3 = 0.0, 0.0
            for s in range(n_stages + 1):
                a5 += E5[s] * K[s, i]
                a3 += E3[s] * K[s, i]
            e5 += (a5 / sc) ** 2
            e3 += (a3 / sc) ** 2
        if e5 == 0.0 and e3 == 0.0:
            return 0.0
        return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n)
    E = st.te
    acc2 = 0.0
    for i in range(n):
        sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        e = 0.0
        for s in range(n_stages + 1):
            e += E[s] * K[s, i]
        acc2 += (e * h / sc) ** 2
    return math.sqrt(acc2 / n)


@internal()
def combine(n_stages, h, st):
    """st.y_new = y + h sum_s B[s] K[s]."""
    B, K, y, y_new = st.tb, st.K, st.y, st.y_new
    for i in range(y.size):
        acc = 0.0
        for s in range(n_stages):
            acc += B[s] * K[s, i]
        y_new[i] = y[i] + h * acc


@internal()
def dense_setup(evaluate, bias, phases, t_old, h, st):
    """Coefficients st.D of the step's interpolant from st.y to st.y_new (scipy's RkDenseOutput / Dop853DenseOutput /
    Hermite)."""
    method, n_stages, K, D = st.method, st.n_stages, st.K, st.D
    y_old, y_new, f_old, f_new = st.y, st.y_new, st.f, st.f_new
    n = y_old.size
    if method == RK4_ID:
        for i in range(n):
            D[0, i], D[1, i], D[2, i], D[3, i] = y_old[i], y_new[i], h * f_old[i], h * f_new[i]
        return 0
    if method == DOP853_ID:
        status = stages(evaluate, bias, phases, t_old, h, n_stages + 1, K.shape[0], st)
        Dm = st.tp
        for i in range(n):
            dy = y_new[i] - y_old[i]
            D[0, i] = dy
            D[1, i] = h * f_old[i] - dy
            D[2, i] = 2 * dy - h * (f_new[i] + f_old[i])
            for r in range(Dm.shape[0]):
                acc = 0.0
                for s in range(K.shape[0]):
                    acc += Dm[r, s] * K[s, i]
                D[3 + r, i] = h * acc
        return status
    P = st.tp
    for r in range(P.shape[1]):
        for i in range(n):
            acc = 0.0
            for s in range(n_stages + 1):
                acc += K[s, i] * P[s, r]
            D[r, i] = h * acc
    return 0


@internal()
def dense_eval(x, st, out):
    """The step's interpolant (st.D, from st.y) at x = (t - t_old) / h, into out."""
    method, n_rows, D, y_old = st.method, st.n_rows, st.D, st.y
    n = y_old.size
    if method == RK4_ID:
        h00, h10 = 2 * x**3 - 3 * x**2 + 1, x**3 - 2 * x**2 + x
        h01, h11 = -2 * x**3 + 3 * x**2, x**3 - x**2
        for i in range(n):
            out[i] = D[0, i] * h00 + D[2, i] * h10 + D[1, i] * h01 + D[3, i] * h11
        return
    if method == DOP853_ID:
        for i in range(n):
            acc = 0.0
            for k in range(n_rows):
                acc += D[n_rows - 1 - k, i]
                acc *= x if k % 2 == 0 else 1.0 - x
            out[i] = acc + y_old[i]
        return
    for i in range(n):
        acc, xp = 0.0, 1.0
        for k in range(n_rows):
            xp *= x
            acc += D[k, i] * xp
        out[i] = y_old[i] + acc
