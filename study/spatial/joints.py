"""The constraint rows of the spatial joints, in the body coordinates (r, p) of :mod:`study.spatial.derive`.

With A_i = A(p_i) (:func:`study.spatial.rotations.rotation`) and a point s' of body i, its global position is
r_i + A_i s' (ground: the point's global coordinates, a constant); d = r_a + A_a s_a' - r_b - A_b s_b' is the gap
between the joint's two points. A joint with axes has a frame on each body (:func:`joint_frames`: R_a on body a,
R_b on body b, columns e_0, e_1, e_2; (f, g, h) is :func:`axis_frame` of a unit axis h), the frames Exudyn's markers
take (:mod:`study.exudyn_models.spatial`):

* spherical: d = 0                                                  (3 rows, ``<name>_x``, ``_y``, ``_z``)
* revolute: d = 0 and (A_a f_a)^T (A_b h_b) = (A_a g_a)^T (A_b h_b) = 0: body a's axis h_a stays parallel to
  h_b (Nikravesh 1988, sec. 11.3)                                   (``_x``, ``_y``, ``_z``, ``_f``, ``_g``)
* revolute with friction (``d.frictions``): d = 0 written in body b's joint frame, (A_b f_b)^T d = (A_b g_b)^T d =
  (A_b h_b)^T d = 0 (the same point set), so the first two multipliers are the transverse reaction R_t that scales
  the friction torque (:mod:`study.spatial.friction`)     (``_tx``, ``_ty``, ``_tz``, ``_f``, ``_g``)
* cylindrical: (A_b f_b)^T d = (A_b g_b)^T d = 0 (point a on body b's axis line) and the revolute's two parallel
  rows                                                              (``_tx``, ``_ty``, ``_f``, ``_g``)
* universal: d = 0 and (A_a h_a)^T (A_b h_b) = 0                      (``_x``, ``_y``, ``_z``, ``_h``)
* fixed: d = 0 and the lock (A_a R_a e_k)^T (A_b R_b e_n) = 0 for (k, n) = (0, 1), (1, 2), (2, 0) with R_a = I,
  R_b = C the locked relative orientation: three rows that vanish at A_a = A_b C and are independent there (their
  Jacobian is the relative rotation's)                               (``_x``, ``_y``, ``_z``, ``_rx``, ``_ry``, ``_rz``)
* prismatic: (A_b f_b)^T d = (A_b g_b)^T d = 0 and the lock with R_b = (f_b, g_b, h_b), R_a = C^T R_b (the frames
  coincide at A_a = A_b C)                                          (``_tx``, ``_ty``, ``_rx``, ``_ry``, ``_rz``)
* distance: |d| - L = 0                                              (``_length``)
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from study.spatial.description import SpatialDescription
from study.spatial.elements import GROUND, Cylindrical, Distance, FixedJoint, Prismatic, Revolute, Spherical, Universal
from study.spatial.rotations import rotation


class BodyFrames:
    """Each body's rotation A(p) and the global positions of its points, as sympy expressions of q."""

    def __init__(self, d: SpatialDescription, q: sp.Matrix):
        self.d = d
        self.position = {name: q[7 * i:7 * i + 3, 0] for i, name in enumerate(d.bodies)}
        self.rotation = {name: rotation(list(q[7 * i + 3:7 * i + 7, 0])) for i, name in enumerate(d.bodies)}

    def point(self, body: str, point) -> sp.Matrix:
        """The global position of a body's named point (a ground point: its coordinates)."""
        if body == GROUND:
            return sp.Matrix([sp.Float(v) for v in point])
        local = sp.Matrix([sp.Float(v) for v in self.d.bodies[body].points[point]])
        return self.position[body] + self.rotation[body] * local

    def vector(self, body: str, local) -> sp.Matrix:
        """A body-frame vector (a tuple of numbers) in the global frame (ground: as it is)."""
        v = sp.Matrix([sp.Float(x) for x in local])
        return v if body == GROUND else self.rotation[body] * v


def perpendicular_pair(h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors f, g with (f, g, h) orthonormal, for a unit h."""
    helper = np.eye(3)[int(np.argmin(np.abs(h)))]
    f = np.cross(h, helper)
    f /= np.linalg.norm(f)
    return f, np.cross(h, f)


def axis_frame(h: np.ndarray) -> np.ndarray:
    """The rotation matrix with columns (f, g, h) (:func:`perpendicular_pair`): the axis h is its z column."""
    return np.column_stack([*perpendicular_pair(h), h])


def body_axis(d: SpatialDescription, body: str, axis) -> np.ndarray:
    """The body-frame components of a named axis (a ground axis: its global components)."""
    return np.array(axis if body == GROUND else d.bodies[body].axes[axis], dtype=float)


def joint_frames(d: SpatialDescription, j) -> tuple[np.ndarray, np.ndarray] | None:
    """(R_a, R_b): the joint's frame on body a and on body b (body-frame columns), None for a joint without axes.

    Universal: R_b = (g_b, h_b, f_b), h_b its y column (Exudyn's universal locks its marker 0's y column against its
    marker 1's z column)."""
    if isinstance(j, (Spherical, Distance)):
        return None
    if isinstance(j, FixedJoint):
        return np.eye(3), np.asarray(j.orientation, dtype=float)
    frame_b = axis_frame(body_axis(d, j.body_b, j.axis_b))
    if isinstance(j, Prismatic):
        return np.asarray(j.orientation, dtype=float).T @ frame_b, frame_b
    frame_a = axis_frame(body_axis(d, j.body_a, j.axis_a))
    if isinstance(j, Universal):
        return frame_a, frame_b[:, [1, 2, 0]]
    return frame_a, frame_b


def _dot(u: sp.Matrix, v: sp.Matrix) -> sp.Expr:
    return (u.T * v)[0]


def gap(frames: BodyFrames, j) -> sp.Matrix:
    """d = r_a + A_a s_a' - r_b - A_b s_b', the gap between the joint's two points (global components)."""
    return frames.point(j.body_a, j.a) - frames.point(j.body_b, j.b)


def frame_vectors(d: SpatialDescription, frames: BodyFrames, j) -> tuple[list[sp.Matrix], list[sp.Matrix]]:
    """The columns of the joint's frames R_a, R_b (:func:`joint_frames`) in the global frame: (A_a R_a e_k, A_b R_b
    e_k) for k = 0, 1, 2 (a joint with axes)."""
    r_a, r_b = joint_frames(d, j)
    return ([frames.vector(j.body_a, r_a[:, k]) for k in range(3)],
            [frames.vector(j.body_b, r_b[:, k]) for k in range(3)])


def _rows(d: SpatialDescription, frames: BodyFrames, j) -> list[tuple[str, sp.Expr]]:
    """(suffix, row) of one joint (module docstring)."""
    gap_ = gap(frames, j)
    if isinstance(j, Distance):
        return [("length", sp.sqrt(_dot(gap_, gap_)) - j.length)]
    spherical = [(c, gap_[k]) for k, c in enumerate("xyz")]
    if isinstance(j, Spherical):
        return spherical
    a, b = frame_vectors(d, frames, j)
    across = [("tx", _dot(b[0], gap_)), ("ty", _dot(b[1], gap_))]
    if isinstance(j, Revolute) and j.name in d.frictions:
        spherical = across + [("tz", _dot(b[2], gap_))]
    parallel = [("f", _dot(a[0], b[2])), ("g", _dot(a[1], b[2]))]
    lock = [(f"r{c}", _dot(a[k], b[n])) for c, (k, n) in zip("xyz", ((0, 1), (1, 2), (2, 0)))]
    perpendicular = [("h", _dot(a[2], b[1]))]
    return {Revolute: spherical + parallel, Cylindrical: across + parallel, Universal: spherical + perpendicular,
            FixedJoint: spherical + lock, Prismatic: across + lock}[type(j)]


def joint_rows(d: SpatialDescription, frames: BodyFrames) -> tuple[list[sp.Expr], list[str]]:
    """Every joint's constraint rows and their names, in the description's order."""
    rows, names = [], []
    for j in d.joints:
        for suffix, row in _rows(d, frames, j):
            rows.append(row)
            names.append(f"{j.name}_{suffix}")
    return rows, names

