"""Bricard's mechanism (IFToMM benchmark A04) as a spatial description, from reference/spatial/bricard.toml.

Five rods in a closed loop of six revolute joints, two of them to ground. Grübler's count gives 6 * 5 - 5 * 6 = 0
degrees of freedom; the joints' axes make it 1, so one of the 30 joint rows depends on the others at every
configuration: the description declares it (:meth:`~study.spatial.description.SpatialDescription.redundant_rows`),
the initial state checks rank(Phi_q) = r - 1, and only an acceleration solver defined for a rank-deficient Jacobian
runs it (``augmented_lagrangian``; the others stop at the start on the rank test of
:class:`study.solver.checks.SingularityMonitor`). The reactions are then not unique (the result's meta says so).

Rod k (1..5) runs from corner k-1 to corner k ([corners]); its points ``tail`` and ``head`` are its ends, its axes
``tail`` and ``head`` the joints' there ([axes]); every body frame is parallel to the global frame at t = 0.
"""

from __future__ import annotations

import numpy as np

from study.model.eom import EquationsOfMotion
from study.reference_data import tolerance, values
from study.spatial.description import SpatialDescription
from study.spatial.elements import GROUND
from study.spatial.equations import spatial_equations
from study.spatial.initial import initial_state
from study.spatial.mechanism import SpatialMechanism

TABLE = "spatial/bricard"
RODS = 5
REASON = ("Bricard's linkage: six revolute joints close a loop of five rods, 30 rows for 30 coordinates of the rods' "
          "motion (Grubler: 0 degrees of freedom), yet the axes' arrangement leaves 1")


def geometry() -> tuple[np.ndarray, np.ndarray]:
    """(corners (6, 3) [m], axes (6, 3)) of the joints at t = 0."""
    length = tolerance("length", TABLE)
    corners = length * np.array(values("corners", TABLE)).reshape(RODS + 1, 3)
    return corners, np.array(values("axes", TABLE)).reshape(RODS + 1, 3)


def rod_loop(d: SpatialDescription, corners: np.ndarray, axes: np.ndarray, mass: float, width: float,
             frames: list[np.ndarray] | None = None) -> None:
    """Bricard's loop into ``d``: rods ``rod1`` .. ``rod5`` of ``mass`` and a square cross-section of side ``width``,
    rod k from corner k-1 to corner k with its centre of mass at the middle, the revolute joints ``joint0`` ..
    ``joint5`` at the corners (6, 3) about ``axes`` (6, 3, global at t = 0), the first and the last to ground, and the
    redundant row. ``frames``: rod k's body frame at t = 0 (the matrix whose columns are its axes in global
    components), None for frames parallel to the global one."""
    for k in range(RODS):
        along, tail, head = corners[k + 1] - corners[k], axes[k], axes[k + 1]
        length = float(np.linalg.norm(along))
        if frames is not None:
            along, tail, head = frames[k].T @ along, frames[k].T @ tail, frames[k].T @ head
        u = along / length
        across = mass * (length ** 2 + width ** 2) / 12
        inertia = across * np.eye(3) + (mass * 2 * width ** 2 / 12 - across) * np.outer(u, u)
        d.body(f"rod{k + 1}", mass, inertia, points={"tail": tuple(-along / 2), "head": tuple(along / 2)},
               axes={"tail": tuple(tail), "head": tuple(head)})
    d.revolute("joint0", ("rod1", "tail", "tail"), (GROUND, tuple(corners[0]), tuple(axes[0])))
    for k in range(1, RODS):
        d.revolute(f"joint{k}", (f"rod{k + 1}", "tail", "tail"), (f"rod{k}", "head", "head"))
    d.revolute(f"joint{RODS}", (f"rod{RODS}", "head", "head"), (GROUND, tuple(corners[RODS]), tuple(axes[RODS])))
    d.redundant_rows(1, REASON)


def bricard() -> SpatialDescription:
    """The description of A04 (module docstring)."""
    corners, axes = geometry()
    d = SpatialDescription("bricard", label="Bricard's mechanism (IFToMM A04)")
    rod_loop(d, corners, axes, tolerance("mass", TABLE), tolerance("cross_section", TABLE))
    d.gravity(values("gravity", TABLE))
    return d


def bricard_start() -> tuple[SpatialDescription, EquationsOfMotion, np.ndarray, np.ndarray]:
    """The description, its equations and the consistent initial state: at rest, every rod at its place."""
    d = bricard()
    eom = spatial_equations(d)
    corners, _ = geometry()
    centres = {f"rod{k + 1}": (corners[k] + corners[k + 1]) / 2 for k in range(RODS)}
    q0, qd0 = initial_state(d, eom, centres)
    return d, eom, q0, qd0


def bricard_mechanism() -> SpatialMechanism:
    """A04 with its start: at rest, every rod at its place (what :func:`bricard_start` solves, for every engine)."""
    corners, _ = geometry()
    return SpatialMechanism(bricard(), positions={f"rod{k + 1}": tuple((corners[k] + corners[k + 1]) / 2)
                                                  for k in range(RODS)})
