"""Reproducible validation study of redundant-coordinate multibody methods against Exudyn."""

from study.errors import (EquationsError, NonFiniteError, ResultIntegrityError, RunBoundError, RunTooLargeError,
                          SimulationError, SingularConfigurationError)
from study.model import EquationsOfMotion, MechanismBuilder, SlidingContact
from study.params import ParameterError, ParameterSet, load_parameters
from study.results import SimulationResult
from study.simulate import simulate

__all__ = [
    "EquationsError",
    "EquationsOfMotion",
    "MechanismBuilder",
    "NonFiniteError",
    "ParameterError",
    "ParameterSet",
    "ResultIntegrityError",
    "RunBoundError",
    "RunTooLargeError",
    "SimulationError",
    "SimulationResult",
    "SingularConfigurationError",
    "SlidingContact",
    "load_parameters",
    "simulate",
]
