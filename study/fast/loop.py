"""The compiled integration loop: adaptive step control, located switches, projection, sampling.

:func:`integrate_segment` advances from t0 until ``t_end`` or the first switch, exactly as one
restart of ``study.solver.integrate.integrate``:

1. after each accepted step the switching functions are checked; a sign change is located on the
   step's interpolant by the reference loop's law (``study.laws.events.crossing_finder``: a scan, then
   Brent's method), the samples before it are written, and the segment returns the event to the
   caller, which sets the new mode (``study.laws.modes.switch``) and starts the next segment (so the
   integrator restarts at the switch);
2. the post-step projection is applied (stabilization ``projection``);
3. the requested output times inside the step are sampled from the interpolant.

Only the samples are stored (``y_out``, preallocated by the caller): memory is bounded by the
requested output, not by the number of steps. Every array the segment works in is allocated by NumPy in the caller
(:func:`segment_arrays`, ``study.fast.dynamics.work_arrays``) and reached by the helpers through one structref, the
integration state (:func:`integration_state`), so no allocation is compiled and no call passes a list of arrays.
"""

from __future__ import annotations

import numpy as np
from numba import types
from numba.experimental import structref

from study.kernels.cache import internal, kernel
from study.fast.dynamics import (CF_HEADER, CI_NLOADMODE, CI_PROJECTS, CI_SWITCHED, PIN_NORM, WORK_T, WORKSPACE,
                                 accelerations, dimensions, note_failure, pin_block, rhs, workspace)
from study.fast.project import project
from study.kernels.signatures import BIAS_T, EVALUATE_T, I1, INDICATORS_T, KINEMATICS_T, PHASES_T, V1, V2, f8, i8
from study.fast.steppers import (DOP853_ID, MAX_FACTOR, MIN_FACTOR, RK4_ID, SAFETY, combine, dense_eval,
                                 dense_setup, error_norm, select_initial_step, stages)
from study.laws.friction import friction_level, switching_pair   # a stuck entry's limit, the entries' switching
from study.laws.events import crossing_finder

# segment outcomes (>= 0) and failures (< 0)
DONE, EVENT = 0, 1
FAIL_STEP, FAIL_RHS, FAIL_PROJECTION, FAIL_EVALUATIONS, FAIL_STALL, FAIL_NONFINITE, FAIL_LOCATE = -1, -2, -3, -4, -5, -6, -7
SAMPLE_ATOL = 1e-12  # np.isclose(t_out, t_hi, rtol=0, atol=1e-12 max(1, |t_hi|)) in the reference

I2 = types.Array(i8, 2, "C")
TABLEAU_T = types.Tuple((V2, V1, V1, V1, V1, V1, V2))
STEP_T = types.Tuple((V2, V2, V1, V1, V1, V1, V1, V1))   # segment_arrays
SEGMENT = types.Tuple((i8, f8, i8))(
    EVALUATE_T, BIAS_T, PHASES_T, INDICATORS_T, KINEMATICS_T, i8, TABLEAU_T, i8, i8, i8, f8, V1, f8, f8, f8, f8, I1, V1,
    V1, I1, V1, V1, V2, I2, I1, V1, V1, WORK_T, STEP_T)


def segment_signature(friction: bool, projects: bool):
    """The loop's signature for a run (chosen by study.fast.frontend.run): without friction ``phases`` is None, so the
    friction solve is not compiled into it (study.fast.dynamics.accelerations); without the post-step projection
    ``kinematics`` is None, so the projection and its LAPACK calls are not (study.fast.project.project)."""
    args = list(SEGMENT.args)
    if not friction:
        args[2] = types.none
    if not projects:
        args[4] = types.none
    return SEGMENT.return_type(*args)


@structref.register
class _StateType(types.StructRef):
    """The numba type of a segment's integration state (see :func:`integration_state`)."""


STATE = _StateType([
    ("ws", WORKSPACE), ("method", i8), ("n_stages", i8), ("n_rows", i8), ("rtol", f8), ("atol", f8),
    ("ta", V2), ("tb", V1), ("tc", V1), ("te", V1), ("te3", V1), ("te5", V1), ("tp", V2),
    ("K", V2), ("D", V2), ("y", V1), ("y_new", V1), ("f", V1), ("f_new", V1), ("tmp", V1), ("g_new", V1),
    ("g_tmp", V1), ("t_out", V1), ("y_out", V2), ("mode_out", I2), ("counters", I1), ("y_end", V1), ("bounds", V1)])


@internal()
def event_count(ci, nc, npin):
    """The run's switching functions: its loads', then, with switched friction, 2 per contact and per pin (nc, npin:
    study.fast.dynamics.dimensions; Python calls its ``py_func``)."""
    return ci[CI_NLOADMODE] + (2 * (nc + npin) if ci[CI_SWITCHED] == 1 else 0)


def segment_arrays(method: int, tab: tuple, n_stages: int, n_rows: int, n: int, ci: np.ndarray) -> tuple:
    """A segment's own arrays, zeroed, allocated by NumPy (see ``study.fast.dynamics.work_arrays``): the stages K (DOP853:
    its 16 extended stages), the interpolant's coefficients D, the step's y_new, f, f_new, a scratch state tmp, and
    the switching functions g_new (at the step's end) and g_tmp (where located)."""
    n_k = tab[0].shape[0] if method == DOP853_ID else n_stages + 1
    nc, npin = dimensions.py_func(ci)[2::2]
    n_g = max(int(event_count.py_func(ci, nc, npin)), 1)
    return (np.zeros((max(n_k, 4), n)), np.zeros((max(n_rows, 4), n)), np.zeros(n), np.zeros(n), np.zeros(n),
            np.zeros(n), np.zeros(n_g), np.zeros(n_g))


@internal()
def integration_state(ws, method, tab, n_stages, n_rows, rtol, atol, y0, steps, t_out, y_out, mode_out, counters,
                      y_end, bounds):
    """Everything a segment's helpers share, behind one pointer (each array argument costs a call ~7 LLVM arguments):
    the evaluation workspace ``ws``, the method's numbers and tableau (A, B, C, E, E3, E5, P or D: ``ta``..``tp``),
    the step's y (from y0), the arrays ``steps`` (:func:`segment_arrays`) and the caller's (integrate_segment)."""
    st = structref.new(STATE)
    st.ws, st.method, st.n_stages, st.n_rows, st.rtol, st.atol = ws, method, n_stages, n_rows, rtol, atol
    st.ta, st.tb, st.tc, st.te, st.te3, st.te5, st.tp = tab
    st.y = y0.copy()
    st.K, st.D, st.y_new, st.f, st.f_new, st.tmp, st.g_new, st.g_tmp = steps
    st.t_out, st.y_out, st.mode_out, st.counters, st.y_end, st.bounds = t_out, y_out, mode_out, counters, y_end, bounds
    return st


@internal()
def event_values(evaluate, bias, phases, indicators, t, y, ws, out):
    """Switching functions whose signs equal the mode while it holds (loads, then 2 per contact, then 2 per pin: the
    law ``study.laws.friction.switching_pair``)."""
    ci, cf, mode = ws.ci, ws.cf, ws.mode
    m, nlm = ws.q.size, ci[CI_NLOADMODE]
    for i in range(m):
        ws.q[i] = y[i]
        ws.qd[i] = y[m + i]
    if nlm > 0:
        indicators(t, ws.q, ws.qd, ws.p, ws.lp, out[:nlm])
    if phases is None or ci[CI_SWITCHED] == 0:   # None: the loop compiled for runs without friction, none switched
        return 0
    status = accelerations(evaluate, bias, phases, t, ws)
    if status != 0:
        note_failure(ws, status, t)
    npin = dimensions(ci)[4]
    nc = ws.Jt.shape[0] - npin
    off, po = CF_HEADER, pin_block(nc)
    for j in range(nc + npin):
        stuck, k = mode[nlm + 2 * j] > 0, j - nc
        level = 0.0   # the static limit, read only when stuck: a contact's R + mu_s |N|, a pin's T0 + mu_s r |R|_delta
        if stuck and j < nc:
            level = friction_level(cf[off + nc + j], ws.normal[j], cf[off + 2 * nc + j])
        elif stuck:
            level = friction_level(cf[po + k], ws.pin[PIN_NORM * npin + k], cf[po + 2 * npin + k])
        switching_pair(stuck, level, ws.f[j], float(mode[nlm + 2 * j + 1]), ws.vt[j], out, nlm + 2 * j)
    return status


@internal()
def _g(s, i, evaluate, bias, phases, indicators, t_old, h, st):
    """Switching function i at time s on the step's interpolant: the function of t that ``first_crossing`` locates."""
    dense_eval((s - t_old) / h, st, st.tmp)
    event_values(evaluate, bias, phases, indicators, s, st.tmp, st.ws, st.g_tmp)
    return st.g_tmp[i]


first_crossing = internal()(crossing_finder(_g))   # the law of study.laws.events for _g


@internal()
def _store(kinematics, y, st, m, r):
    """y (projected if the run projects) and the mode as the next sample."""
    counters, y_out, mode = st.counters, st.y_out, st.ws.mode
    k = counters[0]
    for i in range(y.size):
        y_out[k, i] = y[i]
    if st.ws.ci[CI_PROJECTS] == 1:
        yk = y.copy()
        changed, status = project(kinematics, yk, st.ws, m, r)
        if status != 0:
            return status
        for i in range(y.size):
            y_out[k, i] = yk[i]
    for i in range(mode.size):
        st.mode_out[k, i] = mode[i]
    counters[0] = k + 1
    return 0


@internal()
def _rhs_failed(st):
    """FAIL_RHS at the time of the failing evaluation; its q, qd to y_end[:2m] and its status to counters[6]."""
    ws, y_end = st.ws, st.y_end
    m = ws.q.size
    for i in range(m):
        y_end[i] = ws.q[i]
        y_end[m + i] = ws.qd[i]
    st.counters[6] = ws.counters[1]
    return FAIL_RHS, ws.at[0], -1


@internal()
def _due(t_out, k, t_hi):
    return k < t_out.size and (t_out[k] < t_hi or abs(t_out[k] - t_hi) <= SAMPLE_ATOL * max(1.0, abs(t_hi)))


@internal()
def _failed(outcome, t, st):
    """The segment's result for a failure ``outcome`` at t (FAIL_RHS: at the failing evaluation, see _rhs_failed)."""
    if outcome == FAIL_RHS:
        return _rhs_failed(st)
    return outcome, t, -1


@internal()
def _start(evaluate, bias, phases, kinematics, order, t, t_end, first_step, st):
    """f at the start, the samples due there (the run's first segment only) and the first step size:
    -> (0 or FAIL_RHS, FAIL_PROJECTION; h_abs)."""
    ws, counters, y = st.ws, st.counters, st.y
    m, r = ws.q.size, dimensions(ws.ci)[1]
    if rhs(evaluate, bias, phases, t, y, ws, st.f) != 0:
        return FAIL_RHS, 0.0
    if counters[4] == 1:
        counters[4] = 0
        while _due(st.t_out, counters[0], t):
            if _store(kinematics, y, st, m, r) != 0:
                return FAIL_PROJECTION, 0.0
    if st.method == RK4_ID or first_step > 0:
        return 0, first_step
    h_abs, status = select_initial_step(evaluate, bias, phases, t, t_end, order, st)
    return (FAIL_RHS if status != 0 else 0), h_abs


@internal()
def _rk4_step(evaluate, bias, phases, t, h_abs, t_end, st):
    """One RK4 step, h = min(h_abs, t_end - t), into st.y_new, st.f_new: -> (0 or FAIL_RHS, t_new, h)."""
    h = min(h_abs, t_end - t)
    K, f = st.K, st.f
    for i in range(f.size):
        K[0, i] = f[i]
    if stages(evaluate, bias, phases, t, h, 1, 4, st) != 0:
        return FAIL_RHS, t, h
    combine(4, h, st)
    t_new = t + h
    if rhs(evaluate, bias, phases, t_new, st.y_new, st.ws, st.f_new) != 0:
        return FAIL_RHS, t_new, h
    return 0, t_new, h


@internal()
def _adaptive_step(evaluate, bias, phases, exponent, t, h_abs, t_end, st):
    """One accepted step under scipy's error control into st.y_new, st.f_new: -> (0, t_new, h, the next h_abs), or
    (FAIL_STEP, FAIL_EVALUATIONS, FAIL_RHS or FAIL_NONFINITE; t; ...)."""
    ws, counters, bounds, K, f, f_new, n_stages = st.ws, st.counters, st.bounds, st.K, st.f, st.f_new, st.n_stages
    min_step = 10 * max(abs(t) * 2.220446049250313e-16, 5e-324)
    rejected = False
    while True:
        if not h_abs >= min_step:  # also a NaN step (a non-finite error estimate)
            return FAIL_STEP, t, 0.0, h_abs
        if counters[2] + ws.counters[0] >= bounds[0]:  # rejected steps count too
            counters[2] += ws.counters[0]
            return FAIL_EVALUATIONS, t, 0.0, h_abs
        t_new = min(t + h_abs, t_end)
        h = t_new - t
        h_abs = abs(h)
        for i in range(f.size):
            K[0, i] = f[i]
        if stages(evaluate, bias, phases, t, h, 1, n_stages, st) != 0:
            return FAIL_RHS, t, h, h_abs
        combine(n_stages, h, st)
        if rhs(evaluate, bias, phases, t_new, st.y_new, ws, f_new) != 0:
            return FAIL_RHS, t, h, h_abs
        for i in range(f_new.size):
            K[n_stages, i] = f_new[i]
        err = error_norm(h, st)
        if not np.isfinite(err):  # a non-finite stage: shrinking the step would only hide it
            return FAIL_NONFINITE, t, h, h_abs
        if err < 1:
            factor = MAX_FACTOR if err == 0 else min(MAX_FACTOR, SAFETY * err ** exponent)
            if rejected:
                factor = min(1.0, factor)
            return 0, t_new, h, h_abs * factor
        h_abs *= max(MIN_FACTOR, SAFETY * err ** exponent)
        rejected = True


@internal()
def _bounded(t_new, t_end, h, st):
    """Count an accepted step and check the run's bounds after it: -> 0, FAIL_NONFINITE, FAIL_EVALUATIONS or
    FAIL_STALL (see integrate_segment)."""
    counters, bounds, f_new, ws = st.counters, st.bounds, st.f_new, st.ws
    counters[1] += 1
    for i in range(f_new.size):
        if not np.isfinite(f_new[i]):  # RK4 (no error estimate) or an infinite error estimate
            return FAIL_NONFINITE
    if counters[2] + ws.counters[0] >= bounds[0]:
        counters[2] += ws.counters[0]
        return FAIL_EVALUATIONS
    if st.method != RK4_ID and t_new < t_end:
        counters[5] = counters[5] + 1 if h < bounds[1] else 0
        if counters[5] >= bounds[2]:
            counters[2] += ws.counters[0]
            return FAIL_STALL
    return 0


@internal()
def _earliest_switch(evaluate, bias, phases, indicators, t_old, h, t_new, st):
    """The earliest crossing in the step of a switching function that ended it off its mode's side, located on the
    step's interpolant (set up into st.D on the first one): -> (0, t_e, i_e or -1 for none, dense ready), or
    FAIL_RHS, or FAIL_LOCATE with the i whose crossing cannot be located (``study.laws.events.crossing_finder``)."""
    g_new, mode = st.g_new, st.ws.mode
    if event_values(evaluate, bias, phases, indicators, t_new, st.y_new, st.ws, g_new) != 0:
        return FAIL_RHS, t_new, -1, False
    t_e, i_e, dense_ready = np.inf, -1, False
    for i in range(g_new.size):
        if g_new[i] * mode[i] < 0:
            if not dense_ready:
                dense_setup(evaluate, bias, phases, t_old, h, st)
                dense_ready = True
            root = first_crossing(mode[i], t_old, t_new, i, evaluate, bias, phases, indicators, t_old, h, st)
            if np.isnan(root):
                return FAIL_LOCATE, t_old, i, dense_ready
            if root < t_e:
                t_e, i_e = root, i
    return 0, t_e, i_e, dense_ready


@internal()
def _sample_step(evaluate, bias, phases, kinematics, t_old, h, dense_ready, t_hi, st):
    """The output times due up to t_hi from the step's interpolant (set up into st.D if not ready): -> 0 or
    FAIL_PROJECTION."""
    ws, counters, t_out, tmp = st.ws, st.counters, st.t_out, st.tmp
    m, r = ws.q.size, dimensions(ws.ci)[1]
    while _due(t_out, counters[0], t_hi):
        if not dense_ready:
            dense_setup(evaluate, bias, phases, t_old, h, st)
            dense_ready = True
        tk = t_out[counters[0]]
        dense_eval((tk - t_old) / h, st, tmp)
        if _store(kinematics, tmp, st, m, r) != 0:
            return FAIL_PROJECTION
    return 0


@internal()
def _project_step(evaluate, bias, phases, kinematics, t_new, st):
    """The post-step projection of st.y_new (st.f_new evaluated again if it moved): -> 0, FAIL_PROJECTION or
    FAIL_RHS."""
    ws = st.ws
    changed, status = project(kinematics, st.y_new, ws, ws.q.size, dimensions(ws.ci)[1])
    if status != 0:
        return FAIL_PROJECTION
    if changed:
        st.counters[3] += 1
        if rhs(evaluate, bias, phases, t_new, st.y_new, ws, st.f_new) != 0:
            return FAIL_RHS
    return 0


@internal()
def _finish(kinematics, t, st):
    """The end of the run reached: the output times due at t (the last equals t_end), the state to y_end."""
    ws, counters, y, y_end = st.ws, st.counters, st.y, st.y_end
    m, r = ws.q.size, dimensions(ws.ci)[1]
    while counters[0] < st.t_out.size and _due(st.t_out, counters[0], t + 1e-300):
        if _store(kinematics, y, st, m, r) != 0:
            return FAIL_PROJECTION, t, -1
    for i in range(y.size):
        y_end[i] = y[i]
    counters[2] += ws.counters[0]
    return DONE, t, -1


@kernel()   # compiled (or loaded) for SEGMENT on first use (study.fast.frontend.entry)
def integrate_segment(evaluate, bias, phases, indicators, kinematics, method, tab, n_stages, order, n_rows, t0, y0,
                      t_end, first_step, rtol, atol, mode, p, lp, ci, t_out, cf, y_out, mode_out, counters, y_end, bounds,
                      work, steps):
    """Integrate from (t0, y0) to t_end or the first switch; see the module docstring.

    counters (int64): [k_out, steps, nfev, projections, take the t0 sample (1/0), accepted steps in a row
    below min_step, status of a failing evaluation]; updated in place. bounds: [max_evaluations, min_step,
    min_step_run], the reference loop's run bounds (``study.solver.integrate.integrate``): the run fails with
    FAIL_EVALUATIONS once the evaluations of the whole run reach max_evaluations, and with FAIL_STALL after
    min_step_run accepted adaptive steps in a row shorter than min_step.
    Returns (outcome, t reached, index of the switching function that crossed or -1); the state
    reached is written to y_end (FAIL_RHS: the time and the q, qd of the failing evaluation). work and steps: the
    zeroed arrays of ``study.fast.dynamics.work_arrays`` and :func:`segment_arrays`, fresh for each segment.
    """
    ws = workspace(work, mode, p, lp, ci, cf)
    m, r, nc, nw, npin = dimensions(ci)
    n_events = event_count(ci, nc, npin)
    st = integration_state(ws, method, tab, n_stages, n_rows, rtol, atol, y0, steps, t_out, y_out, mode_out,
                           counters, y_end, bounds)
    y, y_new, f, f_new = st.y, st.y_new, st.f, st.f_new
    n = y.size
    t = t0
    status, h_abs = _start(evaluate, bias, phases, kinematics, order, t, t_end, first_step, st)
    if status != 0:
        return _failed(status, t, st)
    exponent = -1.0 / (order + 1)
    while t < t_end:
        t_old = t
        if method == RK4_ID:   # --- one accepted step ---------------------------------------------------------
            status, t_new, h = _rk4_step(evaluate, bias, phases, t, h_abs, t_end, st)
        else:
            status, t_new, h, h_abs = _adaptive_step(evaluate, bias, phases, exponent, t, h_abs, t_end, st)
        if status == 0:
            status = _bounded(t_new, t_end, h, st)
        if status != 0:
            return _failed(status, t_new, st)
        dense_ready = False
        if n_events > 0:   # --- 1. switches -------------------------------------------------------------------
            status, t_e, i_e, dense_ready = _earliest_switch(evaluate, bias, phases, indicators, t_old, h, t_new, st)
            if status == FAIL_LOCATE:
                counters[2] += ws.counters[0]
                return FAIL_LOCATE, t_old, i_e
            if status != 0:
                return _failed(status, t_new, st)
            if i_e >= 0:
                dense_eval((t_e - t_old) / h, st, y_end)
                if _sample_step(evaluate, bias, phases, kinematics, t_old, h, True, t_e, st) != 0:
                    return FAIL_PROJECTION, t, -1
                counters[2] += ws.counters[0]
                return EVENT, t_e, i_e
        # --- 3. samples (before the projection, as in the reference), 2. projection ------------------------------
        if _sample_step(evaluate, bias, phases, kinematics, t_old, h, dense_ready, t_new, st) != 0:
            return FAIL_PROJECTION, t, -1
        if ci[CI_PROJECTS] == 1:
            status = _project_step(evaluate, bias, phases, kinematics, t_new, st)
            if status != 0:
                return _failed(status, t_new, st)
        t = t_new
        for i in range(n):   # elementwise: a slice assignment compiles numba's shape check and its message
            y[i], f[i] = y_new[i], f_new[i]
    return _finish(kinematics, t, st)
