"""The compiled right-hand side: stabilization bias, multiplier solve and the coupled friction solve.

Same equations as ``study.solver.dynamics.Dynamics`` with the ``multiplier`` acceleration solver and
``study.solver.friction.FrictionDynamics``::

    [[M, Phi_q^T], [Phi_q, 0]] [qdd; lambda] = [Q + sum_j Jt_j^T f_j; gamma + b(Phi, Phidot)]

with the contacts' tangential forces f found per normal-force sign hypothesis by superposition
(see the reference module's docstring; the hypotheses are visited in the same order and the same
consistency rule picks exactly one, else a Painleve status is returned).

Revolute joints with friction (pins) follow the sliding contacts in every per-contact array: the generated
``evaluate`` appends each pin's rate Jacobian P_p to Jt and its rate bias to bt, so v_t ends with the pins'
relative rates omega_p, and a stuck pin (exact treatment) is a stuck row of the contacts' solve (its multiplier is
the torque that keeps P_p qdd + rate_bias_p = 0). A sliding pin's torque tau_p = -(mu_k r |R_p|_delta + T0) s_p
enters as the generalized force P_p^T tau_p and is solved by Newton around the contacts' solve, with the
reference's iteration (``FrictionDynamics._solve_pins``: start, Jacobian, stopping rule, iteration bound).

The laws arrive as compiled functions of their classes, passed as first-class functions: the
stabilization's ``compiled_bias`` (``study.solver.stabilization``) and the friction treatment's
``compiled_phases`` (``study.solver.friction.laws``: stick flags and slip factors of the contacts).
Options travel in two arrays, ``ci`` (int64) and ``cf`` (float64), whose layout is given by the
``CI_*`` / ``CF_*`` constants below and packed by ``study.fast.frontend``. State y = [q, qd, W_loads,
W_friction (only with friction)], as in the reference.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import types

from study.kernels.cache import internal, kernel
from study.kernels.linalg import lu_factor, lu_solve
from study.kernels.signatures import BIAS_T, EVALUATE_T, I1, PHASES, PHASES_T, V1, f8
from study.solver.friction import CONSISTENCY_RTOL  # the same sign-consistency rule
from study.solver.friction.contact import PIN_MAX_ITERATIONS  # the same bound on the pins' Newton iterations
from study.solver.friction.laws import friction_level, pin_norm  # each written once for both backends

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

# status codes
OK, SINGULAR, PAINLEVE_NONE, PAINLEVE_MANY, PIN_NOT_CONVERGED = 0, 1, 2, 3, 4

# ws.pin, per pin (blocks of np): the slip factor s, the torque tau, the Newton residual F, |R|_delta (block PIN_NORM);
# then the multipliers per unit torque (np x r) and the Newton Jacobian (np x np). Kept in one array: every call
# that passes the workspace pays per array in it (reference counts), pins or not.
PIN_SLIP, PIN_TAU, PIN_RESIDUAL, PIN_NORM, PIN_MATRICES = range(5)
Workspace = namedtuple("Workspace", [
    "q", "qd", "M", "Q", "phi", "J", "gamma", "Jt", "bt", "powers", "c", "phidot", "K", "piv", "x",
    "qdd", "lam", "U", "L", "A", "b", "pivA", "best", "sigma", "best_sigma", "normal", "tol",
    "best_normal", "best_tol", "f", "vt", "stick", "s", "pin", "at", "counters"])


@internal()
def workspace(m, r, nc, nw, npin):
    """Every array one evaluation needs, allocated once per integration (nc contacts and npin pins: nt rows of Jt).
    ``at``: the time of the last failing evaluation; counters: [evaluations, its status]."""
    n, nt = m + r, nc + npin
    return Workspace(
        np.zeros(m), np.zeros(m), np.zeros((m, m)), np.zeros(m), np.zeros(r), np.zeros((r, m)), np.zeros(r),
        np.zeros((nt, m)), np.zeros(nt), np.zeros(nw), np.zeros(r), np.zeros(r), np.zeros((n, n)),
        np.zeros(n, np.int64),
        np.zeros(n), np.zeros(m), np.zeros(r), np.zeros((m, nt)), np.zeros((r, nt)), np.zeros((nt, nt)),
        np.zeros(nt), np.zeros(nt, np.int64), np.zeros(nt), np.zeros(nt), np.zeros(nt), np.zeros(nt),
        np.zeros(nt), np.zeros(nt), np.zeros(nt), np.zeros(nt), np.zeros(nt),
        np.zeros(nt, np.bool_), np.zeros(nt), np.zeros(npin * (PIN_MATRICES + r + npin)), np.zeros(1),
        np.zeros(2, np.int64))


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
def constraint_rhs(bias, ci, cf, ws):
    """ws.c = gamma + b(Phi, Phidot) of the stabilization method: its compiled counterpart ``bias``
    (``compiled_bias`` of its class in study.solver.stabilization), parameters at cf[ci[CI_BIAS]:]."""
    r, m = ws.J.shape
    for i in range(r):
        phidot = 0.0
        for j in range(m):
            phidot += ws.J[i, j] * ws.qd[j]
        ws.phidot[i] = phidot
    bias(ws.phi, ws.phidot, cf, ci[CI_BIAS], ws.c)
    for i in range(r):
        ws.c[i] = ws.gamma[i] + ws.c[i]


@kernel(PHASES)
def no_phases(mode, nlm, vt, cf, off, stick, s):
    """The ``phases`` argument of a run without friction (not called)."""


@internal()
def _friction(ci, cf, ws, m, r, nc):
    """The coupled normal-force / friction problem (study.solver.friction.FrictionDynamics._solve) on top of the
    solution without tangential forces in ws.qdd, ws.lam. The rows of Jt with a tangential force are the stuck ones
    and the sliding ones with s != 0; sliding rows are contacts (j < nc), a stuck row may be a pin's."""
    nt = ws.Jt.shape[0]
    off = CF_HEADER
    n_act = 0
    active = np.empty(nt, np.int64)
    for j in range(nt):
        if ws.stick[j] or ws.s[j] != 0.0:
            active[n_act] = j
            n_act += 1
    for j in range(nt):
        ws.f[j] = 0.0
    if n_act == 0:
        for j in range(nc):
            ws.normal[j] = -ws.lam[ci[CI_CONTACT0 + j]]
        return OK
    for col in range(n_act):  # response to a unit tangential force at row active[col]
        j = active[col]
        for i in range(m):
            ws.x[i] = ws.Jt[j, i]
        for i in range(r):
            ws.x[m + i] = 0.0
        lu_solve(ws.K, ws.piv, ws.x)
        for i in range(m):
            ws.U[i, col] = ws.x[i]
        for i in range(r):
            ws.L[i, col] = ws.x[m + i]
    assumed = np.empty(n_act, np.int64)
    n_ass = 0
    for col in range(n_act):
        j = active[col]
        if not ws.stick[j] and cf[off + j] > 0.0:
            assumed[n_ass] = col
            n_ass += 1
    n_good = 0
    A, b = ws.A[:n_act, :n_act], ws.b[:n_act]
    for combo in range(1 << n_ass):  # itertools.product((1, -1), ...) order
        for col in range(n_act):
            ws.sigma[col] = 0.0
        for a in range(n_ass):
            ws.sigma[assumed[a]] = -1.0 if (combo >> (n_ass - 1 - a)) & 1 else 1.0
        for row in range(n_act):
            j = active[row]
            if ws.stick[j]:
                acc = ws.bt[j]
                for i in range(m):
                    acc += ws.Jt[j, i] * ws.qdd[i]
                for col in range(n_act):
                    v = 0.0
                    for i in range(m):
                        v += ws.Jt[j, i] * ws.U[i, col]
                    A[row, col] = v
                b[row] = -acc
            else:
                kj = ci[CI_CONTACT0 + j]
                w = ws.s[j] * cf[off + j] * ws.sigma[row]
                for col in range(n_act):
                    A[row, col] = -w * ws.L[kj, col]
                A[row, row] += 1.0
                b[row] = -ws.s[j] * cf[off + 2 * nc + j] + w * ws.lam[kj]
        if not lu_factor(A, ws.pivA):
            continue
        lu_solve(A, ws.pivA, b)
        consistent = True
        for row in range(n_act):
            if active[row] >= nc:   # a stuck pin: no normal force, no sign assumed
                ws.normal[row], ws.tol[row] = 0.0, 0.0
                continue
            kj = ci[CI_CONTACT0 + active[row]]
            lam_k, scale = ws.lam[kj], abs(ws.lam[kj])
            for col in range(n_act):
                lam_k += ws.L[kj, col] * b[col]
                scale += abs(ws.L[kj, col]) * abs(b[col])
            ws.normal[row] = -lam_k
            ws.tol[row] = CONSISTENCY_RTOL * scale
            if ws.sigma[row] != 0.0 and ws.sigma[row] * ws.normal[row] < -ws.tol[row]:
                consistent = False
        if not consistent:
            continue
        if n_good == 0:
            for row in range(n_act):
                ws.best[row], ws.best_sigma[row] = b[row], ws.sigma[row]
                ws.best_normal[row], ws.best_tol[row] = ws.normal[row], ws.tol[row]
        else:  # agree only if every contact whose assumed sign differs is grazing (N = 0) in both
            for row in range(n_act):
                if ws.sigma[row] != ws.best_sigma[row]:
                    if abs(ws.normal[row]) > ws.tol[row] or abs(ws.best_normal[row]) > ws.best_tol[row]:
                        return PAINLEVE_MANY
        n_good += 1
    if n_good == 0:
        return PAINLEVE_NONE
    for col in range(n_act):
        fa = ws.best[col]
        ws.f[active[col]] = fa
        for i in range(m):
            ws.qdd[i] += ws.U[i, col] * fa
        for i in range(r):
            ws.lam[i] += ws.L[i, col] * fa
    for j in range(nc):
        ws.normal[j] = -ws.lam[ci[CI_CONTACT0 + j]]
    return OK


@internal()
def _pins(ci, cf, ws, m, r, nc, npin):
    """The pins' torques (FrictionDynamics._solve_pins): Newton on F(tau) = tau + (mu r |R(tau)|_delta + T0) s = 0
    from tau = 0 (ws.qdd, ws.lam hold that solution), the contacts' solve repeated at every iterate. s = 0 for a
    stuck pin, whose torque is its stuck row's multiplier. Leaves f and normal (|R|) of the pins; PIN_NOT_CONVERGED
    after PIN_MAX_ITERATIONS, or if the Newton step is singular or not finite."""
    slip, tau = ws.pin[PIN_SLIP * npin:(PIN_SLIP + 1) * npin], ws.pin[PIN_TAU * npin:(PIN_TAU + 1) * npin]
    res, norm = ws.pin[PIN_RESIDUAL * npin:(PIN_RESIDUAL + 1) * npin], ws.pin[PIN_NORM * npin:(PIN_NORM + 1) * npin]
    o = PIN_MATRICES * npin
    Lp = ws.pin[o:o + npin * r].reshape((npin, r))
    jac = ws.pin[o + npin * r:o + npin * (r + npin)].reshape((npin, npin))
    for k in range(npin):   # a sliding pin's slip factor goes to the Newton loop, not to the contacts' solve
        slip[k] = ws.s[nc + k]
        ws.s[nc + k] = 0.0
    po = pin_block(nc)
    delta, rtol = cf[po + 3 * npin], cf[po + 3 * npin + 1]
    row0 = CI_CONTACT0 + nc
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
        status = _friction(ci, cf, ws, m, r, nc)
        if status != OK:
            return status
        converged = True
        for k in range(npin):
            rx, ry = ws.lam[ci[row0 + 2 * k]], ws.lam[ci[row0 + 2 * k + 1]]
            norm[k] = pin_norm(rx, ry, delta)
            level = friction_level(cf[po + npin + k], norm[k], cf[po + 2 * npin + k])
            res[k] = tau[k] + level * slip[k]
            if not abs(res[k]) <= rtol * max(level, abs(tau[k])):
                converged = False
        if converged:
            for k in range(npin):
                rx, ry = ws.lam[ci[row0 + 2 * k]], ws.lam[ci[row0 + 2 * k + 1]]
                ws.normal[nc + k] = np.sqrt(rx * rx + ry * ry)
                if not ws.stick[nc + k]:
                    ws.f[nc + k] = tau[k]
            return OK
        for i in range(npin):   # I + (mu r s / |R|_delta) R . dR/dtau
            w = cf[po + npin + i] * slip[i] / norm[i]
            a, b = ci[row0 + 2 * i], ci[row0 + 2 * i + 1]
            for j in range(npin):
                jac[i, j] = w * (ws.lam[a] * Lp[j, a] + ws.lam[b] * Lp[j, b])
            jac[i, i] += 1.0
        if not lu_factor(jac, ws.pivA):   # the contacts' solve is done with its pivots until the next iterate
            return PIN_NOT_CONVERGED
        lu_solve(jac, ws.pivA, res)
        for k in range(npin):
            if not np.isfinite(res[k]):
                return PIN_NOT_CONVERGED
        for k in range(npin):
            tau[k] -= res[k]
    return PIN_NOT_CONVERGED


@internal()
def accelerations(evaluate, bias, phases, t, mode, p, lp, ci, cf, ws):
    """qdd, lambda (and with friction f, v_t, N) at the state in ws.q, ws.qd; returns a status code."""
    evaluate(t, ws.q, ws.qd, mode, p, lp, ws.M, ws.Q, ws.phi, ws.J, ws.gamma, ws.Jt, ws.bt, ws.powers)
    ws.counters[0] += 1
    m, r = ws.q.size, ws.phi.size
    constraint_rhs(bias, ci, cf, ws)
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
    if ci[CI_FRICTION] == 0:
        return OK
    nt = ws.Jt.shape[0]
    for j in range(nt):
        v = 0.0
        for i in range(m):
            v += ws.Jt[j, i] * ws.qd[i]
        ws.vt[j] = v
    phases(mode, ci[CI_NLOADMODE], ws.vt, cf, ci[CI_PHASES], ws.stick, ws.s)
    npin = dimensions(ci)[4]
    if npin > 0:
        return _pins(ci, cf, ws, m, r, nt - npin, npin)
    return _friction(ci, cf, ws, m, r, nt)


@internal()
def note_failure(ws, status, t):
    """Keep a failing evaluation's status and time (ws.counters[1], ws.at[0]; its q, qd stay in ws.q, ws.qd) for the
    loop's report."""
    ws.counters[1] = status
    ws.at[0] = t


@internal()
def rhs(evaluate, bias, phases, t, y, mode, p, lp, ci, cf, ws, dy):
    """dy = [qd, qdd, load powers, friction powers f_j v_t,j of the contacts, then the pins]; returns a status code."""
    m = ws.q.size
    for i in range(m):
        ws.q[i] = y[i]
        ws.qd[i] = y[m + i]
    status = accelerations(evaluate, bias, phases, t, mode, p, lp, ci, cf, ws)
    if status != OK:
        note_failure(ws, status, t)
    for i in range(m):
        dy[i] = ws.qd[i]
        dy[m + i] = ws.qdd[i]
    nw = ws.powers.size
    for k in range(nw):
        dy[2 * m + k] = ws.powers[k]
    if ci[CI_FRICTION] == 1:
        for j in range(ws.Jt.shape[0]):
            dy[2 * m + nw + j] = ws.f[j] * ws.vt[j]
    return status


#: the entry kernels' declared signatures: each compiles (or loads) for it on first use (study.fast.frontend.entry)
ACCELERATIONS_ENTRY = types.int64(EVALUATE_T, BIAS_T, PHASES_T, f8, V1, V1, I1, V1, V1, I1, V1, V1, types.int64)
RHS_ENTRY = types.int64(EVALUATE_T, BIAS_T, PHASES_T, f8, V1, I1, V1, V1, I1, V1, V1)


@kernel()
def accelerations_entry(evaluate, bias, phases, t, q, qd, mode, p, lp, ci, cf, out, repeat):
    """``repeat`` acceleration evaluations at (t, q, qd); out = [qdd, lambda, N, f] (N and f: contacts, then pins:
    |R| and the torque). For tests and timing."""
    m, r, nc, nw, npin = dimensions(ci)
    ws = workspace(m, r, nc, nw, npin)
    nt = nc + npin
    status = 0
    for _ in range(repeat):
        for i in range(m):
            ws.q[i] = q[i]
            ws.qd[i] = qd[i]
        status = accelerations(evaluate, bias, phases, t, mode, p, lp, ci, cf, ws)
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
def rhs_entry(evaluate, bias, phases, t, y, mode, p, lp, ci, cf, dy):
    """:func:`rhs` called from Python: dy = y' at (t, y), for scipy's integrators; returns a status code."""
    m, r, nc, nw, npin = dimensions(ci)
    return rhs(evaluate, bias, phases, t, y, mode, p, lp, ci, cf, workspace(m, r, nc, nw, npin), dy)
