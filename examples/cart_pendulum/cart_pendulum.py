"""A cart on a horizontal rail with Coulomb friction, carrying a pendulum: a user's mechanism through the public API.

The cart is a free body placed by its own coordinates (x, y: its centre of mass); the rail is a prismatic joint to
ground without a travel, so it is a cut joint: its gap row y = 0 holds the cart on the rail, and that row's
multiplier is the normal force which the Coulomb friction (``study.Friction``, mu_s = mu_k = mu) scales. (Friction
needs a prismatic joint without a travel; its guide may be ground, as here, or a moving body.) The
pendulum, a uniform rod, is hinged to the cart at its top end; its angle th (from the downward vertical) is a
coordinate and the hinge places it from the cart (a tree joint). Vertical plane, gravity -y.

The cart's angle: the rail keeps the cart from turning, so by default the cart is given the angle 0 and the rail's
rotation lock is identically satisfied (no row): q = [x, y, th], one constraint row, two degrees of freedom. This is
the form every engine takes, Exudyn included. ``describe(ps, turning=True)`` gives the cart an angle coordinate ph
instead, q = [x, y, ph, th], held at 0 by the rail's second row ``rail_angle``: the in-house engines run it and
move the same way, but the Exudyn translator (study.exudyn_models) has no counterpart for a prismatic joint's
``_angle`` row (its multiplier, the rail's holding torque), so Exudyn cannot run that form.

Run it: ``python examples/cart_pendulum/cart_pendulum.py`` (the exact stick/slip law, every stabilization method, 2 s).
"""

from __future__ import annotations

from pathlib import Path


import study

HERE = Path(__file__).resolve().parent
PARAMETERS = ("mc", "Jc", "mp", "lp", "mu", "g")


def describe(ps: study.ParameterSet, turning: bool = False) -> study.Description:
    """The joint-level description for one parameter set; ``turning``: the cart's angle is a coordinate (see the
    module's docstring), else the cart has the angle 0."""
    coordinates = ["x", "y", "ph", "th"] if turning else ["x", "y", "th"]
    d = study.Description("cart_pendulum", coordinates, {k: getattr(ps.values, k) for k in PARAMETERS},
                          "cart-pendulum with rail friction (example)")
    p = d.p
    x, y, th = d.q[0], d.q[1], d.q[-1]
    d.ground("O", 0, 0)
    d.body("cart", p.mc, p.Jc, {"rail": (0, 0), "hinge": (0, 0)}, angle=d.q[2] if turning else 0, position=(x, y))
    d.body("pendulum", p.mp, p.mp * p.lp ** 2 / 12, {"top": (0, p.lp / 2)}, angle=th)
    # no travel: a cut joint, whose gap row's multiplier is the normal force that the friction scales
    d.prismatic("rail", slider=("cart", "rail"), guide=(study.GROUND, "O"), axis=(1, 0), normal=(0, 1),
                friction=study.Friction(p.mu, p.mu))
    d.revolute("hinge", ("cart", "hinge"), ("pendulum", "top"))
    d.gravity(p.g)
    return d


def mechanism() -> study.Mechanism:
    """The example's mechanism; q(0), qd(0): the consistent state of the parameter file."""
    ps = study.load_parameters("cart_pendulum", reference_dir=HERE)
    return study.Mechanism(describe(ps), ps)


def run(t_end: float = 2.0, rtol: float = 1e-10, friction: str = "exact") -> dict[str, study.SimulationResult]:
    """Every stabilization method, DOP853 at ``rtol``, with the ``friction`` treatment of the rail."""
    return study.simulate_methods(mechanism(), t_end=t_end, integrator="DOP853", rtol=rtol, atol=rtol * 1e-2,
                                  friction=friction)


if __name__ == "__main__":
    for method, r in run().items():
        print(method, r.summary(), [x for x in r.stats["friction_transitions"] if x["contact"]])
