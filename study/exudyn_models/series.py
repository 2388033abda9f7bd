"""The description's quantities at every step, from Exudyn's body series (centre-of-mass pose and rates): a law's
inputs and values, a body point's position and velocity, a guide's axis."""

from __future__ import annotations

import numpy as np
import sympy as sp

from study.exudyn_models.load_law import Law
from study.model.joints import GROUND, Description, Prismatic

Array = np.ndarray


def series_inputs(law: Law, d: Description, subs: dict, pos: dict, vel: dict) -> list[Array]:
    """The law's inputs at every step from Exudyn's body series (COM pose and rates)."""
    out = []
    for inp in law.kinds:
        if inp.point is None:
            out.append(pos[inp.body][:, 2] if inp.kind == "angle" else vel[inp.body][:, 2])
        else:
            out.append(point_series(d, subs, pos, vel, inp.body, inp.point)[inp.kind])
    return out


def point_series(d: Description, subs: dict, pos: dict, vel: dict, body: str, point: str) -> dict[str, Array]:
    """Global position and velocity of a body point (or a ground point) at every step from the body's COM
    pose and rates."""
    if body == GROUND:
        x, y = (float(sp.sympify(c).xreplace(subs)) for c in d.ground_points[point])
        n = len(next(iter(pos.values())))
        return {"x": np.full(n, x), "y": np.full(n, y), "vx": np.zeros(n), "vy": np.zeros(n)}
    local = np.array([float(sp.sympify(c).xreplace(subs)) for c in d.bodies[body].points[point]])
    th, w = pos[body][:, 2], vel[body][:, 2]
    rx = np.cos(th) * local[0] - np.sin(th) * local[1]
    ry = np.sin(th) * local[0] + np.cos(th) * local[1]
    return {"x": pos[body][:, 0] + rx, "y": pos[body][:, 1] + ry, "vx": vel[body][:, 0] - w * ry,
            "vy": vel[body][:, 1] + w * rx}


def law_series(law: Law, t: Array, inputs: list[Array]) -> Array:
    """(n, k) values of the law at every step (mode = sign of the switching function at the state)."""
    if law.constant:
        return np.tile(np.asarray(law.values, dtype=float), (len(t), 1))
    return np.array([law(ti, [x[i] for x in inputs]) for i, ti in enumerate(t)], dtype=float)


def axis_series(j: Prismatic, subs: dict, pos: dict) -> Array:
    """The prismatic joint's axis, global, at every step (turning with a moving guide)."""
    axis = np.array([float(sp.sympify(c).xreplace(subs)) for c in j.axis])
    if j.guide[0] == GROUND:
        return np.tile(axis, (len(next(iter(pos.values()))), 1))
    th = pos[j.guide[0]][:, 2]
    return np.column_stack([np.cos(th) * axis[0] - np.sin(th) * axis[1],
                            np.sin(th) * axis[0] + np.cos(th) * axis[1]])
