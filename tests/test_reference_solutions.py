"""The A02 reference motion against numbers published outside this repository."""

import numpy as np

from study.reference_data import tolerance, values
from scipy.integrate import solve_ivp

from study.reference_solutions import n_four_bar_b0, richardson_second_order, simple_pendulum_p1


def test_a02_reference_matches_exudyns_published_value_at_10_s():
    """Exudyn's IFToMM four-bar test model prints x_B0(10 s) = 0.32846 m for N = 2 (5 digits)."""
    x, vx = n_four_bar_b0(np.array([0.0, 10.0]), 2, 1.0, 9.81)
    assert abs(x[-1] - tolerance("a02_published_x_b0_10s", table="benchmarks")) <= 5e-6
    assert abs(x[0]) <= 1e-15 and vx[0] == 1.0   # cranks vertical at t = 0, B0 at 1 m/s along +x


def test_a02_reference_conserves_the_branch_energy():
    """Along the branch, a L^2 th'^2 + b g L sin th is constant; recovered here from x = L cos th by finite
    differences of the dense samples, to the differences' own error (h^2 ~ 1e-8)."""
    n, length, g = 2, 1.0, 9.81
    a, b = (n + 1) / 6 + n / 2, (n + 1) / 2 + n
    t = np.linspace(0.0, 0.3, 3001)   # before the first crossing: th in (0, pi/2], sin th > 0
    x, vx = n_four_bar_b0(t, n, length, g)
    th = np.arccos(x / length)
    thd = np.gradient(th, t)
    energy = a * length**2 * thd**2 + b * g * length * np.sin(th)
    assert np.ptp(energy[5:-5]) <= 1e-6 * energy[0]
    assert np.abs(vx - np.gradient(x, t))[5:-5].max() <= 1e-6   # the rate is x's derivative, to the same error


def test_a02_reference_matches_exudyns_extrapolated_step_sequence_at_10_s():
    """Exudyn's test model lists B0 at 10 s for h = 2.5e-4 and 1.25e-4 s (second order): the exact motion must lie
    within the finest run's estimated error of their Richardson extrapolation, for the position and the rate."""
    extrapolated, error_of_fine = richardson_second_order(values("a02_exudyn_b0_10s_h2_5e-4", table="benchmarks"),
                                                          values("a02_exudyn_b0_10s_h1_25e-4", table="benchmarks"))
    x, vx = n_four_bar_b0(np.array([0.0, 10.0]), 2, 1.0, 9.81)
    assert (np.abs(np.array([x[-1], vx[-1]]) - extrapolated) <= error_of_fine).all()


def test_simple_pendulum_reference_is_the_pendulum_equation():
    """A01's exact motion (Jacobi's sn) against an independent integration of phi'' = -(g/L) sin(phi) from
    phi(0) = pi/2 at rest, to the integration's accuracy (rtol 1e-13 over 20 s, about eight swings)."""
    t = np.linspace(0.0, 20.0, 41)
    x, y = simple_pendulum_p1(t, 1.0, 9.81)
    sol = solve_ivp(lambda _, z: [z[1], -9.81 * np.sin(z[0])], (0.0, 20.0), [np.pi / 2, 0.0], method="DOP853",
                    rtol=1e-13, atol=1e-15, t_eval=t)
    bound = tolerance("adaptive_global_error_factor") * 1e-13   # the integration's own global error
    assert np.abs(x - np.sin(sol.y[0])).max() <= bound and np.abs(y + np.cos(sol.y[0])).max() <= bound
    assert abs(x[0] - 1.0) <= 4 * np.finfo(float).eps and abs(y[0]) <= 4 * np.finfo(float).eps
