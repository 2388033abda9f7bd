"""Hand-written equations of motion, typed from textbook derivations independently of the builder.

Used to check the builder (same mechanism, written by hand) and to show that a user's own
EquationsOfMotion runs through the solver like a built-in one.
"""

from math import cos, sin

import numpy as np

from study import EquationsOfMotion


def slider_crank(v) -> EquationsOfMotion:
    """Paper 000's slider-crank with the corrected forms of eqs. (14), (17), (18), (22), (28); alpha spring."""
    k = (v.m2 * v.c2 + v.m3 * v.l2) * v.l1

    def mass(q):
        c2 = cos(q[1])
        a11 = v.J1 + v.J2 + v.m2 * (v.l1**2 + v.c2**2 - 2 * v.l1 * v.c2 * c2) + v.m3 * (v.l1**2 + v.l2**2 - 2 * v.l1 * v.l2 * c2)
        a12 = v.J2 + v.m2 * (v.c2**2 - v.l1 * v.c2 * c2) + v.m3 * (v.l2**2 - v.l1 * v.l2 * c2)
        a22 = v.J2 + v.m2 * v.c2**2 + v.m3 * v.l2**2
        return np.array([[a11, a12], [a12, a22]])

    def forces(t, q, qd):
        s2, c1, c12 = sin(q[1]), cos(q[0]), cos(q[0] + q[1])
        coriolis = np.array([k * s2 * (2 * qd[0] * qd[1] + qd[1] ** 2), -k * s2 * qd[0] ** 2])
        grad_v = v.g * np.array([v.m2 * (v.l1 * c1 - v.c2 * c12) + v.m3 * (v.l1 * c1 - v.l2 * c12),
                                 -v.m2 * v.c2 * c12 - v.m3 * v.l2 * c12]) + np.array([v.alpha * q[0], 0.0])
        return np.array([v.M, 0.0]) - grad_v - coriolis

    def phi(q):
        return np.array([v.l1 * sin(q[0]) - v.l2 * sin(q[0] + q[1])])

    def phi_q(q):
        c12 = cos(q[0] + q[1])
        return np.array([[v.l1 * cos(q[0]) - v.l2 * c12, -v.l2 * c12]])

    def gamma(q, qd):
        return np.array([v.l1 * sin(q[0]) * qd[0] ** 2 - v.l2 * sin(q[0] + q[1]) * (qd[0] + qd[1]) ** 2])

    def potential(q):
        s1, s12 = sin(q[0]), sin(q[0] + q[1])
        return v.g * (v.m2 * (v.l1 * s1 - v.c2 * s12) + v.m3 * (v.l1 * s1 - v.l2 * s12)) + 0.5 * v.alpha * q[0] ** 2

    return EquationsOfMotion(2, 1, mass, forces, phi, phi_q, gamma, name="slider_crank_by_hand",
                             potential_energy=potential)


def quick_return(v, cutting_force=lambda t, x, vx: 0.0) -> EquationsOfMotion:
    """Paper 001's quick-return with the corrected C vector, the ram's weight and B = [[1, 0], [0, -l2 s2], [0, -l3 s3]]."""
    c = v.m3 * v.l2 * v.a3 + v.m5 * v.l2 * v.l3

    def mass(q):
        m23 = c * cos(q[1] - q[2])
        return np.array([
            [v.J1 + v.m1 * v.a1**2 + v.m4 * v.l1**2, 0.0, 0.0],
            [0.0, v.J2 + v.J4 + v.m2 * v.a2**2 + v.m3 * v.l2**2 + v.m5 * v.l2**2, m23],
            [0.0, m23, v.J3 + v.m3 * v.a3**2 + v.m5 * v.l3**2],
        ])

    def forces(t, q, qd):
        s23 = sin(q[1] - q[2])
        coriolis = np.array([0.0, c * s23 * qd[2] ** 2, -c * s23 * qd[1] ** 2])
        grad_v = v.g * np.array([(v.m1 * v.a1 + v.m4 * v.l1) * cos(q[0]),
                                 (v.m2 * v.a2 + v.m3 * v.l2 + v.m5 * v.l2) * cos(q[1]),
                                 (v.m3 * v.a3 + v.m5 * v.l3) * cos(q[2])])
        x_d = v.l2 * cos(q[1]) + v.l3 * cos(q[2])
        dx_dq = np.array([0.0, -v.l2 * sin(q[1]), -v.l3 * sin(q[2])])
        f = cutting_force(t, x_d, dx_dq @ qd)
        return np.array([v.M, 0.0, 0.0]) + f * dx_dq - grad_v - coriolis

    def phi(q):
        return np.array([v.l1 * sin(q[0] - q[1]) + v.h1 * cos(q[1]), -v.l2 * sin(q[1]) - v.l3 * sin(q[2]) + v.h2])

    def phi_q(q):
        c12 = cos(q[0] - q[1])
        return np.array([[v.l1 * c12, -v.l1 * c12 - v.h1 * sin(q[1]), 0.0],
                         [0.0, -v.l2 * cos(q[1]), -v.l3 * cos(q[2])]])

    def gamma(q, qd):
        return np.array([v.l1 * sin(q[0] - q[1]) * (qd[0] - qd[1]) ** 2 + v.h1 * cos(q[1]) * qd[1] ** 2,
                         -v.l2 * sin(q[1]) * qd[1] ** 2 - v.l3 * sin(q[2]) * qd[2] ** 2])

    return EquationsOfMotion(3, 2, mass, forces, phi, phi_q, gamma, name="quick_return_by_hand")


def cartesian_pendulum(length=1.0, mass=1.0, g=9.81) -> EquationsOfMotion:
    """A point mass on a massless rod in Cartesian coordinates: q = (x, y), Phi = (x^2 + y^2 - L^2)/2."""

    return EquationsOfMotion(
        n_coordinates=2,
        n_constraints=1,
        mass=lambda q: mass * np.eye(2),
        forces=lambda t, q, qd: np.array([0.0, -mass * g]),
        phi=lambda q: np.array([0.5 * (q @ q - length**2)]),
        phi_q=lambda q: q.reshape(1, 2).copy(),
        gamma=lambda q, qd: np.array([-(qd @ qd)]),
        name="cartesian_pendulum",
        potential_energy=lambda q: mass * g * q[1],
    )


def smooth_cutting_force(v, x, vx):
    """001's cutting force with the study's tanh ramps, typed from the parameter file's definition."""
    from math import tanh

    def s(u):
        return 0.5 * (1.0 + tanh(u))
    return v.F_cut * s(-vx / v.v_ramp) * s((x - v.x_cut_min) / v.x_ramp) * s((v.x_cut_max - x) / v.x_ramp)
