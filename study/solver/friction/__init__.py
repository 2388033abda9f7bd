"""Coulomb friction in sliding joints with the normal force taken from the constraint multipliers.

One module per concept:

* :mod:`.laws`: the treatments (``exact``, ``regularized``, ``sign``) by name, each one class for both
  backends, the readings of a contact's constant resistance, and the default width of the regularized sign (their
  phases laws, the friction level and a pin's reaction norm live in ``study.laws.friction``);
* :mod:`.contact`: the coupled contact problem at one state (:class:`FrictionDynamics`), with its
  normal-force sign hypotheses and Painleve's paradox, around the shared solve of ``study.laws.contact``;
* :mod:`.switching`: event-located stick/slip switching of the exact treatment (:class:`StickSlipSwitching`).

The names below are re-exported, so ``from study.solver.friction import FrictionDynamics`` works.
"""

from study.solver.friction.contact import ContactSolution, FrictionDynamics, PainleveError, PinFrictionError
from study.solver.friction.laws import (DEFAULT_EPS, FRICTION_TREATMENTS, RESISTANCE_READINGS, ExactCoulomb,
                                        PlainSign, RegularizedCoulomb, make_friction)
from study.solver.friction.switching import FrictionLawError, StickSlipSwitching

__all__ = [
    "DEFAULT_EPS", "FRICTION_TREATMENTS", "RESISTANCE_READINGS", "ContactSolution",
    "ExactCoulomb", "FrictionDynamics", "FrictionLawError", "PainleveError", "PinFrictionError", "PlainSign",
    "RegularizedCoulomb",
    "StickSlipSwitching", "make_friction",
]
