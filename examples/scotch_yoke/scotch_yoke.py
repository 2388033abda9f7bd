"""A Scotch yoke, described outside the package: a user's mechanism through the public API.

A crank O-A turns about O; a block pinned at A (it does not turn) slides in the vertical slot of a yoke, which
translates on a horizontal rail. The rail is a prismatic joint with a travel (a tree joint placing the yoke at x);
the slot is a prismatic joint whose guide moves (the yoke), and it closes the loop with one row, x = rc cos(th).
Coordinates q = [th, x]; one constraint row, one degree of freedom. No gravity, no loads: the mechanism coasts.

Run it: ``python examples/scotch_yoke/scotch_yoke.py`` (every stabilization method, 2 s).
"""

from __future__ import annotations

from pathlib import Path


import study

HERE = Path(__file__).resolve().parent
PARAMETERS = ("rc", "mc", "mb", "Jb", "my", "Jy")


def describe(ps: study.ParameterSet) -> study.Description:
    """The joint-level description for one parameter set."""
    d = study.Description("scotch_yoke", ["th", "x"], {k: getattr(ps.values, k) for k in PARAMETERS},
                          "Scotch yoke (example)")
    p = d.p
    th, x = d.q
    d.ground("O", 0, 0)
    d.body("crank", p.mc, p.mc * p.rc ** 2 / 12, {"O": (-p.rc / 2, 0), "A": (p.rc / 2, 0)}, angle=th)
    d.body("block", p.mb, p.Jb, {"A": (0, 0)}, angle=0)
    d.body("yoke", p.my, p.Jy, {"rail": (0, 0), "slot": (0, 0)}, angle=0)
    d.revolute("O", (study.GROUND, "O"), ("crank", "O"))
    d.revolute("A", ("crank", "A"), ("block", "A"))
    d.prismatic("rail", slider=("yoke", "rail"), guide=(study.GROUND, "O"), axis=(1, 0), normal=(0, 1), travel=x)
    d.prismatic("slot", slider=("block", "A"), guide=("yoke", "slot"), axis=(0, 1), normal=(1, 0))   # the loop
    return d


def run(t_end: float = 2.0, rtol: float = 1e-10) -> dict[str, study.SimulationResult]:
    """Every stabilization method, DOP853 at ``rtol``, from the consistent initial state of the parameter file."""
    ps = study.load_parameters("scotch_yoke", reference_dir=HERE)
    mechanism = study.Mechanism(describe(ps), ps)   # q(0), qd(0): the consistent state of the parameter file
    return study.simulate_methods(mechanism, t_end=t_end, integrator="DOP853", rtol=rtol, atol=rtol * 1e-2)


if __name__ == "__main__":
    for method, r in run().items():
        print(method, r.summary())
