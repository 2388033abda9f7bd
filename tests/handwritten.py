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


def andrews(v) -> EquationsOfMotion:
    """Andrews' squeezing mechanism as the Test Set for IVP Solvers writes it (andrews.f, andfunc):
    its mass matrix, force vector f(q, qd) and constraints g(q), typed from there, q = [beta, Theta,
    gamma, Phi, delta, Omega, epsilon]."""
    def mass(q):
        coth, siph, siom = cos(q[1]), sin(q[3]), sin(q[5])
        m = np.zeros((7, 7))
        m[0, 0] = v.m1 * v.ra**2 + v.m2 * (v.rr**2 - 2 * v.da * v.rr * coth + v.da**2) + v.i1 + v.i2
        m[1, 0] = m[0, 1] = v.m2 * (v.da**2 - v.da * v.rr * coth) + v.i2
        m[1, 1] = v.m2 * v.da**2 + v.i2
        m[2, 2] = v.m3 * (v.sa**2 + v.sb**2) + v.i3
        m[3, 3] = v.m4 * (v.e - v.ea) ** 2 + v.i4
        m[4, 3] = m[3, 4] = v.m4 * ((v.e - v.ea) ** 2 + v.zt * (v.e - v.ea) * siph) + v.i4
        m[4, 4] = (v.m4 * (v.zt**2 + 2 * v.zt * (v.e - v.ea) * siph + (v.e - v.ea) ** 2)
                   + v.m5 * (v.ta**2 + v.tb**2) + v.i4 + v.i5)
        m[5, 5] = v.m6 * (v.zf - v.fa) ** 2 + v.i6
        m[6, 5] = m[5, 6] = v.m6 * ((v.zf - v.fa) ** 2 - v.u * (v.zf - v.fa) * siom) + v.i6
        m[6, 6] = (v.m6 * ((v.zf - v.fa) ** 2 - 2 * v.u * (v.zf - v.fa) * siom + v.u**2)
                   + v.m7 * (v.ua**2 + v.ub**2) + v.i6 + v.i7)
        return m

    def forces(t, q, qd):
        bep, thp, php, dep, omp, epp = qd[0], qd[1], qd[3], qd[4], qd[5], qd[6]
        siga, coga = sin(q[2]), cos(q[2])
        xd = v.sd * coga + v.sc * siga + v.xb
        yd = v.sd * siga - v.sc * coga + v.yb
        lang = np.hypot(xd - v.xc, yd - v.yc)
        force = -v.c0 * (lang - v.l0) / lang
        fx, fy = force * (xd - v.xc), force * (yd - v.yc)
        k4, k6 = v.m4 * v.zt * (v.e - v.ea), v.m6 * v.u * (v.zf - v.fa)
        return np.array([
            v.mom - v.m2 * v.da * v.rr * thp * (thp + 2 * bep) * sin(q[1]),
            v.m2 * v.da * v.rr * bep**2 * sin(q[1]),
            fx * (v.sc * coga - v.sd * siga) + fy * (v.sd * coga + v.sc * siga),
            k4 * dep**2 * cos(q[3]),
            -k4 * php * (php + 2 * dep) * cos(q[3]),
            -k6 * epp**2 * cos(q[5]),
            k6 * omp * (omp + 2 * epp) * cos(q[5]),
        ])

    def phi(q):
        be, ga, de, ep = q[0], q[2], q[4], q[6]
        bt, pd, oe = q[0] + q[1], q[3] + q[4], q[5] + q[6]
        fx, fy = v.rr * cos(be) - v.d * cos(bt), v.rr * sin(be) - v.d * sin(bt)
        return np.array([fx - v.ss * sin(ga) - v.xb, fy + v.ss * cos(ga) - v.yb,
                         fx - v.e * sin(pd) - v.zt * cos(de) - v.xa, fy + v.e * cos(pd) - v.zt * sin(de) - v.ya,
                         fx - v.zf * cos(oe) - v.u * sin(ep) - v.xa, fy - v.zf * sin(oe) + v.u * cos(ep) - v.ya])

    def phi_q(q):
        sibe, cobe, siga, coga = sin(q[0]), cos(q[0]), sin(q[2]), cos(q[2])
        side, code, siep, coep = sin(q[4]), cos(q[4]), sin(q[6]), cos(q[6])
        sbt, cbt = sin(q[0] + q[1]), cos(q[0] + q[1])
        spd, cpd = sin(q[3] + q[4]), cos(q[3] + q[4])
        soe, coe = sin(q[5] + q[6]), cos(q[5] + q[6])
        g = np.zeros((6, 7))
        for row in (0, 2, 4):
            g[row, 0], g[row, 1] = -v.rr * sibe + v.d * sbt, v.d * sbt
            g[row + 1, 0], g[row + 1, 1] = v.rr * cobe - v.d * cbt, -v.d * cbt
        g[0, 2], g[1, 2] = -v.ss * coga, -v.ss * siga
        g[2, 3], g[2, 4] = -v.e * cpd, -v.e * cpd + v.zt * side
        g[3, 3], g[3, 4] = -v.e * spd, -v.e * spd - v.zt * code
        g[4, 5], g[4, 6] = v.zf * soe, v.zf * soe - v.u * coep
        g[5, 5], g[5, 6] = -v.zf * coe, -v.zf * coe - v.u * siep
        return g

    def gamma(q, qd):
        """-(d/dt Phi_q) qd: not in the Test Set (index 3 needs none); the directional derivative of
        phi_q along qd by a central difference (error ~h^2 |qd|^3, used only at modest rates)."""
        h = 1e-6
        jdot = (phi_q(q + h * np.asarray(qd)) - phi_q(q - h * np.asarray(qd))) / (2 * h)
        return -jdot @ qd

    return EquationsOfMotion(7, 6, mass, forces, phi, phi_q, gamma, name="andrews_testset")
