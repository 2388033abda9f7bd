"""A five-bar linkage under gravity, described outside the package: a user's mechanism through the public API.

Two ground pivots O = (0, 0) and E = (d, 0); four moving links, uniform bars: the left crank O-A, the left coupler
A-C, the right coupler B-C and the right crank E-B, pinned in a closed loop O-A-C-B-E (ground is the fifth bar).
Coordinates q = [th1, th2, th3, th4], every link's angle from +x (th2 the direction A -> C, th3 the direction
B -> C); the pins O, A, E, B place the links from ground (a spanning tree) and the pin C closes the loop with two
rows: two degrees of freedom. The lengths make every pair of crank angles assemblable and never singular:
d - l1 - l4 = 0.1 m > |l3 - l2| = 0.05 m and d + l1 + l4 = 0.9 m < l2 + l3 = 0.95 m, so |AB| never reaches a
folded or stretched coupler pair. The branch: C below the line A-B (elbow down), sin(th2 - th3) > 0.
Vertical plane, gravity -y, no other loads: released from rest it swings.

Run it: ``python examples/five_bar/five_bar.py`` (every stabilization method, 2 s).
"""

from __future__ import annotations

from pathlib import Path

import sympy as sp

import study

HERE = Path(__file__).resolve().parent
PARAMETERS = ("d", "l1", "l2", "l3", "l4", "m1", "m2", "m3", "m4", "g")


def describe(ps: study.ParameterSet) -> study.Description:
    """The joint-level description for one parameter set."""
    d = study.Description("five_bar", ["th1", "th2", "th3", "th4"], {k: getattr(ps.values, k) for k in PARAMETERS},
                          "five-bar linkage (example)")
    p = d.p
    th1, th2, th3, th4 = d.q
    d.ground("O", 0, 0)
    d.ground("E", p.d, 0)
    d.body("left", p.m1, p.m1 * p.l1 ** 2 / 12, {"O": (-p.l1 / 2, 0), "A": (p.l1 / 2, 0)}, angle=th1)
    d.body("left_coupler", p.m2, p.m2 * p.l2 ** 2 / 12, {"A": (-p.l2 / 2, 0), "C": (p.l2 / 2, 0)}, angle=th2)
    d.body("right_coupler", p.m3, p.m3 * p.l3 ** 2 / 12, {"B": (-p.l3 / 2, 0), "C": (p.l3 / 2, 0)}, angle=th3)
    d.body("right", p.m4, p.m4 * p.l4 ** 2 / 12, {"E": (-p.l4 / 2, 0), "B": (p.l4 / 2, 0)}, angle=th4)
    d.revolute("O", (study.GROUND, "O"), ("left", "O"))
    d.revolute("A", ("left", "A"), ("left_coupler", "A"))
    d.revolute("E", (study.GROUND, "E"), ("right", "E"))
    d.revolute("B", ("right", "B"), ("right_coupler", "B"))
    d.revolute("C", ("left_coupler", "C"), ("right_coupler", "C"))     # the loop closure
    d.gravity(p.g)
    d.assembly_branch(sp.sin(th2 - th3), "sin(th2 - th3) > 0 (C below the line A-B: elbow down)")
    return d


def mechanism() -> study.Mechanism:
    """The example's mechanism; q(0), qd(0): the consistent state of the parameter file."""
    ps = study.load_parameters("five_bar", reference_dir=HERE)
    return study.Mechanism(describe(ps), ps)


def run(t_end: float = 2.0, rtol: float = 1e-10) -> dict[str, study.SimulationResult]:
    """Every stabilization method, DOP853 at ``rtol``, from the consistent initial state of the parameter file."""
    return study.simulate_methods(mechanism(), t_end=t_end, integrator="DOP853", rtol=rtol, atol=rtol * 1e-2)


if __name__ == "__main__":
    for method, r in run().items():
        print(method, r.summary())
