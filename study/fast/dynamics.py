"""The compiled right-hand side: stabilization bias, multiplier solve and the coupled friction solve.

Same equations as ``study.solver.dynamics.Dynamics`` with the ``multiplier`` acceleration solver and
``study.solver.friction.FrictionDynamics``::

    [[M, Phi_q^T], [Phi_q, 0]] [qdd; lambda] = [Q + sum_j Jt_j^T f_j; gamma + b(Phi, Phidot)]

with the contacts' tangential forces f found per normal-force sign hypothesis by superposition: the contact solve
is ``study.laws.contact`` (its one home, which the reference path calls too; a failure is a Painleve status).

Revolute joints with friction (pins) follow the sliding contacts in every per-contact array: the generated
``evaluate`` appends each pin's rate Jacobian P_p to Jt and its rate bias to bt, so v_t ends with the pins'
relative rates omega_p, and a stuck pin (exact treatment) is a stuck row of the contacts' solve (its multiplier is
the torque that keeps P_p qdd + rate_bias_p = 0). A sliding pin's torque tau_p = -(mu_k r |R_p|_delta + T0) s_p
enters as the generalized force P_p^T tau_p and is solved by Newton around the contacts' solve, with the
reference's start and iteration bound (``FrictionDynamics._solve_pins``) and the shared Newton iterate
(``study.laws.contact.pin_newton_step``: Jacobian, stopping rule).

The laws arrive as compiled functions of their classes, passed as first-class functions: the
stabilization's ``compiled_bias`` (``study.solver.stabilization``) and the friction treatment's
``compiled_phases`` (``study.laws.friction``: stick flags and slip factors of the contacts).
Options travel in two arrays, ``ci`` (int64) and ``cf`` (float64), whose layout is given by the
``CI_*`` / ``CF_*`` constants below and packed by ``study.fast.frontend``. State y = [q, qd, W_loads,
W_friction (only with friction)], as in the reference.
"""

from __future__ import annotations

import numpy as np
from numba import types
from numba.experimental import structref

from study.kernels.cache import internal, kernel
from study.kernels.linalg import lu_factor, lu_solve
from study.kernels.signatures import B1, BIAS_T, EVALUATE_T, I1, PHASES, PHASES_T, V1, V2, f8
from study.laws.contact import (CONVERGED, OK, PIN_MAX_ITERATIONS, PIN_NOT_CONVERGED, SCRATCH_ROWS, SINGULAR,
                                STEP_FAILED, active_entries, contact_forces, pin_newton_step)
from study.laws.friction import pin_norm

# --- option layout ---------------------------------------------------------------------------
CI_PROJECTS, CI_BIAS, CI_FRICTION, CI_SWITCHED, CI_PHASES = range(5)
CI_PROJ_MASS, CI_PROJ_MAXITER, CI_NLOADMODE, CI_CONTACT0 = range(5, 9)
CF_PROJ_TOL, CF_HEADER = 0, 1
# ci: CI_PROJECTS 1 if the stabilization projects after each step; CI_BIAS the offset of its bias parameters in cf;
# CI_FRICTION 1 with a friction treatment, CI_SWITCHED 1 if it is switched (stick/slip entries in the mode, located
# switches), CI_PHASES the offset of its parameters in cf; from CI_CONTACT0 the contacts' normal rows (nc), then the
# pins' two reaction rows each (2 np); ci ends with the dimensions (np, nw, nc, r, m): see dimensions()
# cf after the header: mu_kinetic (nc), mu_static (nc), resistance (nc), then the pins' block (pin_block): mu_static
# radius (np), mu_kinetic radius (np), torque T0 (np), delta, rtol; then the bias parameters, the friction parameters

# ws.pin, per pin (blocks of np): the slip factor s, the torque tau, the Newton residual F, |R|_delta (block PIN_NORM),
# the Newton step; then the multipliers per unit torque (np x r) and the Newton Jacobian (np x np), in one array.
PIN_SLIP, PIN_TAU, PIN_RESIDUAL, PIN_NORM, PIN_STEP, PIN_MATRICES = range(6)


@structref.register
class _WorkspaceType(types.StructRef):
    """The numba type of the workspace: a reference to its arrays, so every helper that receives it gets one pointer
    (a tuple of the arrays would be passed as its ~250 fields into and out of every call, which made most of the
    compiled code: study.kernels.linking)."""


#: the workspace's arrays, in the order of :func:`work_arrays` (the run's mode, p, lp, ci, cf follow them)
WORK_FIELDS = [
    ("q", V1), ("qd", V1), ("M", V2), ("Q", V1), ("phi", V1), ("J", V2), ("gamma", V1), ("Jt", V2), ("bt", V1),
    ("powers", V1), ("c", V1), ("phidot", V1), ("K", V2), ("piv", I1), ("x", V1), ("qdd", V1), ("lam", V1),
    ("U", V2), ("L", V2), ("A", V2), ("pivA", I1), ("active", I1), ("scratch", V2), ("normal", V1), ("f", V1),
    ("vt", V1), ("stick", B1), ("s", V1), ("pin", V1), ("at", V1), ("counters", I1)]
WORKSPACE = _WorkspaceType(WORK_FIELDS + [("mode", I1), ("p", V1), ("lp", V1), ("ci", I1), ("cf", V1)])
WORK_T = types.Tuple([t for _, t in WORK_FIELDS])   # the entry kernels' argument ``work``


def work_arrays(ci: np.ndarray) -> tuple:
    """Every array one evaluation needs (nc contacts and npin pins: nt rows of Jt), zeroed, in the order of
    ``WORK_FIELDS``: allocated by NumPy, so the compiled code has no allocation of its own to compile (np.zeros'
    four specializations were ~0.7 s CPU of a cold run). ``at``: the time of the last failing evaluation; counters:
    [evaluations, its status]."""
    m, r, nc, nw, npin = (int(v) for v in dimensions.py_func(ci))
    n, nt = m + r, nc + npin
    z = np.zeros
    return (z(m), z(m), z((m, m)), z(m), z(r), z((r, m)), z(r), z((nt, m)), z(nt), z(nw), z(r), z(r), z((n, n)),
            z(n, np.int64), z(n), z(m), z(r), z((m, nt)), z((r, nt)), z((nt, nt)), z(nt, np.int64), z(nt, np.int64),
            z((SCRATCH_ROWS, nt)), z(nt), z(nt), z(nt), z(nt, np.bool_), z(nt), z(npin * (PIN_MATRICES + r + npin)),
            z(1), z(2, np.int64))


@internal()
def workspace(work, mode, p, lp, ci, cf):
    """The workspace of one integration: the arrays ``work`` (:func:`work_arrays`) with the run's mode, parameters
    and options (read, never written: one pointer instead of five arrays in every call)."""
    ws = structref.new(WORKSPACE)
    (ws.q, ws.qd, ws.M, ws.Q, ws.phi, ws.J, ws.gamma, ws.Jt, ws.bt, ws.powers, ws.c, ws.phidot, ws.K, ws.piv, ws.x,
     ws.qdd, ws.lam, ws.U, ws.L, ws.A, ws.pivA, ws.active, ws.scratch, ws.normal, ws.f, ws.vt, ws.stick, ws.s, ws.pin,
     ws.at, ws.counters) = work
    ws.mode, ws.p, ws.lp, ws.ci, ws.cf = mode, p, lp, ci, cf
    return ws


@internal()
def dimensions(ci):
    """(m, r, nc, nw, np): coordinates, constraints, sliding contacts, load works, pins, stored at the end of ci."""
    k = ci.size
    return ci[k - 1], ci[k - 2], ci[k - 3], ci[k - 4], ci[k - 5]


@internal()
def pin_block(nc):
    """Offset in cf of the pins' numbers (mu_static radius, mu_kinetic radius, torque; delta, rtol)."""
    return CF_HEADER + 3 * nc


@internal()
def constraint_rhs(bias, ws):
    """ws.c = gamma + b(Phi, Phidot) of the stabilization method: its compiled counterpart ``bias``
    (``compiled_bias`` of its class in study.solver.stabilization), parameters at cf[ci[CI_BIAS]:]."""
    r, m = ws.J.shape
    for i in range(r):
        phidot = 0.0
        for j in range(m):
            phidot += ws.J[i, j] * ws.qd[j]
        ws.phidot[i] = phidot
    bias(ws.phi, ws.phidot, ws.cf, ws.ci[CI_BIAS], ws.c)
    for i in range(r):
        ws.c[i] = ws.gamma[i] + ws.c[i]


@kernel(PHASES)
def no_phases(mode, nlm, vt, cf, off, stick, s):
    """The ``phases`` argument of a run without friction (not called)."""


@internal()
def _friction(ws, m, r, nc):
    """The coupled normal-force / friction problem (``study.laws.contact.contact_forces``) on top of the solution
    without tangential forces in ws.qdd, ws.lam. The rows of Jt with a tangential force are the stuck ones and the
    sliding ones with s != 0; sliding rows are contacts (j < nc), a stuck row may be a pin's."""
    n_act = active_entries(ws.stick, ws.s, ws.active)
    for col in range(n_act):  # response to a unit tangential force at row active[col]
        j = ws.active[col]
        for i in range(m):
            ws.x[i] = ws.Jt[j, i]
        for i in range(r):
            ws.x[m + i] = 0.0
        lu_solve(ws.K, ws.piv, ws.x)
        for i in range(m):
            ws.U[i, col] = ws.x[i]
        for i in range(r):
            ws.L[i, col] = ws.x[m + i]
    ci, cf = ws.ci, ws.cf
    mu_k, resistance = cf[CF_HEADER:CF_HEADER + nc], cf[CF_HEADER + 2 * nc:CF_HEADER + 3 * nc]
    return contact_forces(ws.active, n_act, ws.stick, ws.s, ws.Jt, ws.bt, ws.qdd, ws.lam, ws.U, ws.L,
                          ci[CI_CONTACT0:CI_CONTACT0 + nc], mu_k, resistance, ws.A, ws.pivA, ws.scratch, ws.f,
                          ws.normal)


@internal()
def _pins(ws, m, r, nc, npin):
    """The pins' torques (FrictionDynamics._solve_pins): Newton (``study.laws.contact.pin_newton_step``) from
    tau = 0 (ws.qdd, ws.lam hold that solution), the contacts' solve repeated at every iterate. s = 0 for a stuck
    pin, whose torque is its stuck row's multiplier. Leaves f and normal (|R|) of the pins; PIN_NOT_CONVERGED after
    PIN_MAX_ITERATIONS, or if the Newton step is singular or not finite."""
    slip, tau = ws.pin[PIN_SLIP * npin:(PIN_SLIP + 1) * npin], ws.pin[PIN_TAU * npin:(PIN_TAU + 1) * npin]
    res, norm = ws.pin[PIN_RESIDUAL * npin:(PIN_RESIDUAL + 1) * npin], ws.pin[PIN_NORM * npin:(PIN_NORM + 1) * npin]
    step = ws.pin[PIN_STEP * npin:(PIN_STEP + 1) * npin]
    ci, cf = ws.ci, ws.cf
    o = PIN_MATRICES * npin
    Lp = ws.pin[o:o + npin * r].reshape((npin, r))
    jac = ws.pin[o + npin * r:o + npin * (r + npin)].reshape((npin, npin))
    for k in range(npin):   # a sliding pin's slip factor goes to the Newton loop, not to the contacts' solve
        slip[k] = ws.s[nc + k]
        ws.s[nc + k] = 0.0
    po = pin_block(nc)
    delta, rtol = cf[po + 3 * npin], cf[po + 3 * npin + 1]
    rows = ci[CI_CONTACT0 + nc:CI_CONTACT0 + nc + 2 * npin]
    for k in range(npin):   # multipliers per unit torque at pin k
        for i in range(m):
            ws.x[i] = ws.Jt[nc + k, i]
        for i in range(r):
            ws.x[m + i] = 0.0
        lu_solve(ws.K, ws.piv, ws.x)
        for i in range(r):
            Lp[k, i] = ws.x[m + i]
        tau[k] = 0.0
    for iteration in range(PIN_MAX_ITERATIONS):
        if iteration > 0:   # no tangential forces, the torques tau: [M, J^T; J, 0] x = [Q + P^T tau; c] (tau = 0: done)
            for i in range(m):
                v = ws.Q[i]
                for k in range(npin):
                    v += ws.Jt[nc + k, i] * tau[k]
                ws.x[i] = v
            for k in range(r):
                ws.x[m + k] = ws.c[k]
            lu_solve(ws.K, ws.piv, ws.x)
            for i in range(m):
                ws.qdd[i] = ws.x[i]
            for k in range(r):
                ws.lam[k] = ws.x[m + k]
        status = _friction(ws, m, r, nc)
        if status != OK:
            return status
        outcome = pin_newton_step(ws.lam, rows, Lp, tau, slip, cf[po + npin:po + 2 * npin],
                                  cf[po + 2 * npin:po + 3 * npin], delta, rtol, norm, res, step, jac, ws.pivA)
        if outcome == CONVERGED:
            for k in range(npin):
                ws.normal[nc + k] = pin_norm(ws.lam[rows[2 * k]], ws.lam[rows[2 * k + 1]], 0.0)   # |R|
                if not ws.stick[nc + k]:
                    ws.f[nc + k] = tau[k]
            return OK
        if outcome == STEP_FAILED:   # the contacts' solve is done with its pivots until the next iterate
            return PIN_NOT_CONVERGED
    return PIN_NOT_CONVERGED


@internal()
def accelerations(evaluate, bias, phases, t, ws):
    """qdd, lambda (and with friction f, v_t, N) at the state in ws.q, ws.qd; returns a status code."""
    evaluate(t, ws.q, ws.qd, ws.mode, ws.p, ws.lp, ws.M, ws.Q, ws.phi, ws.J, ws.gamma, ws.Jt, ws.bt, ws.powers)
    ws.counters[0] += 1
    m, r = ws.q.size, ws.phi.size
    constraint_rhs(bias, ws)
    K = ws.K
    for i in range(m):
        for j in range(m):
            K[i, j] = ws.M[i, j]
        for k in range(r):
            K[i, m + k] = ws.J[k, i]
            K[m + k, i] = ws.J[k, i]
    for k in range(r):
        for kk in range(r):
            K[m + k, m + kk] = 0.0
    if not lu_factor(K, ws.piv):
        return SINGULAR
    for i in range(m):
        ws.x[i] = ws.Q[i]
    for k in range(r):
        ws.x[m + k] = ws.c[k]
    lu_solve(K, ws.piv, ws.x)
    for i in range(m):
        ws.qdd[i] = ws.x[i]
    for k in range(r):
        ws.lam[k] = ws.x[m + k]
    if phases is None:   # the loop compiled for runs without friction (study.fast.frontend.entry): no friction code
        return OK
    ci = ws.ci
    if ci[CI_FRICTION] == 0:
        return OK
    nt = ws.Jt.shape[0]
    for j in range(nt):
        v = 0.0
        for i in range(m):
            v += ws.Jt[j, i] * ws.qd[i]
        ws.vt[j] = v
    phases(ws.mode, ci[CI_NLOADMODE], ws.vt, ws.cf, ci[CI_PHASES], ws.stick, ws.s)
    npin = dimensions(ci)[4]
    if npin > 0:
        return _pins(ws, m, r, nt - npin, npin)
    return _friction(ws, m, r, nt)


@internal()
def note_failure(ws, status, t):
    """Keep a failing evaluation's status and time (ws.counters[1], ws.at[0]; its q, qd stay in ws.q, ws.qd) for the
    loop's report."""
    ws.counters[1] = status
    ws.at[0] = t


@internal()
def rhs(evaluate, bias, phases, t, y, ws, dy):
    """dy = [qd, qdd, load powers, friction powers f_j v_t,j of the contacts, then the pins]; returns a status code."""
    m = ws.q.size
    for i in range(m):
        ws.q[i] = y[i]
        ws.qd[i] = y[m + i]
    status = accelerations(evaluate, bias, phases, t, ws)
    if status != OK:
        note_failure(ws, status, t)
    for i in range(m):
        dy[i] = ws.qd[i]
        dy[m + i] = ws.qdd[i]
    nw = ws.powers.size
    for k in range(nw):
        dy[2 * m + k] = ws.powers[k]
    if ws.ci[CI_FRICTION] == 1:
        for j in range(ws.Jt.shape[0]):
            dy[2 * m + nw + j] = ws.f[j] * ws.vt[j]
    return status


#: the entry kernels' declared signatures: each compiles (or loads) for it on first use (study.fast.frontend.entry)
ACCELERATIONS_ENTRY = types.int64(EVALUATE_T, BIAS_T, PHASES_T, f8, V1, V1, I1, V1, V1, I1, V1, V1, types.int64,
                                  WORK_T)
RHS_ENTRY = types.int64(EVALUATE_T, BIAS_T, PHASES_T, f8, V1, I1, V1, V1, I1, V1, V1, WORK_T)


@kernel()
def accelerations_entry(evaluate, bias, phases, t, q, qd, mode, p, lp, ci, cf, out, repeat, work):
    """``repeat`` acceleration evaluations at (t, q, qd); out = [qdd, lambda, N, f] (N and f: contacts, then pins:
    |R| and the torque); ``work``: :func:`work_arrays`. For tests and timing."""
    m, r, nc, nw, npin = dimensions(ci)
    ws = workspace(work, mode, p, lp, ci, cf)
    nt = nc + npin
    status = 0
    for _ in range(repeat):
        for i in range(m):
            ws.q[i] = q[i]
            ws.qd[i] = qd[i]
        status = accelerations(evaluate, bias, phases, t, ws)
    for i in range(m):
        out[i] = ws.qdd[i]
    for k in range(r):
        out[m + k] = ws.lam[k]
    if ci[CI_FRICTION] == 1:
        for j in range(nt):
            out[m + r + j] = ws.normal[j]
            out[m + r + nt + j] = ws.f[j]
    return status


@kernel()
def rhs_entry(evaluate, bias, phases, t, y, mode, p, lp, ci, cf, dy, work):
    """:func:`rhs` called from Python: dy = y' at (t, y), for scipy's integrators, ``work`` the zeroed arrays of
    :func:`work_arrays`; returns a status code."""
    return rhs(evaluate, bias, phases, t, y, workspace(work, mode, p, lp, ci, cf), dy)
