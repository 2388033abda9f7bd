"""An oscillating-cylinder mechanism, described outside the package: a user's mechanism through the public API.

A crank O-A turns about O; a cylinder swings about C = (d, 0); a rod slides in the cylinder (a prismatic joint whose
guide, the cylinder, moves: its travel s places the rod, so it is a tree joint) and its end B is pinned to the
crank's tip A, which closes the loop. Coordinates q = [th, ph, s]: the crank's and the cylinder's angles and the
rod's travel; two constraint rows (the pin A = B), one degree of freedom.

Run it: ``python examples/oscillating_cylinder/oscillating_cylinder.py`` (every stabilization method, 2 s).
"""

from __future__ import annotations

from pathlib import Path


import study

HERE = Path(__file__).resolve().parent
PARAMETERS = ("rc", "d", "mc", "my", "Jy", "mr", "lr", "g")


def describe(ps: study.ParameterSet) -> study.Description:
    """The joint-level description for one parameter set."""
    d = study.Description("oscillating_cylinder", ["th", "ph", "s"],
                          {k: getattr(ps.values, k) for k in PARAMETERS}, "oscillating cylinder (example)")
    p = d.p
    th, ph, s = d.q
    d.ground("O", 0, 0)
    d.ground("C", p.d, 0)
    d.body("crank", p.mc, p.mc * p.rc ** 2 / 12, {"O": (-p.rc / 2, 0), "A": (p.rc / 2, 0)}, angle=th)
    d.body("cylinder", p.my, p.Jy, {"C": (0, 0)}, angle=ph)
    d.body("rod", p.mr, p.mr * p.lr ** 2 / 12, {"B": (p.lr / 2, 0)}, angle=ph)
    d.revolute("O", (study.GROUND, "O"), ("crank", "O"))
    d.revolute("C", (study.GROUND, "C"), ("cylinder", "C"))
    d.prismatic("sleeve", slider=("rod", "B"), guide=("cylinder", "C"), axis=(1, 0), normal=(0, 1), travel=s)
    d.revolute("pin", ("crank", "A"), ("rod", "B"))      # the loop closure
    d.gravity(p.g)
    d.assembly_branch(s, "s > 0 (the rod's end on the crank's side of C)")
    return d


def run(t_end: float = 2.0, rtol: float = 1e-10) -> dict[str, study.SimulationResult]:
    """Every stabilization method, DOP853 at ``rtol``, from the consistent initial state of the parameter file."""
    ps = study.load_parameters("oscillating_cylinder", reference_dir=HERE)
    mechanism = study.Mechanism(describe(ps), ps)   # q(0), qd(0): the consistent state of the parameter file
    return study.simulate_methods(mechanism, t_end=t_end, integrator="DOP853", rtol=rtol, atol=rtol * 1e-2)


if __name__ == "__main__":
    for method, r in run().items():
        print(method, r.summary())
