"""Exudyn's slider-crank test model (``sliderCrankFloatingTest``), floating-frame case: see
:mod:`study.mechanisms.exudyn_slider_crank`, whose description covers both cases."""

from study.mechanisms.exudyn_slider_crank import FRAME, TIME_SCALE, describe  # noqa: F401
from study.mechanisms.exudyn_slider_crank import PARAMETERS as MECHANISM

LABEL = "Exudyn's slider-crank test model (floating frame)"
PARAMETERS = MECHANISM + FRAME
