"""The constraint rows of the spatial joints, in the body coordinates (r, p) of :mod:`study.spatial.derive`.

With A_i = A(p_i) (:func:`study.spatial.rotations.rotation`) and a point s' of body i, its global position is
r_i + A_i s' (ground: the point's global coordinates, a constant):

* spherical: r_a + A_a s_a' - r_b - A_b s_b' = 0                       (3 rows, ``<name>_x``, ``_y``, ``_z``)
* revolute: the spherical rows and (A_a f)^T (A_b h_b) = (A_a g)^T (A_b h_b) = 0, f, g two unit vectors
  perpendicular to body a's axis h_a (so h_a stays parallel to h_b; Nikravesh 1988, sec. 11.3) (``_f``, ``_g``)
* fixed: the spherical rows and (A_a x)^T (A_b C y) = (A_a y)^T (A_b C z) = (A_a z)^T (A_b C x) = 0 with x, y, z the
  unit vectors and C the locked relative orientation: three rows that vanish at A_a = A_b C and are independent
  there (their Jacobian is the relative rotation's) (``_rx``, ``_ry``, ``_rz``)
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from study.spatial.description import SpatialDescription
from study.spatial.elements import GROUND, FixedJoint, Revolute
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

    def axis(self, body: str, axis) -> np.ndarray:
        """The body-frame components of a named axis (a ground axis: its global components)."""
        return np.array(axis if body == GROUND else self.d.bodies[body].axes[axis], dtype=float)


def perpendicular_pair(h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors f, g with (f, g, h) orthonormal, for a unit h."""
    helper = np.eye(3)[int(np.argmin(np.abs(h)))]
    f = np.cross(h, helper)
    f /= np.linalg.norm(f)
    return f, np.cross(h, f)


def joint_rows(d: SpatialDescription, frames: BodyFrames) -> tuple[list[sp.Expr], list[str]]:
    """Every joint's constraint rows and their names, in the description's order."""
    rows, names = [], []
    for j in d.joints:
        gap = frames.point(j.body_a, j.a) - frames.point(j.body_b, j.b)
        rows += list(gap)
        names += [f"{j.name}_{c}" for c in "xyz"]
        if isinstance(j, Revolute):
            h_b = frames.vector(j.body_b, frames.axis(j.body_b, j.axis_b))
            for label, v in zip("fg", perpendicular_pair(frames.axis(j.body_a, j.axis_a))):
                rows.append((frames.vector(j.body_a, v).T * h_b)[0])
                names.append(f"{j.name}_{label}")
        elif isinstance(j, FixedJoint):
            unit = np.eye(3)
            for label, (k, n) in zip(("rx", "ry", "rz"), ((0, 1), (1, 2), (2, 0))):
                rows.append((frames.vector(j.body_a, unit[k]).T * frames.vector(j.body_b, j.orientation @ unit[n]))[0])
                names.append(f"{j.name}_{label}")
    return rows, names
