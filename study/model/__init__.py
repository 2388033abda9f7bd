"""Mechanism description -> symbolic derivation -> compiled numeric equations of motion."""

from study.model.builder import DescriptionError, MechanismBuilder
from study.model.eom import EquationsOfMotion, PinFriction, SlidingContact

__all__ = ["DescriptionError", "EquationsOfMotion", "MechanismBuilder", "PinFriction", "SlidingContact"]
