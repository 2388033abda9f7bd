"""Reproducible validation study of redundant-coordinate multibody methods against Exudyn."""

from study.model import EquationsOfMotion, MechanismBuilder, SlidingContact
from study.params import ParameterError, ParameterSet, load_parameters

__all__ = [
    "EquationsOfMotion",
    "MechanismBuilder",
    "ParameterError",
    "ParameterSet",
    "SlidingContact",
    "load_parameters",
]
