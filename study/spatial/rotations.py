"""Euler parameters p = (e0, e1, e2, e3) and the matrices of their kinematics (Nikravesh, *Computer-Aided Analysis of
Mechanical Systems*, 1988, sec. 6.3; Haug, *Computer-Aided Kinematics and Dynamics of Mechanical Systems*, 1989,
sec. 6.3), as sympy matrices of whatever entries ``p`` holds (symbols or numbers)::

    E(p) = [-e  e~ + e0 I],   G(p) = [-e  -e~ + e0 I]        (3 x 4, e = (e1, e2, e3), e~ its skew matrix)
    A(p) = E G^T                                              the rotation matrix, body frame -> global
    omega = 2 E p_dot   (global frame),   omega' = 2 G p_dot   (body frame)
    p_dot = 1/2 E^T omega = 1/2 G^T omega'                    (for p^T p = 1 and p^T p_dot = 0)

E and G are linear in p, G(a) a = 0 and G(a) b = -G(b) a (so omega' = -2 G(p_dot) p); A is homogeneous quadratic in p
and a rotation when p^T p = 1.
"""

from __future__ import annotations

from typing import Sequence

import sympy as sp


def skew(v: Sequence) -> sp.Matrix:
    """The matrix v~ with v~ w = v x w."""
    return sp.Matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def _split(p: Sequence) -> tuple[sp.Expr, sp.Matrix]:
    if len(p) != 4:
        raise ValueError(f"Euler parameters need 4 entries, got {len(p)}: {list(p)}")
    return p[0], sp.Matrix(p[1:])


def e_matrix(p: Sequence) -> sp.Matrix:
    """E(p) (3 x 4): omega = 2 E p_dot, the angular velocity in the global frame."""
    e0, e = _split(p)
    return sp.Matrix.hstack(-e, skew(e) + e0 * sp.eye(3))


def g_matrix(p: Sequence) -> sp.Matrix:
    """G(p) (3 x 4): omega' = 2 G p_dot, the angular velocity in the body frame."""
    e0, e = _split(p)
    return sp.Matrix.hstack(-e, -skew(e) + e0 * sp.eye(3))


def rotation(p: Sequence) -> sp.Matrix:
    """A(p) = E G^T (3 x 3): global = A body."""
    return e_matrix(p) * g_matrix(p).T
