"""The compiled loop's arrays: allocated by NumPy in the frontend (study.fast.dynamics.work_arrays,
study.fast.loop.segment_arrays) in the types and shapes the structrefs' fields declare, and nothing allocated in
compiled code (each np.zeros/np.empty specialization is a compile of its own on a cold cache)."""

from __future__ import annotations

import numpy as np
from numba import typeof
from numba.core.registry import CPUDispatcher

from study.fast import dynamics, loop, project, steppers
from study.fast.dynamics import WORK_FIELDS, WORK_T, work_arrays
from study.fast.loop import STEP_T, segment_arrays
from study.fast.steppers import tableau
from study.fast.support import METHOD_IDS

# m = 3 coordinates, r = 2 constraints, nc = 1 contact, nw = 1 load work, npin = 1 pin; switched friction, 2 load modes
M, R, NC, NW, NPIN = 3, 2, 1, 1, 1
CI = np.array([0, 1, 1, 1, 1, 0, 0, 2, 0, 1, 1, NPIN, NW, NC, R, M], dtype=np.int64)


def test_work_arrays_have_the_workspace_fields_types_and_shapes():
    work = work_arrays(CI)
    assert typeof(work) == WORK_T
    shapes = {name: a.shape for (name, _), a in zip(WORK_FIELDS, work)}
    n, nt = M + R, NC + NPIN
    assert shapes["M"] == (3, 3) and shapes["J"] == (2, 3) and shapes["Jt"] == (nt, 3) and shapes["K"] == (n, n)
    assert shapes["U"] == (3, nt) and shapes["L"] == (2, nt) and shapes["A"] == (nt, nt)
    assert shapes["powers"] == (NW,) and shapes["lam"] == (R,) and shapes["x"] == (n,) and shapes["counters"] == (2,)
    assert shapes["pin"] == (NPIN * (5 + R + NPIN),)   # slip, tau, residual, |R|, step; multipliers; Jacobian
    assert all(not a.any() for a in work)


def test_segment_arrays_have_the_state_fields_types_and_shapes():
    n = 2 * M + NW + NC + NPIN
    for method, stage_rows, dense_rows in (("RK45", 7, 4), ("DOP853", 16, 7), ("RK4", 5, 4)):
        tab = tableau(method)
        steps = segment_arrays(METHOD_IDS[method], tab[:7], tab[7], tab[9], n, CI)
        assert typeof(steps) == STEP_T
        assert steps[0].shape == (stage_rows, n) and steps[1].shape == (dense_rows, n)
        assert steps[6].shape == steps[7].shape == (2 + 2 * (NC + NPIN),)   # load modes, then 2 per friction entry


def test_the_compiled_path_allocates_nothing_in_compiled_code():
    for module in (dynamics, loop, project, steppers):
        for name, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == module.__name__:
                names = set(value.py_func.__code__.co_names)
                assert not names & {"zeros", "empty", "ones", "full"}, f"{module.__name__}.{name} allocates"
