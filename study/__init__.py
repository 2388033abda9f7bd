"""Reproducible validation study of redundant-coordinate multibody methods against Exudyn.

The public way in: a :class:`Description` (bodies, joints, loads) and its parameters make a :class:`Mechanism`
(``study.model``; a spatial description makes a ``study.spatial.SpatialMechanism``; the study's own mechanisms come
from the registries ``study.mechanisms.CATALOGUE`` and ``study.spatial.catalogue.SPATIAL`` through one lookup,
``study.mechanisms.named_mechanism``); a run specification says how to run it, :class:`InHouse` (stabilization method, integrator, friction treatment, backend)
or :class:`Exudyn` (solver, step); ``run(mechanism, spec, t_end)`` returns a :class:`SimulationResult` for every
engine. ``simulate`` and ``exudyn_run`` are the same runs by keyword arguments.

Architecture
------------
The layers, bottom to top, are ``study.imports.LAYERS`` (a test refuses any import that goes up them):
base modules (errors, data locations, integrity, results) < ``kernels`` (numba machinery) < ``model`` (description,
Mechanism, symbolic equations, the one code generator ``model.codegen``, the consistent initial state;
``mechanisms``; ``spatial``) < ``laws`` < ``solver`` (the reference path: scipy integrators, readable classes) <
``fast`` (the compiled path: the compiled loop and its frontend) < ``engines``, ``exudyn_models``, ``simulate`` <
``pipeline`` < studies, report, bench, validation < ``cli``.

Each numerical law has one home in ``study.laws``, compiled with numba; the compiled loop calls it natively, the
reference loop calls the same compiled function (or, where a Python callable is passed in, its source):

=====================================================  ==========================================================
law                                                    home
=====================================================  ==========================================================
stabilization bias b(Phi, Phidot): none, Baumgarte,    ``study.laws.stabilization``
sliding mode (and each one's parameter layout)
post-step projection (correction, position and         ``study.laws.projection``
velocity iterations)
friction level, a pin's reaction norm, the friction    ``study.laws.friction``
treatments' phases (stick flags, slip factors), a
friction entry's switching functions (stuck: margin
to the static limit; sliding: -direction v_t;
then the direction)
contact and pin solve (normal-force sign hypotheses,   ``study.laws.contact``
consistency rule, Painleve cases, the pins' Newton
step)
event location (scan, then Brent)                      ``study.laws.events``
mode switch (mode at t0, after a located crossing)     ``study.laws.modes``
the sgn approximations (sign, sat, tanh, arctan, sqrt) ``study.kernels.signs`` (also the Exudyn guards' tanh)
code generation (sympy -> CSE -> reference and numba   ``study.model.codegen``
modules)
=====================================================  ==========================================================
"""

import os as _os

# numba's optimization level for the compiled path (read once, when numba is first imported): LLVM -O1 compiles the
# loop and the generated equations about 15 % faster than numba's default -O3 (a cold first quick-return run 11.0 ->
# 9.6 s CPU) and evaluates as fast (0.40 against 0.43 us per quick-return evaluation, the benchmark's pace). Without
# fast-math flags no optimization level changes a floating-point result: a fresh clone's `make reproduce` regenerates
# every table identical to the snapshot made at -O3. A NUMBA_OPT the user sets wins.
_os.environ.setdefault("NUMBA_OPT", "1")

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
