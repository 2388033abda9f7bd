"""Spatial mechanisms: rigid bodies in 3D with Euler parameters, their joints and loads, through the same solver.

* :mod:`~study.spatial.rotations`: E(p), G(p), A(p) of the Euler parameters;
* :mod:`~study.spatial.elements`, :mod:`~study.spatial.description`: the description (bodies, joints, loads), each
  value checked as it enters (:class:`SpatialDescriptionError`);
* :mod:`~study.spatial.joints`, :mod:`~study.spatial.derive`: the symbolic equations in r (3) and p (4) per body;
* :mod:`~study.spatial.equations`: those equations as the solver's EquationsOfMotion;
* :mod:`~study.spatial.friction`: Coulomb friction in revolute and prismatic joints as the planar pins' friction;
* :mod:`~study.spatial.initial`: the consistent initial state from angular velocities per body;
* :mod:`~study.spatial.mechanism`: :class:`SpatialMechanism`, a description with its start by body, what every engine
  takes (``study.run``, ``study.validate``), the one public way to run a spatial mechanism;
* :mod:`~study.spatial.bricard`: Bricard's mechanism (IFToMM A04), rows redundant at every configuration;
  :mod:`~study.spatial.bricard_peer`: the same loop as Exudyn's test model ``bricardMechanism.py`` builds it;
* :mod:`~study.spatial.heavy_top`, :mod:`~study.spatial.slider_crank`: the heavy top and Haug's spatial slider-crank;
* :mod:`~study.spatial.friction_carriage`: a carriage on an inclined guide carrying a wheel, friction in both joints;
* :mod:`~study.spatial.catalogue`: the study's spatial mechanisms by name (``SPATIAL``, read by
  :func:`study.mechanisms.named_mechanism`).
"""

from study.spatial.description import SpatialDescription
from study.spatial.elements import GROUND, SpatialDescriptionError
from study.spatial.equations import spatial_equations
from study.spatial.initial import initial_state
from study.spatial.mechanism import SpatialMechanism

__all__ = ["GROUND", "SpatialDescription", "SpatialDescriptionError", "SpatialMechanism", "initial_state",
           "spatial_equations"]
