"""Exudyn's test model ``TestModels/bricardMechanism.py`` as a spatial description (a peer model; data in
reference/spatial/exudyn_bricard.toml, transcribed from the file with its line numbers).

The file builds IFToMM A04's loop (:mod:`study.spatial.bricard`) from its own numbers: cuboid rods of density 100
kg/m^3 and L x r x r, each body frame turned by the file's rotation matrix so that its x axis runs along the rod, the
body's reference point (Exudyn's node) at the rod's first joint and the centre of mass at (L/2, 0, 0) from it. Here
the same loop is built by :func:`study.spatial.bricard.rod_loop` in those body frames, each rod's centre of mass
placed where the file puts it and its Euler parameters those of the file's rotation, at rest. The quantity the file
publishes is read from a run by :mod:`study.studies.peer_models`.
"""

from __future__ import annotations

import numpy as np

from study.reference_data import tolerance, values
from study.spatial.bricard import RODS, rod_loop
from study.spatial.description import SpatialDescription
from study.spatial.mechanism import SpatialMechanism
from study.spatial.rotations import rotation

TABLE = "spatial/exudyn_bricard"
NODE_POINT = "tail"   # the rods' point at Exudyn's node (the body's reference point): its first joint


def euler_parameters() -> list[np.ndarray]:
    """Every rod's Euler parameters at t = 0: (cos a/2, sin a/2 n) of the file's rotation by a about n."""
    axes = np.array(values("frame_axes", TABLE)).reshape(RODS, 3)
    angles = np.pi * np.array(values("frame_angles", TABLE))
    return [np.array([np.cos(a / 2), *(np.sin(a / 2) * n)]) for n, a in zip(axes, angles)]


def frames() -> list[np.ndarray]:
    """Every rod's body frame at t = 0: A(p) of :func:`euler_parameters` (body components -> global)."""
    return [np.array(rotation(list(p)).tolist(), dtype=float) for p in euler_parameters()]


def joints() -> tuple[np.ndarray, np.ndarray]:
    """(positions (6, 3) [m], axes (6, 3), global) of the joints: listP and listRotAxes."""
    length = tolerance("length", TABLE)
    return (length * np.array(values("positions", TABLE)).reshape(RODS + 1, 3),
            np.array(values("axes", TABLE)).reshape(RODS + 1, 3))


def exudyn_bricard() -> SpatialDescription:
    """The test model's mechanism (module docstring): its loop in its body frames, a rod's mass density L r^2."""
    corners, axes = joints()
    length, width = tolerance("length", TABLE), tolerance("cross_section", TABLE)
    d = SpatialDescription("exudyn_bricard", label="Bricard's mechanism (Exudyn's TestModels/bricardMechanism.py)")
    rod_loop(d, corners, axes, tolerance("density", TABLE) * length * width ** 2, width, frames())
    d.gravity(values("gravity", TABLE))
    return d


def centres() -> dict[str, np.ndarray]:
    """Every rod's centre of mass at t = 0: its reference point (listP) plus its frame times the file's offset."""
    corners, _ = joints()
    offset = tolerance("length", TABLE) * np.array(values("centre_of_mass", TABLE))
    return {f"rod{k + 1}": corners[k] + frame @ offset for k, frame in enumerate(frames())}


def exudyn_bricard_mechanism() -> SpatialMechanism:
    """The test model with its start: at rest, every rod at its place, turned as the file turns it."""
    return SpatialMechanism(exudyn_bricard(), positions={name: tuple(c) for name, c in centres().items()},
                            orientations={f"rod{k + 1}": tuple(p) for k, p in enumerate(euler_parameters())})
