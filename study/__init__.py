"""Reproducible validation study of redundant-coordinate multibody methods against Exudyn."""

from study.errors import (EquationsError, NonFiniteError, ResultIntegrityError, RunBoundError, RunTooLargeError,
                          SimulationError, SingularConfigurationError)
from study.model import EquationsOfMotion, Mechanism, SlidingContact
from study.model.mechanism import consistent_state, equations_of
from study.model.joints import GROUND, Description, DescriptionError, Friction
from study.params import ParameterError, ParameterSet, load_parameters
from study.engines import Exudyn, InHouse, exudyn_run, run, spec_from_dict
from study.results import SimulationResult
from study.simulate import simulate, simulate_methods

__all__ = [
    "GROUND",
    "Description",
    "DescriptionError",
    "EquationsError",
    "EquationsOfMotion",
    "Exudyn",
    "Friction",
    "InHouse",
    "Mechanism",
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
    "exudyn_run",
    "joint_reactions",
    "load_mechanism",
    "load_parameters",
    "run",
    "simulate",
    "simulate_methods",
    "spec_from_dict",
    "validate",
    "ValidationSettings",
]

# Imported when first used: Exudyn (and the report's plotting) load only for what needs them.
_LAZY = {"joint_reactions": ("study.reactions", "joint_reactions"),
         "validate": ("study.validation", "validate"), "ValidationSettings": ("study.validation", "Settings"),
         "load_mechanism": ("study.user_mechanism", "load_mechanism")}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'study' has no attribute {name!r}")
