"""The handlers of a description's bodies and joints: one function per element kind, adding it to the model.

* Every body: NodeRigidBody2D at its centre of mass with mass and centroidal inertia, gravity -g along y
  (LoadMassProportional). The node's reference configuration is the initial state (initial displacements 0); its
  initial velocities are the consistent ones (:func:`study.exudyn_models.kinematics.body_states`).
* ``revolute(J, a, b)``: RevoluteJoint2D between MarkerBodyRigid markers at a (marker 0) and b (marker 1); a ground
  point is a marker on the ground object.
* ``distance(J, a, b, L)``: DistanceConstraint of length L between the markers at a and b.
* ``prismatic(J, slider, guide, axis, normal)``: PrismaticJoint2D with marker 0 at the guide point,
  ``axisMarker0`` = the description's axis (guide frame), marker 1 at the slider point, ``normalMarker1`` = the
  normal expressed in the slider's frame at the initial configuration, ``constrainRotation=True``.
"""

from __future__ import annotations

import numpy as np

from study.exudyn_models.assembly import Assembly
from study.exudyn_models.kinematics import rotation
from study.model.joints import GROUND, Distance, Prismatic, Revolute


def add_bodies(a: Assembly) -> None:
    """Every body of the description at its initial state, under gravity."""
    d = a.d
    g = a.val(d.gravity_g) if d.gravity_g is not None else 0.0
    for b, body in d.bodies.items():
        a.model.body(b, a.val(body.mass), a.val(body.inertia), a.states[b], g)


def add_revolute(a: Assembly, j: Revolute) -> None:
    a.model.revolute(j.name, a.marker(*j.a), a.marker(*j.b))


def add_distance(a: Assembly, j: Distance) -> None:
    a.model.distance(j.name, a.marker(*j.a), a.marker(*j.b), a.val(j.length))


def add_prismatic(a: Assembly, j: Prismatic) -> None:
    """The joint, and its normal in the guide's body frame (``Built.normals``, read by the result mapping)."""
    axis = (a.val(j.axis[0]), a.val(j.axis[1]))
    n_guide = np.array([a.val(j.normal[0]), a.val(j.normal[1])])
    guide_angle = a.refs[j.guide[0]] if j.guide[0] != GROUND else 0.0
    slider_angle = a.refs[j.slider[0]] if j.slider[0] != GROUND else 0.0
    n_slider = rotation(slider_angle).T @ rotation(guide_angle) @ n_guide
    a.model.prismatic(j.name, a.marker(*j.guide), a.marker(*j.slider), axis0=axis, normal1=n_slider)
    a.built.normals[j.name] = (float(n_guide[0]), float(n_guide[1]))


#: joint class -> its handler
JOINTS = {Revolute: add_revolute, Distance: add_distance, Prismatic: add_prismatic}


def add_joint(a: Assembly, j) -> None:
    """The handler of the joint's kind."""
    for kind, handler in JOINTS.items():
        if isinstance(j, kind):
            return handler(a, j)
    raise TypeError(f"joint {j.name!r} of kind {type(j).__name__} has no Exudyn handler (kinds: "
                    f"{', '.join(k.__name__ for k in JOINTS)})")
