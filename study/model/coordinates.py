"""From a joint-level description to body-level equations in a chosen coordinate set.

:func:`lower` turns a :class:`~study.model.joints.Description` into a
:class:`~study.model.builder.MechanismBuilder` (bodies as centre-of-mass expressions of q, points,
constraint rows, contacts, loads as expressions of t, q, qd), which :mod:`study.model.derive` and
:mod:`study.model.compile` turn into equations of motion. Two coordinate sets:

``relative``
    The description's own coordinates: each body's angle is the expression the description gives;
    a free body sits where its ``position`` says, the others are placed from ground (or from a free
    body) along a spanning tree of revolute joints and of prismatic joints that have a ``travel`` (description order, a revolute joint marked ``cut=True`` is never a tree joint);
    every other joint is a cut joint whose rows are the loop-closure constraints. Rows that are
    identically zero (a prismatic joint's rotation lock when the angles already agree) are dropped.
``absolute``
    x, y, theta of every body's centre of mass (coordinates ``<body>_x``, ``<body>_y``,
    ``<body>_theta``); every joint contributes its full block of rows (see :mod:`study.model.joints`).

Both sets name their rows the same way (``<joint>_x``, ``<joint>_y`` for a revolute joint,
``<joint>`` for a prismatic joint's gap, ``<joint>_angle`` for its rotation lock), so a row's
multiplier means the same force in both: the multiplier of a cut joint's rows in relative
coordinates equals the multiplier of the same rows in absolute coordinates.

Builder point names are ``<body>.<point>``; every body's centre of mass is also a point
``<body>.com``.
"""

from __future__ import annotations

import sympy as sp

from study.model.builder import MechanismBuilder
from study.model.joints import GROUND, Description, DescriptionError, Distance, Prismatic, Revolute, rotation

COORDINATE_SETS = ("relative", "absolute")


def absolute_names(d: Description) -> tuple[str, ...]:
    return tuple(f"{b}_{k}" for b in d.bodies for k in ("x", "y", "theta"))


def _poses_relative(d: Description) -> tuple[dict[str, tuple[sp.Matrix, sp.Expr]], list]:
    """COM position and angle of every body in q, and the cut joints (description order)."""
    angles = {GROUND: sp.Integer(0), **{name: b.angle for name, b in d.bodies.items()}}
    poses: dict[str, tuple[sp.Matrix, sp.Expr]] = {GROUND: (sp.zeros(2, 1), sp.Integer(0))}
    poses.update({name: (sp.Matrix(b.position), b.angle) for name, b in d.bodies.items() if b.position is not None})
    tree: set[str] = set()
    changed = True
    while changed:  # sweep the joints in order until no body can be placed any more
        changed = False
        for j in d.joints:
            if j.name in tree or isinstance(j, Distance) or \
                    ((j.cut or j.friction is not None) if isinstance(j, Revolute) else j.travel is None):
                continue
            for (pa, ta), (pb, tb) in _tree_ends(j):
                if pa in poses and pb not in poses:
                    anchor = _world(d, poses, pa, ta)
                    if isinstance(j, Prismatic):   # along the axis, in the guide's frame, by the travel
                        _check_sliding(d, j, angles)
                        along = rotation(angles[j.guide[0]]) * sp.Matrix(j.axis) * j.travel
                        anchor = anchor + (along if pa == j.guide[0] else -along)
                    local = sp.Matrix(d.bodies[pb].points[tb])
                    r = sp.expand(anchor - rotation(angles[pb]) * local)
                    poses[pb] = (r, angles[pb])
                    tree.add(j.name)
                    changed = True
                    break
    missing = [b for b in d.bodies if b not in poses]
    if missing:
        raise DescriptionError(f"mechanism {d.name!r}: bodies {missing} cannot be placed from ground through "
                               f"revolute joints or prismatic joints with a travel (relative coordinates need a "
                               f"tree of such joints), and have no position of their own (a free body): "
                               + "; ".join(_why_unplaced(d, b, poses) for b in missing))
    unused = [str(c) for c, qc in zip(d.coordinate_names, d.q)
              if not any(qc in (r.free_symbols | a.free_symbols) for name, (r, a) in poses.items() if name != GROUND)]
    if unused:
        raise DescriptionError(f"mechanism {d.name!r}: coordinates {unused} move no body (no body's angle or "
                               f"position depends on them, directly or through a joint's travel), so they are no "
                               f"degrees of freedom of the mechanism")
    cut = [j for j in d.joints if j.name not in tree]
    return poses, cut


def _why_unplaced(d: Description, body: str, poses) -> str:
    """Why no joint places a body in relative coordinates: its joints, each with the reason it places nothing."""
    reasons = []
    for j in d.joints:
        ends = (j.a, j.b) if isinstance(j, (Revolute, Distance)) else (j.guide, j.slider)
        if body not in (ends[0][0], ends[1][0]):
            continue
        other = ends[1][0] if ends[0][0] == body else ends[0][0]
        if isinstance(j, Distance):
            reasons.append(f"{j.name!r} is a distance joint (a constraint row, never a tree joint)")
        elif isinstance(j, Revolute) and j.cut:
            reasons.append(f"{j.name!r} is marked cut=True")
        elif isinstance(j, Revolute) and j.friction is not None:
            reasons.append(f"{j.name!r} has friction (a cut joint: its reaction is its rows' multipliers)")
        elif isinstance(j, Prismatic) and j.travel is None:
            reasons.append(f"{j.name!r} is a prismatic joint without a travel")
        elif other not in poses:
            reasons.append(f"{j.name!r} joins it to {other!r}, which is not placed either")
    return f"body {body!r}: " + ("; ".join(reasons) if reasons else "no joint has it at an end")


def _tree_ends(j: Revolute | Prismatic) -> tuple:
    """(placed end, end to place) pairs of a joint, both ways round."""
    a, b = (j.a, j.b) if isinstance(j, Revolute) else (j.guide, j.slider)
    return (a, b), (b, a)


def _check_sliding(d: Description, j: Prismatic, angles: dict) -> None:
    """A prismatic tree joint has no rows: the slider's angle must be the guide's plus the offset by itself."""
    if sp.simplify(angles[j.slider[0]] - angles[j.guide[0]] - j.angle_offset) != 0:
        raise DescriptionError(f"mechanism {d.name!r}: joint {j.name!r} has a travel, so it places a body without "
                               f"constraint rows, but the slider's angle is not the guide's plus angle_offset "
                               f"({j.angle_offset}) for every q: give the slider that angle, or drop the travel")


def _world(d: Description, poses, body: str, point: str) -> sp.Matrix:
    if body == GROUND:
        return sp.Matrix(d.ground_points[point])
    r, angle = poses[body]
    return r + rotation(angle) * sp.Matrix(d.bodies[body].points[point])


def joint_rows(d: Description, poses, joint) -> list[tuple[str, sp.Expr]]:
    """The named constraint rows of one joint in the coordinates of ``poses``."""
    if isinstance(joint, Revolute):
        gap = sp.expand(_world(d, poses, *joint.a) - _world(d, poses, *joint.b))
        return [(f"{joint.name}_x", gap[0]), (f"{joint.name}_y", gap[1])]
    if isinstance(joint, Distance):
        gap = _world(d, poses, *joint.a) - _world(d, poses, *joint.b)
        return [(joint.name, sp.sqrt(sp.expand(gap[0] ** 2 + gap[1] ** 2)) - joint.length)]
    guide_angle = poses[joint.guide[0]][1]
    normal = rotation(guide_angle) * sp.Matrix(joint.normal)
    gap = (normal.T * (_world(d, poses, *joint.slider) - _world(d, poses, *joint.guide)))[0]
    rows = [(joint.name, sp.expand(gap))]
    turn = sp.simplify(poses[joint.slider[0]][1] - guide_angle - joint.angle_offset)
    if turn != 0:
        if not turn.free_symbols - set(vars(d.p).values()):  # no coordinate in it: a constant mismatch
            raise DescriptionError(f"mechanism {d.name!r}: joint {joint.name!r}: the body angles differ from the "
                                   f"prismatic joint's angle_offset by the constant {turn}")
        rows.append((f"{joint.name}_angle", turn))
    return rows


def _inputs(d: Description, poses, q: sp.Matrix, qd: sp.Matrix) -> dict[sp.Symbol, sp.Expr]:
    """Every load-law input symbol as an expression of q and qd."""
    out = {}
    for sym, inp in d.inputs.items():
        if inp.point is None:
            angle = poses[inp.body][1]
            out[sym] = angle if inp.kind == "angle" else (sp.Matrix([angle]).jacobian(q) * qd)[0]
        else:
            r = _world(d, poses, inp.body, inp.point)
            k = 0 if inp.kind in ("x", "vx") else 1
            out[sym] = r[k] if inp.kind in ("x", "y") else (r.jacobian(q) * qd)[k]
    return out


def poses(d: Description, coordinates: str) -> tuple[sp.Matrix, sp.Matrix, dict, list]:
    """(q, qd, body poses, constraint joints) of a coordinate set; poses map body -> (r (2x1), angle)."""
    if coordinates == "relative":
        placed, joints = _poses_relative(d)
        return d.q, d.qd, placed, joints
    if coordinates == "absolute":
        names = absolute_names(d)
        q = sp.Matrix(sp.symbols([f"q_{c}" for c in names], real=True))
        qd = sp.Matrix(sp.symbols([f"qd_{c}" for c in names], real=True))
        placed = {GROUND: (sp.zeros(2, 1), sp.Integer(0))}
        for k, b in enumerate(d.bodies):
            placed[b] = (sp.Matrix([q[3 * k], q[3 * k + 1]]), q[3 * k + 2])
        return q, qd, placed, list(d.joints)
    raise ValueError(f"unknown coordinate set {coordinates!r}; valid choices: {', '.join(COORDINATE_SETS)}")


def lower(d: Description, coordinates: str = "relative") -> MechanismBuilder:
    """The body-level builder of a description in ``coordinates`` ('relative' or 'absolute').

    Raises DescriptionError for what :meth:`Description.validate` reports, for a body the relative coordinates cannot
    place (naming its joints and why each places nothing), a relative coordinate that moves no body, and fewer
    than one degree of freedom (coordinates minus constraint rows, naming the joints that have rows)."""
    d.validate()
    q, qd, placed, joints = poses(d, coordinates)
    names = d.coordinate_names if coordinates == "relative" else absolute_names(d)
    name = d.name if coordinates == "relative" else f"{d.name}__absolute"
    b = MechanismBuilder(name, names, d.values)
    bodies, points = {}, {}
    for bname, body in d.bodies.items():
        r, angle = placed[bname]
        bodies[bname] = b.body(bname, r[0], r[1], angle, body.mass, body.inertia)
        points[(bname, "com")] = b.point(f"{bname}.com", r[0], r[1])
        for pname in body.points:
            w = _world(d, placed, bname, pname)
            points[(bname, pname)] = b.point(f"{bname}.{pname}", sp.expand(w[0]), sp.expand(w[1]))
    if d.gravity_g is not None:
        b.gravity(d.gravity_g)
    subs = _inputs(d, placed, q, qd)
    for pot in d.potentials:
        b.potential(pot.name, pot.energy.xreplace(subs))
    counts = []   # (joint, number of its rows)
    for jnt in joints:
        rows = joint_rows(d, placed, jnt)
        counts.append((jnt.name, len(rows)))
        if isinstance(jnt, Prismatic) and jnt.friction is not None:
            (gap_name, _), rest = rows[0], rows[1:]   # the contact writes the same gap row itself
            fr = jnt.friction
            if jnt.guide[0] == GROUND:          # guide fixed in ground: global = guide frame
                normal = tuple(jnt.normal)
                tangent = tuple(jnt.axis)
                offset = sp.expand(sum(n * x for n, x in zip(normal, d.ground_points[jnt.guide[1]])))
                b.sliding_contact(gap_name, points[jnt.slider], normal, offset, tangent, fr.mu_static,
                                  fr.mu_kinetic, fr.resistance)
            else:                               # moving guide: its axis and normal turn with it
                turn = rotation(placed[jnt.guide[0]][1])
                normal = tuple(turn * sp.Matrix(jnt.normal))
                tangent = tuple(turn * sp.Matrix(jnt.axis))
                offset = sum(n * x for n, x in zip(normal, _world(d, placed, *jnt.guide)))
                b.sliding_contact(gap_name, points[jnt.slider], normal, offset, tangent, fr.mu_static,
                                  fr.mu_kinetic, fr.resistance, guide=bodies[jnt.guide[0]])
            for row in rest:
                b.constraint(*row)
        else:
            for row in rows:
                b.constraint(*row)
            if isinstance(jnt, Revolute) and jnt.friction is not None:   # its two rows' multipliers: the reaction
                fr = jnt.friction
                b.pin_friction(jnt.name, [n for n, _ in rows], *(None if e[0] == GROUND else bodies[e[0]]
                                                                  for e in (jnt.a, jnt.b)),
                               fr.mu_static, fr.mu_kinetic, jnt.radius, fr.resistance)
    m, r = len(names), len(b.constraints)
    if r >= m:
        held = ", ".join(f"{n!r} ({_count(k, 'row')})" for n, k in counts if k)
        raise DescriptionError(f"mechanism {d.name!r}: in {coordinates} coordinates, {_count(m, 'coordinate')} and "
                               f"{_count(r, 'constraint row')} (joints {held}) leave {m - r} degrees of freedom; a "
                               f"mechanism needs at least one (a joint too many, or a coordinate too few)")
    for name_, expr, mode in d.switches:
        b.switch(name_, expr.xreplace(subs), mode)
    for load in d.loads:
        comps = tuple(c.xreplace(subs) for c in load.components)
        if load.point is None:
            b.torque(load.name, bodies[load.body], comps[0])
        else:
            b.force(load.name, points[(load.body, load.point)], *comps)
    return b


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")
