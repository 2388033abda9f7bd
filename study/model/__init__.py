"""The model: a joint-level description with its parameters and initial state (:class:`Mechanism`), lowered to
coordinates, derived symbolically and compiled into :class:`EquationsOfMotion`.

The one public way to a mechanism is Description -> Mechanism (:mod:`study.model.mechanism`); the body-level
:class:`study.model.builder.MechanismBuilder` a description is lowered to is internal to the derivation.
"""

from study.model.builder import DescriptionError
from study.model.eom import EquationsOfMotion, FrictionalPin, SlidingContact
from study.model.mechanism import Mechanism

__all__ = ["DescriptionError", "EquationsOfMotion", "FrictionalPin", "Mechanism", "SlidingContact"]
