"""The checks of a joint-level description (:meth:`study.model.joints.Description.validate`), one function per part.

Each returns the problems it finds, one sentence each, naming the body, joint, load, point or input and why:
unknown bodies and points, a joint between a body and itself, a body that no joint places and that has no position,
a mass or inertia that is not positive (a number, or with the parameter values), friction data out of range, and
symbols that are not the description's in a load law, potential, switch or the assembly branch. What needs the
coordinate set (the placement tree, the degrees of freedom) is checked by :func:`study.model.coordinates.lower`.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from study.model.elements import GROUND, Distance, Revolute


def description_problems(d: Any) -> list[str]:
    """Every problem of the description ``d`` (a :class:`~study.model.joints.Description`)."""
    params = set(vars(d.p).values())
    values = {getattr(d.p, k): sp.Float(v) for k, v in d.values.items()}
    joint_problems, joined = _joints(d, params, values)
    return (_names(d) + _bodies(d, params, values) + joint_problems + _unplaced(d, joined) + _loads(d, params)
            + _potentials_and_switches(d, params) + _inputs(d) + _branch(d, params))


def point_problem(d: Any, ref: tuple[str, str]) -> str | None:
    """Why a (body, point) reference names no point of the description, or None."""
    body, point = ref
    if body == GROUND:
        return None if point in d.ground_points else f"unknown ground point {point!r}"
    if body not in d.bodies:
        return f"unknown body {body!r}"
    if point not in d.bodies[body].points:
        return f"body {body!r} has no point {point!r} (has {sorted(d.bodies[body].points)})"
    return None


def _at(d: Any, where: str, *refs: tuple[str, str]) -> list[str]:
    return [f"{where}: {p}" for p in (point_problem(d, ref) for ref in refs) if p]


def _stray(what: str, e: sp.Basic, allowed: set) -> list[str]:
    stray = e.free_symbols - allowed
    return [f"{what} uses unknown symbols {sorted(map(str, stray))}"] if stray else []


def _names(d: Any) -> list[str]:
    out = [] if d.bodies else ["no bodies"]
    names = [j.name for j in d.joints] + [ld.name for ld in d.loads] + [pt.name for pt in d.potentials]
    dup = sorted({n for n in names if names.count(n) > 1})
    return out + ([f"duplicate joint or load names: {dup}"] if dup else [])


def _positive(b: Any, key: str, e: sp.Basic, params: set, values: dict) -> list[str]:
    """A body's mass or inertia: parameters only, and positive and finite with the parameter values."""
    if e.free_symbols - params:
        return [f"body {b.name!r}.{key} uses symbols other than parameters: {sorted(map(str, e.free_symbols - params))}"]
    value = e.xreplace(values)   # a number: no other symbols (checked above)
    if value.is_extended_positive and value.is_finite:
        return []
    finite = bool(value.is_real and value.is_finite)
    shown = f"{float(value):g}" if finite else str(value)
    given = "" if e.is_number else f" ({e} with the parameter values)"
    return [f"body {b.name!r}.{key} = {shown}{given} is not {'positive' if finite else 'a finite positive number'} "
            f"(a body needs a positive mass and centroidal inertia)"]


def _bodies(d: Any, params: set, values: dict) -> list[str]:
    out = []
    for b in d.bodies.values():
        out += _positive(b, "mass", b.mass, params, values) + _positive(b, "inertia", b.inertia, params, values)
        for key, e in (("angle", b.angle), *((f"position[{i}]", x) for i, x in enumerate(b.position or ()))):
            out += _stray(f"body {b.name!r}.{key}", e, params | set(d.q))
        out += [f"point {b.name}.{pname} must be constant in the body frame"
                for pname, xy in b.points.items() for e in xy if e.free_symbols - params]
    return out


def _joints(d: Any, params: set, values: dict) -> tuple[list[str], set]:
    """The joints' problems and the bodies they join."""
    out, joined = [], set()
    for j in d.joints:
        ends = (j.a[0], j.b[0]) if isinstance(j, (Revolute, Distance)) else (j.slider[0], j.guide[0])
        joined.update(ends)
        if ends[0] == ends[1]:
            what = "ground to itself" if ends[0] == GROUND else f"body {ends[0]!r} to itself"
            out.append(f"joint {j.name!r} joins {what} (a joint connects two different bodies, or a body and ground)")
        if isinstance(j, (Revolute, Distance)):
            out += _at(d, f"joint {j.name!r}", j.a, j.b)
            if isinstance(j, Distance) and j.length.free_symbols - params:
                out.append(f"joint {j.name!r}: length must be a constant (numbers and parameters)")
            if isinstance(j, Revolute):
                out += _pin_problems(j, params, values)
        else:
            out += _at(d, f"joint {j.name!r}", j.slider, j.guide) + _prismatic_problems(d, j, params)
    return out, joined


def _prismatic_problems(d: Any, j: Any, params: set) -> list[str]:
    out = []
    ax, n = j.axis, j.normal
    if sp.simplify(ax[0] ** 2 + ax[1] ** 2 - 1) != 0 or sp.simplify(n[0] ** 2 + n[1] ** 2 - 1) != 0 \
            or sp.simplify(ax[0] * n[0] + ax[1] * n[1]) != 0:
        out.append(f"joint {j.name!r}: axis and normal must be orthogonal unit vectors")
    if j.friction is not None and j.slider[0] == GROUND:
        out.append(f"joint {j.name!r}: friction needs a slider body (the slider is ground; make ground the guide)")
    if j.travel is not None:
        out += _stray(f"joint {j.name!r}: travel", j.travel, params | set(d.q))
        if j.friction is not None:
            out.append(f"joint {j.name!r}: a joint with friction cannot have a travel (its normal force is the "
                       f"multiplier of its gap row, which a tree joint does not have)")
    return out


def _pin_problems(j: Revolute, params: set, values: dict) -> list[str]:
    """What is wrong with a revolute joint's friction data (radius, coefficients, constant torque, cut)."""
    if j.friction is None:
        return [] if j.radius is None else [f"joint {j.name!r}: radius is given without friction (it is the pin's "
                                            f"radius for friction=Friction(...))"]
    out = []
    if j.cut is False:
        out.append(f"joint {j.name!r}: a revolute joint with friction is a cut joint (its reaction, which sets the "
                   f"friction torque, is the multipliers of its rows), so it cannot be cut=False")
    if j.radius is None:
        out.append(f"joint {j.name!r}: friction on a revolute joint needs radius=r (the pin's radius [m])")
    fr = j.friction
    for key, e, positive in (("radius", j.radius, True), ("friction.mu_kinetic", fr.mu_kinetic, False),
                             ("friction.mu_static", fr.mu_static, False),
                             ("friction.resistance (the constant torque T0)", fr.resistance, False)):
        if e is None:
            continue
        e = sp.sympify(e)
        if e.free_symbols - params:
            out.append(f"joint {j.name!r}: {key} must be a constant (numbers and parameters)")
            continue
        v = e.xreplace(values)
        ok = v.is_finite and (v.is_extended_positive if positive else v.is_extended_nonnegative)
        if not ok:
            out.append(f"joint {j.name!r}: {key} = {v} must be finite and {'> 0' if positive else '>= 0'}")
    return out


def _unplaced(d: Any, joined: set) -> list[str]:
    return [f"body {b.name!r}: no joint places it and it has no position of its own (join it to ground or to another "
            f"body, or give a free body position=(x, y))"
            for b in d.bodies.values() if b.position is None and b.name not in joined]


def _loads(d: Any, params: set) -> list[str]:
    out = []
    allowed = params | set(d.inputs) | {d.t} | {m for _, _, m in d.switches}
    for ld in d.loads:
        if ld.body not in d.bodies:
            out.append(f"load {ld.name!r}: unknown body {ld.body!r}")
        elif ld.point is not None:
            out += _at(d, f"load {ld.name!r}", (ld.body, ld.point))
        for e in ld.components:
            out += [f"{p} (a load law is an expression of parameters, the description's inputs, t and switch modes)"
                    for p in _stray(f"load {ld.name!r}", e, allowed)]
    return out


def _potentials_and_switches(d: Any, params: set) -> list[str]:
    out = []
    static = params | {s for s, inp in d.inputs.items() if inp.kind in ("x", "y", "angle")}
    for pot in d.potentials:
        out += [f"{p} (a potential is an expression of parameters and position or angle inputs)"
                for p in _stray(f"potential {pot.name!r}", pot.energy, static)]
    for name, e, _ in d.switches:
        out += _stray(f"switch {name!r}", e, params | set(d.inputs) | {d.t})
    return out


def _inputs(d: Any) -> list[str]:
    """Inputs of unknown bodies or points, one problem per point, naming the laws that use them."""
    users: dict[sp.Symbol, list[str]] = {}   # input symbol -> the loads, potentials and switches that use it
    for who, exprs in ([(f"load {ld.name!r}", ld.components) for ld in d.loads]
                       + [(f"potential {pt.name!r}", (pt.energy,)) for pt in d.potentials]
                       + [(f"switch {n!r}", (e,)) for n, e, _ in d.switches]):
        for sym in set().union(*(e.free_symbols for e in exprs)) & set(d.inputs):
            users.setdefault(sym, []).append(who)
    bad: dict[tuple, tuple[dict, dict]] = {}   # (target, problem) -> (kinds, users)
    for sym, inp in d.inputs.items():
        if inp.point is None:
            problem = None if inp.body in d.bodies else f"unknown body {inp.body!r}"
            of = f"of {inp.body!r}"
        else:
            problem = point_problem(d, (inp.body, inp.point))
            of = f"of point {inp.body}.{inp.point}"
        if problem:
            kinds, who = bad.setdefault((of, problem), ({}, {}))
            kinds[inp.kind] = None
            who.update(dict.fromkeys(users.get(sym, [])))
    return [f"{', '.join(who) or 'an unused input'}: input {', '.join(kinds)} {of}: {problem}"
            for (of, problem), (kinds, who) in bad.items()]


def _branch(d: Any, params: set) -> list[str]:
    if d.branch is None:
        return []
    return [f"{p} (a branch condition is an expression of q and parameters)"
            for p in _stray(f"assembly branch {d.branch[1]!r}", d.branch[0], params | set(d.q))]
