"""Reference motions built independently of the in-house solver and of Exudyn.

IFToMM A01, the simple pendulum released at rest from the horizontal: with phi the angle from the downward
vertical, phi(0) = pi/2, the exact motion is sin(phi/2) = k sn(omega t + K(k), k), k = sin(pi/4), omega =
sqrt(g/L) (Jacobi's elliptic sine; K the complete elliptic integral of the first kind, the quarter period). P1
is at x = L sin(phi), y = -L cos(phi); it starts at x = +L, so phi > 0 on the first swing.

IFToMM A02, the N-four-bar: along the parallelogram branch (every crank at the same angle theta, every
coupler horizontal) the mechanism has one degree of freedom. With unit-density links of length L and
mass m, the kinetic energy is a m L^2 theta'^2 and the potential energy b m g L sin(theta), where
a = (N + 1)/6 + N/2 (the N + 1 cranks rotating about their pivots, the N couplers translating) and
b = (N + 1)/2 + N (the cranks' centres at half height, the couplers at full height). Lagrange's equation
is the ODE 2 a L theta'' + b g cos(theta) = 0, from theta(0) = pi/2 (cranks vertical) with B0 moving
along +x at v0: theta'(0) = -v0 / L. Point B0, the top of the first crank, is at x = L cos(theta) and moves
along x at -L sin(theta) theta'.

Nothing of the study's model enters: not the description, not the generated equations, not a solver of
the package. The motion crosses the singular positions (theta = 0, pi) smoothly; only the redundant
description's Jacobian loses rank there.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

from study.reference_data import tolerance


def richardson_second_order(coarse, fine) -> tuple[np.ndarray, np.ndarray]:
    """Two results of a second-order method at steps h and h/2 -> (Richardson's extrapolation
    v(h/2) + (v(h/2) - v(h)) / 3, the estimated error of the finer result |v(h/2) - v(h)| / 3)."""
    coarse, fine = np.asarray(coarse, dtype=float), np.asarray(fine, dtype=float)
    return fine + (fine - coarse) / 3, np.abs(fine - coarse) / 3


def n_four_bar_b0(t: np.ndarray, n: int, length: float, g: float, v0: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """x of B0 [m] and its rate [m/s] at the times ``t`` [s] (increasing, from 0) for the A02 N-four-bar with ``n``
    windows, B0 starting at ``v0`` [m/s] along +x."""
    a, b = (n + 1) / 6 + n / 2, (n + 1) / 2 + n
    t = np.asarray(t, dtype=float)

    def rhs(_, y):
        return [y[1], -b * g * np.cos(y[0]) / (2 * a * length)]

    rtol = tolerance("a02_reference_rtol", table="benchmarks")
    sol = solve_ivp(rhs, (0.0, float(t[-1])), [np.pi / 2, -v0 / length], method="DOP853", t_eval=t, rtol=rtol,
                    atol=rtol * 1e-2)
    if not sol.success:
        raise RuntimeError(f"the A02 reference motion failed: {sol.message}")
    theta, rate = sol.y
    return length * np.cos(theta), -length * np.sin(theta) * rate


def simple_pendulum_p1(t: np.ndarray, length: float, g: float) -> tuple[np.ndarray, np.ndarray]:
    """x, y of P1 [m] at the times ``t`` [s] for A01: released at rest at x = +L, y = 0 (exact, Jacobi's sn).

    x = L sin(phi) = 2 L sin(phi/2) cos(phi/2) and y = -L cos(phi) = -L (1 - 2 sin^2(phi/2)), with sin(phi/2) =
    k sn(u, k) and cos(phi/2) = dn(u, k) = sqrt(1 - k^2 sn^2), u = omega t + K(k)."""
    m = 0.5   # k^2, k = sin(pi/4): the amplitude phi(0) = pi/2
    sn, _, dn, _ = ellipj(np.sqrt(g / length) * np.asarray(t, dtype=float) + ellipk(m), m)
    half_sin = np.sqrt(m) * sn
    return 2 * length * half_sin * dn, -length * (1 - 2 * half_sin ** 2)
