"""Canned mechanisms, each built from its parameter set: ``load(name, variant) -> (ParameterSet, EOM)``."""

from __future__ import annotations

from types import ModuleType

import numpy as np

from study.mechanisms import quick_return, slider_crank
from study.model import EquationsOfMotion
from study.params import ParameterSet, load_parameters
from study.solver.initial import ConsistentState, InitialConditionError, consistent_initial_conditions

MECHANISMS: dict[str, ModuleType] = {"slider_crank": slider_crank, "quick_return": quick_return}


def module(name: str) -> ModuleType:
    if name not in MECHANISMS:
        raise ValueError(f"unknown mechanism {name!r}; valid choices: {', '.join(MECHANISMS)}")
    return MECHANISMS[name]


def load(name: str, variant: str = "seed") -> tuple[ParameterSet, EquationsOfMotion]:
    """Parameter set and compiled equations of a built-in mechanism variant."""
    mod = module(name)
    ps = load_parameters(name, variant)
    return ps, mod.equations(ps)


def initial_state(ps: ParameterSet, eom: EquationsOfMotion) -> ConsistentState:
    """Consistent q(0), qd(0) from the parameter file's specification, checked against its branch.

    Newton starts from the printed q(0) with the independent coordinates replaced by the
    specified values (``[initial_conditions.consistent]``).
    """
    ic = ps.initial
    guess = np.array(ic.printed_q, dtype=float)
    guess[list(ic.independent)] = ic.q_independent
    state = consistent_initial_conditions(eom, guess, ic.independent, ic.qd_independent)
    if not module(ps.mechanism).on_branch(ps, state.q):
        raise InitialConditionError(
            f"{ps.mechanism}: Newton from the printed q(0) converged to q = {state.q}, which is not on the "
            f"assembly branch '{ic.branch}'")
    return state
