"""Reproducible validation study of redundant-coordinate multibody methods against Exudyn."""

from study.errors import (EquationsError, NonFiniteError, ResultIntegrityError, RunBoundError, RunTooLargeError,
                          SimulationError, SingularConfigurationError)
from study.mechanisms import consistent_state, equations_of
from study.model import EquationsOfMotion, MechanismBuilder, SlidingContact
from study.model.joints import GROUND, Description, DescriptionError, Friction
from study.params import ParameterError, ParameterSet, load_parameters
from study.results import SimulationResult
from study.simulate import simulate, simulate_methods

__all__ = [
    "GROUND",
    "Description",
    "DescriptionError",
    "EquationsError",
    "EquationsOfMotion",
    "Friction",
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
    "consistent_state",
    "equations_of",
    "load_parameters",
    "simulate",
    "simulate_methods",
]
