"""Reproducible validation study of redundant-coordinate multibody methods against Exudyn."""

from study.model import EquationsOfMotion, MechanismBuilder, SlidingContact
from study.params import ParameterError, ParameterSet, load_parameters
from study.results import SimulationResult
from study.simulate import simulate

__all__ = [
    "EquationsOfMotion",
    "MechanismBuilder",
    "ParameterError",
    "ParameterSet",
    "SimulationResult",
    "SlidingContact",
    "load_parameters",
    "simulate",
]
