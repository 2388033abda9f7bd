"""Error types of the library's well-defined failures, shared by the solver, the results and the CLI.

Two families:

- input errors (``ValueError`` subclasses): the user asked for something that cannot be done as
  asked (equations that are not what they claim, a state off the constraints, a run too large);
- run failures (:class:`SimulationError`, a ``RuntimeError``): a run started and could not go on
  (non-finite or complex values, a mass matrix no longer positive-definite, a user's callable that raised,
  a singular configuration, a bound reached). Each carries the time and the quantity, and its message
  says the likely cause.

The command line turns any of them into one line on stderr and a non-zero exit code.
"""

from __future__ import annotations

from typing import Any


class EquationsError(ValueError):
    """A user's EquationsOfMotion or initial state failed the checks made before a run.

    ``problems`` lists every failed check (one sentence each).
    """

    def __init__(self, message: str, problems: tuple[str, ...] = ()):
        super().__init__(message)
        self.problems = tuple(problems)


class RunTooLargeError(ValueError):
    """A run whose estimated cost exceeds its bounds, refused before it starts (the message has the estimate)."""


class UserFileError(ValueError):
    """A user's mechanism file (``describe(ps)`` in ``<name>.py``) could not give a mechanism: the message names the
    file, the function, the line and the cause; an exception the file raised is the ``__cause__``."""


class ResultIntegrityError(ValueError):
    """A saved result (or generated file, or table) does not match the checksum recorded with it."""


class SimulationError(RuntimeError):
    """A run failed. ``t`` is the time [s] and ``quantity`` what failed (e.g. 'forces', 'qdd', 'step')."""

    def __init__(self, message: str, t: float | None = None, quantity: str = "", **details: Any):
        super().__init__(message)
        self.t = t
        self.quantity = quantity
        self.details = details


class NonFiniteError(SimulationError):
    """A NaN or infinity in an evaluation or a saved sample."""


class UserFunctionError(SimulationError):
    """A user's equation callable raised, or returned a value the solver cannot use (wrong shape, not numbers),
    during a run. ``quantity`` names the callable ('forces', 'mass', ...); an exception it raised is the
    ``__cause__``. (Complex values are a :class:`NonFiniteError`.)"""


class SingularConfigurationError(SimulationError):
    """The constraint Jacobian (or the dependent part of it) is rank-deficient at the run's pose."""


class RunBoundError(SimulationError):
    """A run reached its evaluation bound or its smallest step."""
