"""The N-four-bar mechanism: problem A02 of the IFToMM / MBS benchmark library (lim.ii.udc.es/mbsbenchmark).

N square windows in a row: N + 1 cranks pinned to ground at (i L, 0), i = 0..N, and N couplers,
coupler j joining the tops B_{j-1} and B_j of cranks j - 1 and j. All 2N + 1 links are uniform bars of
length L and mass m. Relative coordinates q = [th_0 .. th_N, ph_1 .. ph_N]: the absolute angles of the
cranks and of the couplers. The coupler-to-crank joint at each window's right end is the cut joint, so
each window gives one loop closure (two rows, joint R<j>; L<j> is the coupler's left pin): m = 2N + 1 coordinates, r = 2N rows, one degree of
freedom. In the horizontal position (every crank along the ground line) the x rows of every loop vanish
together: rank Phi_q drops from 2N to N and the mobility jumps from 1 to N + 1.

The number of windows N is a parameter of the parameter file (a positive integer), so the variants
``n5`` .. ``n40`` are data. Initial guess: every crank vertical, couplers horizontal
(:func:`initial_guess`, used by the registry in place of the file's printed q(0), whose length is
that of the N = 2 form).
"""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from study.model.joints import GROUND, Description, DescriptionError
from study.params import ParameterSet

LABEL = "N-four-bar (IFToMM A02)"
PARAMETERS = ("N", "L", "m", "g")


def windows(ps: ParameterSet) -> int:
    """The number of windows N, checked to be a positive integer."""
    n = ps.values.N
    if not (n >= 1 and float(n).is_integer()):
        raise DescriptionError(f"n_four_bar: N = {n!r} must be a positive integer (the number of windows)")
    return int(n)


def coordinate_names(n: int) -> tuple[str, ...]:
    return tuple(f"th{i}" for i in range(n + 1)) + tuple(f"ph{j}" for j in range(1, n + 1))


def describe(ps: ParameterSet) -> Description:
    """The joint-level description of the N-four-bar for one parameter set."""
    n = windows(ps)
    v = ps.values
    d = Description("n_four_bar", coordinate_names(n), {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    p = d.p
    th, ph = d.q[:n + 1], d.q[n + 1:]
    inertia = p.m * p.L ** 2 / 12           # uniform bar about its centre
    ends = {"O": (-p.L / 2, 0), "B": (p.L / 2, 0)}
    for i in range(n + 1):
        d.ground(f"O{i}", i * p.L, 0)
        d.body(f"crank{i}", p.m, inertia, ends, angle=th[i])
        d.revolute(f"O{i}", (GROUND, f"O{i}"), (f"crank{i}", "O"))
    for j in range(1, n + 1):
        d.body(f"coupler{j}", p.m, inertia, {"left": (-p.L / 2, 0), "right": (p.L / 2, 0)}, angle=ph[j - 1])
        d.revolute(f"L{j}", (f"crank{j - 1}", "B"), (f"coupler{j}", "left"))
    for j in range(1, n + 1):       # listed last: the loop closures (cut joints)
        d.revolute(f"R{j}", (f"coupler{j}", "right"), (f"crank{j}", "B"))
    d.gravity(p.g)
    d.assembly_branch(sp.cos(ph[0]), "cos(ph1) > 0 (parallelogram windows)")
    return d


def initial_guess(ps: ParameterSet) -> tuple[np.ndarray, np.ndarray]:
    """Newton's start for any N: cranks vertical (th = pi/2), couplers horizontal (ph = 0), at rest."""
    n = windows(ps)
    q = np.array([math.pi / 2] * (n + 1) + [0.0] * n)
    return q, np.zeros_like(q)
