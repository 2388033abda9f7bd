"""The contact and pin solve: the tangential forces of the sliding contacts from the normal-force sign hypotheses, and
the Newton iterate of the pins' friction torques (paper 000 eqs. 3, 10, 25-34; SPEC sec. 1).

The derivation is in ``study.solver.friction.contact`` (the reference path's readable form around these functions).
In short: with the solution without tangential forces (qdd_a, lambda_a) and the responses to a unit tangential
force at each active entry (columns of U, L), qdd = qdd_a + U f and lambda = lambda_a + L f; per hypothesis sigma of
the signs of the sliding contacts' normal forces, f solves a small linear system, and exactly one consistent
hypothesis must exist (else Painleve's paradox). A sliding pin's torque solves tau + (mu r |R(tau)|_delta + T0) s = 0
by Newton around that solve.

Both paths call these compiled functions: the compiled loop (``study.fast.dynamics``) natively, the reference path
from Python. The backends differ only in how they solve for qdd_a, lambda_a, U, L (the reference: its chosen
acceleration solver; the compiled: one LU of the saddle-point matrix) and in how they report a failure.

Arrays: Jt (nt, m) the rows whose velocity and rate the entries' forces act along (contacts, then pins), bt (nt,)
their rate biases; stick, s (nt,) the phases; index (nc,) each contact's normal row in lambda, mu_k (nc,),
resistance (nc,); active (nt,) the entries with a tangential force (n_act of them, their column in U, L); scratch
(SCRATCH_ROWS, nt) the work rows below.
"""

from __future__ import annotations

import numpy as np

from study.kernels.cache import kernel
from study.kernels.linalg import lu_factor, lu_solve
from study.laws.friction import friction_level, pin_norm

# A sign hypothesis sigma_j for N_j is consistent if sigma_j N_j >= -CONSISTENCY_RTOL * (scale of the
# terms summed into N_j). N_j comes from solves whose condition numbers stay below ~1e5 for the
# study's mechanisms, so its round-off is below 1e5 * 2.2e-16 ~ 2e-11 relative; 1e-10 rejects a
# hypothesis only when N_j has the wrong sign by more than round-off.
CONSISTENCY_RTOL = 1e-10

#: Iterations allowed to the Newton solve of the pins' friction torques before it is reported as not converged.
PIN_MAX_ITERATIONS = 50

#: the outcome of an acceleration evaluation: the saddle-point matrix is singular (SINGULAR), no or two different
#: consistent sign hypotheses (PAINLEVE_NONE, PAINLEVE_MANY), the pins' torques did not converge
OK, SINGULAR, PAINLEVE_NONE, PAINLEVE_MANY, PIN_NOT_CONVERGED = range(5)
#: the outcome of one sign hypothesis (:func:`hypothesis`)
INCONSISTENT, CONSISTENT, SINGULAR_HYPOTHESIS = range(3)
#: the outcome of one Newton iterate of the pins' torques (:func:`pin_newton_step`)
CONVERGED, STEPPED, STEP_FAILED = range(3)
#: rows of the scratch: per active row, a hypothesis' signs, forces, normal forces, tolerances, and the same of the
#: first consistent hypothesis
SIGMA, FORCE, NORMAL, TOL, BEST_SIGMA, BEST_FORCE, BEST_NORMAL, BEST_TOL = range(8)
SCRATCH_ROWS = 8


@kernel()
def active_entries(stick, s, active):
    """The entries with a tangential force, stuck or with s != 0, into active[:n]; returns n."""
    n = 0
    for j in range(stick.size):
        if stick[j] or s[j] != 0.0:
            active[n] = j
            n += 1
    return n


@kernel()
def assumed_signs(active, n_act, stick, mu_k, assumed):
    """The active rows whose normal force's sign is hypothesized (sliding contacts with mu_k > 0) into
    assumed[:n]; returns n."""
    n = 0
    for col in range(n_act):
        j = active[col]
        if not stick[j] and j < mu_k.size and mu_k[j] > 0.0:
            assumed[n] = col
            n += 1
    return n


@kernel()
def hypothesis(combo, assumed, n_ass, active, n_act, stick, s, Jt, bt, qdd, lam, U, L, index, mu_k, resistance,
               A, piv, scratch):
    """Sign hypothesis number ``combo`` (itertools.product((1, -1), repeat=n_ass) order): scratch[SIGMA] its signs,
    scratch[FORCE] the forces f of the active rows, scratch[NORMAL], scratch[TOL] their normal forces and the
    consistency tolerances (0 for a stuck pin's row, j >= nc); returns CONSISTENT, INCONSISTENT or
    SINGULAR_HYPOTHESIS. A: (>= n_act)-square work matrix, piv its pivots."""
    m, nc = qdd.size, index.size
    sigma, f, normal, tol = scratch[SIGMA], scratch[FORCE], scratch[NORMAL], scratch[TOL]
    for col in range(n_act):
        sigma[col] = 0.0
    for a in range(n_ass):
        sigma[assumed[a]] = -1.0 if (combo >> (n_ass - 1 - a)) & 1 else 1.0
    for row in range(n_act):
        j = active[row]
        if stick[j]:   # J_t,j qdd + bt_j = 0
            acc = bt[j]
            for i in range(m):
                acc += Jt[j, i] * qdd[i]
            for col in range(n_act):
                v = 0.0
                for i in range(m):
                    v += Jt[j, i] * U[i, col]
                A[row, col] = v
            f[row] = -acc
        else:          # f_j = -s_j (R_j + mu_k,j sigma_j N_j), N_j = -lambda_k
            kj = index[j]
            w = s[j] * mu_k[j] * sigma[row]
            for col in range(n_act):
                A[row, col] = -w * L[kj, col]
            A[row, row] += 1.0
            f[row] = -s[j] * resistance[j] + w * lam[kj]
    if not lu_factor(A[:n_act, :n_act], piv):
        return SINGULAR_HYPOTHESIS
    lu_solve(A[:n_act, :n_act], piv, f)
    consistent = True
    for row in range(n_act):
        if active[row] >= nc:   # a stuck pin: no normal force, no sign assumed
            normal[row], tol[row] = 0.0, 0.0
            continue
        kj = index[active[row]]
        lam_k, scale = lam[kj], abs(lam[kj])
        for col in range(n_act):
            lam_k += L[kj, col] * f[col]
            scale += abs(L[kj, col]) * abs(f[col])
        normal[row] = -lam_k
        tol[row] = CONSISTENCY_RTOL * scale
        if sigma[row] != 0.0 and sigma[row] * normal[row] < -tol[row]:
            consistent = False
    return CONSISTENT if consistent else INCONSISTENT


@kernel()
def contact_forces(active, n_act, stick, s, Jt, bt, qdd, lam, U, L, index, mu_k, resistance, A, piv, scratch,
                   f, normal):
    """The contacts' solve: every sign hypothesis in turn; exactly one consistent (or several that differ only in
    the signs of grazing contacts, N = 0 in both) is used: f (nt) its forces by entry, qdd and lam (the solution
    without tangential forces on entry) updated to qdd_a + U f, lambda_a + L f, normal (nc) = -lambda[index].
    Returns OK, PAINLEVE_NONE or PAINLEVE_MANY (then qdd, lam, f, normal are not the solution)."""
    for j in range(f.size):
        f[j] = 0.0
    if n_act > 0:
        assumed = np.empty(n_act, np.int64)
        n_ass = assumed_signs(active, n_act, stick, mu_k, assumed)
        n_good = 0
        for combo in range(1 << n_ass):
            if hypothesis(combo, assumed, n_ass, active, n_act, stick, s, Jt, bt, qdd, lam, U, L, index, mu_k,
                          resistance, A, piv, scratch) != CONSISTENT:
                continue
            if n_good == 0:
                for k in range(4):
                    for row in range(n_act):
                        scratch[BEST_SIGMA + k, row] = scratch[SIGMA + k, row]
            else:   # agree only if every contact whose assumed sign differs is grazing (N = 0) in both
                for row in range(n_act):
                    if scratch[SIGMA, row] != scratch[BEST_SIGMA, row] and (
                            abs(scratch[NORMAL, row]) > scratch[TOL, row]
                            or abs(scratch[BEST_NORMAL, row]) > scratch[BEST_TOL, row]):
                        return PAINLEVE_MANY
            n_good += 1
        if n_good == 0:
            return PAINLEVE_NONE
        for col in range(n_act):
            fa = scratch[BEST_FORCE, col]
            f[active[col]] = fa
            for i in range(qdd.size):
                qdd[i] += U[i, col] * fa
            for i in range(lam.size):
                lam[i] += L[i, col] * fa
    for j in range(index.size):
        normal[j] = -lam[index[j]]
    return OK


@kernel()
def pin_newton_step(lam, rows, dlam, tau, slip, coef, torque, delta, rtol, norm, res, step, jac, piv):
    """One Newton iterate on F(tau) = tau + (coef |R(tau)|_delta + torque) slip = 0 of the pins (a stuck pin: slip 0)
    at the contacts' solve with the torques tau: R_k = (lam[rows[2k]], lam[rows[2k + 1]]), dlam[j] the multipliers
    per unit torque at pin j. norm = |R|_delta, res = F. CONVERGED if |F_k| <= rtol max(level_k, |tau_k|) for every
    pin; else tau -= (I + (coef slip / |R|_delta) R . dR/dtau)^-1 F: STEPPED, or STEP_FAILED if that matrix is
    singular or the step not finite. step (npin), jac (npin, npin): work, piv its pivots."""
    npin = tau.size
    converged = True
    for k in range(npin):
        norm[k] = pin_norm(lam[rows[2 * k]], lam[rows[2 * k + 1]], delta)
        level = friction_level(coef[k], norm[k], torque[k])
        res[k] = tau[k] + level * slip[k]
        if not abs(res[k]) <= rtol * max(level, abs(tau[k])):
            converged = False
    if converged:
        return CONVERGED
    for i in range(npin):
        w = coef[i] * slip[i] / norm[i]
        a, b = rows[2 * i], rows[2 * i + 1]
        for j in range(npin):
            jac[i, j] = w * (lam[a] * dlam[j, a] + lam[b] * dlam[j, b])
        jac[i, i] += 1.0
    for k in range(npin):
        step[k] = res[k]
    if not lu_factor(jac, piv):
        return STEP_FAILED
    lu_solve(jac, piv, step)
    for k in range(npin):
        if not np.isfinite(step[k]):
            return STEP_FAILED
    for k in range(npin):
        tau[k] -= step[k]
    return STEPPED

