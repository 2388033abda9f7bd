"""A pendulum with Coulomb friction in its pin: a bar on a ground pin, released from rest, that comes to rest.

The bar (mass m, centroidal inertia Ic) hangs from the ground pin O at its point (0, l) (body frame), vertical plane,
gravity -y. The bar is a free body, q = (th, x, y) with (x, y) its centre of mass, and the pin is a revolute joint
with friction (radius r, mu_s, mu_k, constant torque T0), hence a cut joint whose two rows' multipliers are its
reaction R. Sliding, the pin's torque is mu_k r |R|_delta + T0 against the rotation; at rest it holds the bar while
the gravity moment m g l |sin th| stays within mu_s r |R|_delta + T0. The study's own case, not a paper's.
"""

from __future__ import annotations

from study.model.joints import GROUND, Description, Friction
from study.params import ParameterSet

LABEL = "pendulum with pin friction"
PARAMETERS = ("m", "Ic", "l", "g", "mu_s", "mu_k", "r", "T0")


def describe(ps: ParameterSet) -> Description:
    v = ps.values
    d = Description("pin_pendulum", ("th", "x", "y"), {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    p = d.p
    th, x, y = d.q
    d.ground("O", 0, 0)
    d.body("bar", p.m, p.Ic, {"pin": (0, p.l)}, angle=th, position=(x, y))
    d.revolute("pin", (GROUND, "O"), ("bar", "pin"), friction=Friction(p.mu_s, p.mu_k, p.T0), radius=p.r)
    d.gravity(p.g)
    return d
