"""Andrews' squeezing mechanism: seven bodies, seven angles, six constraints, a spring and a motor.

Hairer and Wanner, *Solving Ordinary Differential Equations II*, sec. VII.7; problem "andrews" of
the Test Set for IVP Solvers (Bari / CWI, ``andrews.f``), whose names and parameters are used here.

Relative coordinates q = [beta, Theta, gamma, Phi, delta, Omega, epsilon], the Test Set's y(1..7).
Fixed points O (origin), A (xa, ya), B (xb, yb), C (xc, yc). Body angles and joints:

* body 1, crank OF, angle beta: pivot O, F = rr e(beta); the motor torque mom drives it;
* body 2, rod FE, angle beta + Theta: E = F - d e(beta + Theta);
* body 3, angle gamma, pivot B: E = B + R(gamma) (0, -ss); spring point D = B + R(gamma) (sd, -sc),
  the spring (stiffness c0, rest length l0) joins D and the fixed point C;
* body 5, angle delta, pivot A: G = A + zt e(delta);
* body 4, angle Phi + delta: E = G + R(Phi + delta) (0, -e);
* body 7, angle epsilon, pivot A: H = A + R(epsilon) (0, -u);
* body 6, angle Omega + epsilon: E = H + zf e(Omega + epsilon).

The spanning tree (O, F, B, A5, G, A7, H) places every body from its angle; E, where bodies 2, 3,
4 and 6 meet, is cut into three two-body joints E3, E4, E6 (rod FE against bodies 3, 4, 6), whose
rows are the Test Set's g(1..6) with the same signs, so the multipliers are its y(22..27).

Centres of mass: the Test Set gives only what its mass matrix needs. Bodies 2, 4 and 6 have their
centre of mass on the line of their two joints (at da from F, at ea from E, at fa from E: the only
placement that gives its off-diagonal terms); bodies 1, 3, 5, 7 turn about a fixed pivot and only
their distance from it enters (ra, sqrt(sa^2 + sb^2), sqrt(ta^2 + tb^2), sqrt(ua^2 + ub^2)). Their
direction in the body is this description's choice (stated per body below); there is no gravity,
so it changes no motion, only the pivots' reactions.
"""

from __future__ import annotations

from study.model.joints import GROUND, Description
from study.params import ParameterSet

LABEL = "Andrews' squeezing mechanism (Test Set for IVP solvers)"
PARAMETERS = ("m1", "m2", "m3", "m4", "m5", "m6", "m7", "xa", "ya", "xb", "yb", "xc", "yc", "c0",
              "i1", "i2", "i3", "i4", "i5", "i6", "i7", "d", "da", "e", "ea", "rr", "ra", "l0",
              "ss", "sa", "sb", "sc", "sd", "ta", "tb", "u", "ua", "ub", "zf", "zt", "fa", "mom")
#: The Test Set's horizon [s]: the crank turns ~2.5 times in it (generic checks scale their horizons by it).
TIME_SCALE = 0.03
COORDINATES = ("beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon")


def describe(ps: ParameterSet) -> Description:
    """The joint-level description of Andrews' squeezing mechanism for one parameter set."""
    v = ps.values
    d = Description("andrews", COORDINATES, {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    p = d.p
    beta, theta, gamma, phi, delta, omega, eps = d.q
    d.ground("O", 0, 0)
    d.ground("A", p.xa, p.ya)
    d.ground("B", p.xb, p.yb)
    d.ground("C", p.xc, p.yc)
    # body 1: centre of mass at ra from O along OF (choice of direction)
    d.body("body1", p.m1, p.i1, {"O": (-p.ra, 0), "F": (p.rr - p.ra, 0)}, angle=beta)
    d.body("body2", p.m2, p.i2, {"F": (p.da, 0), "E": (p.da - p.d, 0)}, angle=beta + theta)
    # body 3: centre of mass at B + R(gamma) (sa, -sb) (choice of direction)
    d.body("body3", p.m3, p.i3, {"B": (-p.sa, p.sb), "E": (-p.sa, p.sb - p.ss), "D": (p.sd - p.sa, p.sb - p.sc)},
           angle=gamma)
    d.body("body4", p.m4, p.i4, {"G": (0, p.e - p.ea), "E": (0, -p.ea)}, angle=phi + delta)
    # body 5: centre of mass at A + R(delta) (ta, tb) (choice of direction)
    d.body("body5", p.m5, p.i5, {"A": (-p.ta, -p.tb), "G": (p.zt - p.ta, -p.tb)}, angle=delta)
    d.body("body6", p.m6, p.i6, {"H": (p.fa - p.zf, 0), "E": (p.fa, 0)}, angle=omega + eps)
    # body 7: centre of mass at A + R(epsilon) (ua, ub) (choice of direction)
    d.body("body7", p.m7, p.i7, {"A": (-p.ua, -p.ub), "H": (-p.ua, -p.u - p.ub)}, angle=eps)
    d.revolute("O", (GROUND, "O"), ("body1", "O"))
    d.revolute("F", ("body1", "F"), ("body2", "F"))
    d.revolute("B", (GROUND, "B"), ("body3", "B"))
    d.revolute("A5", (GROUND, "A"), ("body5", "A"))
    d.revolute("G", ("body5", "G"), ("body4", "G"))
    d.revolute("A7", (GROUND, "A"), ("body7", "A"))
    d.revolute("H", ("body7", "H"), ("body6", "H"))
    d.revolute("E3", ("body2", "E"), ("body3", "E"), cut=True)
    d.revolute("E4", ("body2", "E"), ("body4", "E"), cut=True)
    d.revolute("E6", ("body2", "E"), ("body6", "E"), cut=True)
    d.spring("spring", ("body3", "D"), (GROUND, "C"), p.c0, p.l0)
    d.torque("motor", "body1", p.mom)
    return d
