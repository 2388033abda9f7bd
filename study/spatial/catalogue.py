"""The study's spatial mechanisms by name, the registry :func:`study.mechanisms.named_mechanism` consults beside the
planar catalogue (one lookup): name -> a function making its :class:`~study.spatial.mechanism.SpatialMechanism`
(description and start; their data in reference/spatial/<name>.toml where it has one)."""

from __future__ import annotations

from types import MappingProxyType
from typing import Callable, Mapping

from study.spatial.bricard import bricard_mechanism
from study.spatial.bricard_peer import exudyn_bricard_mechanism
from study.spatial.friction_carriage import friction_carriage
from study.spatial.heavy_top import heavy_top_mechanism
from study.spatial.mechanism import SpatialMechanism
from study.spatial.slider_crank import spatial_slider_crank

#: name -> its mechanism's maker (the name is the description's)
SPATIAL: Mapping[str, Callable[[], SpatialMechanism]] = MappingProxyType({
    "bricard": bricard_mechanism, "exudyn_bricard": exudyn_bricard_mechanism, "heavy_top": heavy_top_mechanism,
    "spatial_slider_crank": spatial_slider_crank, "friction_carriage": friction_carriage})
