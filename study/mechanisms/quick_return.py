"""Mechanism B: the quick-return (shaper) mechanism of paper 001, sec. 4 (Haug's shaper).

Relative coordinates q = [q1, q2, q3]: crank, rocker and connecting-rod angles (absolute).
Rocker pivot P at the origin; crank pivot O = (0, h1); A = O + l1 e(q1) (crank tip, pin of the
block); E = l2 e(q2) (rocker tip); D = E + l3 e(q3) (rod end, pin of the ram). The block (body 4)
is pinned at A and slides on the rocker line (it turns with the rocker); the ram (body 5) slides on
the guide y = h2. The two prismatic joints are 001's constraints f1 (normal gap of A from the
rocker line) and f2 (h2 - y_D).

Cutting force on the ram along x (001 sec. 4, after Haug):
``on_off``: F_cut while v_D < 0 and x_min <= x_D <= x_max, else 0, with the switching functions
(v_D, x_D - x_min, x_max - x_D); ``smooth``: F_cut s(-v_D/v_ramp) s((x_D - x_min)/x_ramp)
s((x_max - x_D)/x_ramp), s(u) = (1 + tanh u)/2.

Friction (``friction_at``): one of the two prismatic joints is a sliding contact with Coulomb friction, the ram guide
(coefficient ``mu_guide``, the paper's data sets with mu_guide = 0, and 'guide_friction') or the rocker's slot
(``mu_slot``, 'slot_friction': the block slides on the turning rocker, a moving guide); the other is a plain prismatic
joint. One contact, not two with one coefficient zero: a frictionless contact would add its work to the state of every
friction run (and so to an adaptive integrator's error norm), and the exact law would locate its stops too, at the
ram's stroke ends, where holding it is a singular problem beside a sliding slot. A coefficient given for the joint
that is not the contact is refused.
"""

from __future__ import annotations

import sympy as sp

from study.model.joints import GROUND, Description, DescriptionError, Friction
from study.params import ParameterSet

LABEL = "quick-return (paper 001)"
PARAMETERS = ("l1", "l2", "l3", "m1", "m2", "m3", "m4", "m5", "a1", "a2", "a3", "J1", "J2", "J3", "J4", "J5",
              "h1", "h2", "g", "mu_guide", "mu_slot", "friction_at", "M", "F_cut", "x_cut_min", "x_cut_max", "v_ramp",
              "x_ramp", "cutting_law")


def _on(mode):
    """1 when a switching function's mode is +1, 0 when it is -1."""
    return (1 + mode) / 2


def _ramp(u):
    return (1 + sp.tanh(u)) / 2


def describe(ps: ParameterSet) -> Description:
    """The joint-level description of the quick-return mechanism for one parameter set."""
    v = ps.values
    plain = {"ram_guide": "mu_slot", "slot": "mu_guide"}[v.friction_at]
    if getattr(v, plain) != 0:
        raise DescriptionError(f"quick_return/{ps.variant}: {plain} = {getattr(v, plain)!r}, but friction_at = "
                               f"{v.friction_at!r} makes that joint a plain prismatic joint (its coefficient would be "
                               f"ignored): set {plain} = 0 or choose friction_at")
    d = Description("quick_return", ("q1", "q2", "q3"), {k: getattr(v, k) for k in PARAMETERS}, LABEL)
    p = d.p
    q1, q2, q3 = d.q
    d.ground("O", 0, p.h1)
    d.ground("P", 0, 0)
    d.ground("ram_guide", 0, p.h2)
    d.body("crank", p.m1, p.J1, {"O": (-p.a1, 0), "A": (p.l1 - p.a1, 0)}, angle=q1)
    d.body("rocker", p.m2, p.J2, {"P": (-p.a2, 0), "E": (p.l2 - p.a2, 0)}, angle=q2)
    d.body("block", p.m4, p.J4, {"A": (0, 0)}, angle=q2)
    d.body("rod", p.m3, p.J3, {"E": (-p.a3, 0), "D": (p.l3 - p.a3, 0)}, angle=q3)
    d.body("ram", p.m5, p.J5, {"D": (0, 0)}, angle=0)
    d.revolute("O", (GROUND, "O"), ("crank", "O"))
    d.revolute("P", (GROUND, "P"), ("rocker", "P"))
    d.revolute("A", ("crank", "A"), ("block", "A"))
    d.prismatic("block_on_rocker", slider=("block", "A"), guide=("rocker", "P"), axis=(1, 0), normal=(0, 1),
                friction=Friction(p.mu_slot, p.mu_slot) if v.friction_at == "slot" else None)
    d.revolute("E", ("rocker", "E"), ("rod", "E"))
    d.revolute("D", ("rod", "D"), ("ram", "D"))
    d.prismatic("ram_guide", slider=("ram", "D"), guide=(GROUND, "ram_guide"), axis=(1, 0), normal=(0, -1),
                friction=Friction(p.mu_guide, p.mu_guide) if v.friction_at == "ram_guide" else None)
    d.gravity(p.g)
    d.torque("drive", "crank", p.M)
    x, _ = d.position("ram", "D")
    vx, _ = d.velocity("ram", "D")
    if v.cutting_law == "on_off":
        moving_left = d.switch("v_D", vx)
        right_of_min = d.switch("x_D-x_min", x - p.x_cut_min)
        left_of_max = d.switch("x_max-x_D", p.x_cut_max - x)
        cut = p.F_cut * _on(-moving_left) * _on(right_of_min) * _on(left_of_max)
    else:
        cut = p.F_cut * _ramp(-vx / p.v_ramp) * _ramp((x - p.x_cut_min) / p.x_ramp) * _ramp((p.x_cut_max - x) / p.x_ramp)
    d.force("cutting", "ram", "D", cut, 0)
    # 001's configuration: crank pivot above the rocker pivot, rocker pointing up
    d.assembly_branch(sp.sin(q2), "sin(q2) > 0")
    return d
