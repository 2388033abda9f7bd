"""Paper 000's slider-crank with Coulomb friction in its three pins O, A, B as well as in the slider guide.

The bodies, masses, inertias, lengths, loads (drive torque M, the alpha law, gravity) and the guide's friction
(mu, F) are paper 000's, as are their description (:mod:`study.mechanisms.slider_crank`'s ``add_bodies`` and
``add_guide_and_loads``) and their values: ``reference/slider_crank_pins.toml`` extends ``reference/slider_crank.toml``
(its entries and variants, inherited as they are). What it adds is the study's own choice: each pin P in {O, A, B}
is a revolute joint with friction, radius ``r_P`` and coefficient ``mu_P`` (static = kinetic, no constant torque
T0), whose torque is -(mu_P r_P |R_P|_delta) s(omega_rel) on its first body and the opposite on its second
(``study.model.joints.Revolute``); omega_rel is -th1' at O (ground, crank), th1' - th2' at A (crank, rod) and th2' at
B (rod, slider).

A pin with friction is a cut joint (its reaction is its two rows' multipliers), so no joint places a body and
every body has its own coordinates (a free body): q = [x1, y1, th1, x2, y2, th2, x3, y3], the centres of mass and
angles of the crank (balanced: its centre of mass is the pivot O) and of the rod (C2), and the slider's centre B.
The slider keeps the angle 0, so the guide's rotation lock holds identically and has no row: the form the Exudyn
translator also takes. Rows: O, A, B (two each) and the guide's gap y_B (its multiplier the normal force): seven
rows, one degree of freedom. th1 is 000's q1 and th2 its q1 + q2; the branch is cos(th2) > 0 (B beyond A from O,
as in 000).
"""

from __future__ import annotations

import sympy as sp

from study.mechanisms import slider_crank
from study.model.joints import Description, Friction
from study.params import ParameterSet

LABEL = "slider-crank with friction in its pins (paper 000's data)"
PINS = tuple(slider_crank.PIN_ENDS)
#: The paper mechanism's entries (inherited from its file), each pin's radius and coefficient, and the friction treatment
#: a run takes unless told otherwise (read by study.friction_default.default_friction).
PARAMETERS = (slider_crank.PARAMETERS + tuple(f"r_{p}" for p in PINS) + tuple(f"mu_{p}" for p in PINS)
              + ("friction_treatment",))
COORDINATES = ("x1", "y1", "th1", "x2", "y2", "th2", "x3", "y3")
COORDINATE_UNIT = "m, rad"     # positions x, y [m], angles th [rad]


def describe(ps: ParameterSet, pin_friction: bool = True) -> Description:
    """The joint-level description for one parameter set; ``pin_friction=False``: the same coordinates with ideal
    pins (no friction data: paper 000's slider-crank in these coordinates, which every friction treatment and
    engine takes)."""
    v = ps.values
    d = Description("slider_crank_pins", COORDINATES, {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    p = d.p
    x1, y1, th1, x2, y2, th2, x3, y3 = d.q
    slider_crank.add_bodies(d, th1, th2, positions={"crank": (x1, y1), "rod": (x2, y2), "slider": (x3, y3)})
    for pin, (a, b) in slider_crank.PIN_ENDS.items():
        if pin_friction:
            mu = getattr(p, f"mu_{pin}")
            d.revolute(pin, a, b, friction=Friction(mu, mu), radius=getattr(p, f"r_{pin}"))
        else:
            d.revolute(pin, a, b)
    slider_crank.add_guide_and_loads(d, v.alpha_law)
    d.assembly_branch(sp.cos(th2), "cos(th2) > 0")
    return d
