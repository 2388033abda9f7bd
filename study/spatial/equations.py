"""A spatial description's symbolic equations as the solver's :class:`~study.model.eom.EquationsOfMotion`.

Each sympy matrix of :func:`study.spatial.derive.derive_spatial` becomes a numpy function with
:func:`sympy.lambdify` (common subexpressions eliminated), so the reference path (``study.simulate``) runs a spatial
mechanism as it runs any user's equations: the same stabilizations, integrators and acceleration solvers act on the
joint rows and on the Euler-parameter norm rows alike.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import sympy as sp

from study.model.eom import EquationsOfMotion
from study.spatial.derive import SpatialSymbolic, derive_spatial
from study.spatial.description import SpatialDescription


def numeric(arguments: tuple, expr: sp.Matrix, shape: tuple[int, ...]) -> Callable[..., np.ndarray]:
    """A numpy function of ``arguments`` (symbols, or matrices of symbols, each bound to one array) returning
    ``expr`` as a float array of ``shape`` (``()``: a scalar)."""
    flat = [list(a) if isinstance(a, sp.MatrixBase) else a for a in arguments]
    entries = list(expr) if isinstance(expr, sp.MatrixBase) else [expr]
    f = sp.lambdify(flat, entries, modules="numpy", cse=True)

    def call(*values):
        out = np.array(f(*values), dtype=float)
        return float(out[0]) if shape == () else out.reshape(shape)
    return call


def spatial_equations(d: SpatialDescription, symbolic: SpatialSymbolic | None = None) -> EquationsOfMotion:
    """The EquationsOfMotion of a spatial description (a planar one is refused by name)."""
    s = derive_spatial(d) if symbolic is None else symbolic
    q, qd, t = s.q, s.qd, s.t
    m, r = len(q), s.phi.shape[0]
    velocity_terms = numeric((q, qd), s.velocity_terms, (m,))
    potential_gradient = numeric((q,), sp.Matrix([s.potential]).jacobian(q).T, (m,))
    loads = {name: numeric((t, q, qd), g, (m,)) for name, g in s.loads.items()}

    def applied_forces(time, qv, qdv, mode=None):
        return {name: f(time, qv, qdv) for name, f in loads.items()}

    def forces(time, qv, qdv, mode=None):
        total = -velocity_terms(qv, qdv) - potential_gradient(qv)
        for g in applied_forces(time, qv, qdv).values():
            total += g
        return total

    return EquationsOfMotion(
        n_coordinates=m, n_constraints=r,
        mass=numeric((q,), s.mass, (m, m)), forces=forces,
        phi=numeric((q,), s.phi, (r,)), phi_q=numeric((q,), s.phi_q, (r, m)),
        gamma=numeric((q, qd), s.gamma, (r,)),
        name=d.name, coordinate_names=s.coordinate_names, constraint_names=s.constraint_names,
        potential_energy=numeric((q,), s.potential, ()), applied_forces=applied_forces,
        points={name: numeric((q,), x, (3,)) for name, x in s.points.items()}, redundant_rows=d.redundant,
    )
