"""Random states on the constraint manifold, for the numeric checks of the errata."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import sympy as sp

from study.model.initial_state import consistent_initial_conditions


# Number of random configurations on the constraint manifold per mechanism; each one is a full
# (q, qd, qdd) state, spread over a whole crank turn. A misprint would have to vanish at all of
# them by accident.
SAMPLES = 8
RNG_SEED = 20240611
# Relative spread of the randomized parameters around the seed values. Small enough that both
# mechanisms still assemble over a whole crank turn (001 needs |h2 - l2 sin q2| < l3 and h1 > l1),
# large enough to break the seed's coincidences. Seed values of exactly zero (001's a1) are
# replaced by a value drawn from ZERO_PARAMETER_RANGE.
PARAMETER_SPREAD = 0.03
ZERO_PARAMETER_RANGE = (0.1, 0.5)
# Largest step of the independent coordinate in the continuation between samples [rad].
CONTINUATION_STEP = 0.1


@dataclass(frozen=True)
class Samples:
    """Random states on the constraint manifold, with the randomized parameter values."""

    values: dict[sp.Symbol, float]
    q: np.ndarray    # (S, m)
    qd: np.ndarray   # (S, m)
    qdd: np.ndarray  # (S, m), Phi_q qdd = gamma
    null: np.ndarray  # (S, m, n) orthonormal null-space bases of Phi_q

    @staticmethod
    def draw(ctx) -> "Samples":
        rng = np.random.default_rng(RNG_SEED)
        values = {}
        for k, sym in ctx.parameters.items():
            v = float(ctx.b.values[k])
            values[sym] = v * rng.uniform(1 - PARAMETER_SPREAD, 1 + PARAMETER_SPREAD) if v else rng.uniform(*ZERO_PARAMETER_RANGE)
        for k in sorted(ctx.extras):
            values[ctx.extras[k]] = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 2.0))
        kin = ctx.kinematics(values)
        ic = ctx.ps.initial
        ind = list(ic.independent)
        guess = np.array(ic.printed_q, dtype=float)
        guess[ind] = ic.q_independent
        start = consistent_initial_conditions(kin, guess, ind, rng.normal(size=len(ind))).q
        gamma = sp.lambdify([list(ctx.q), list(ctx.qd)], ctx.eqs.gamma.xreplace(values), "numpy")
        offsets = np.linspace(0.0, 2 * np.pi, SAMPLES, endpoint=False) + rng.uniform(0.05, 0.6)
        qs, qds, qdds, nulls = [], [], [], []
        current = start.copy()
        for off in offsets:
            target = start[ind] + off
            steps = max(1, int(np.ceil(np.max(np.abs(target - current[ind])) / CONTINUATION_STEP)))
            begin = current[ind].copy()
            for s in range(1, steps + 1):
                guess = current.copy()
                guess[ind] = begin + (target - begin) * s / steps
                current = consistent_initial_conditions(kin, guess, ind, np.zeros(len(ind))).q
            state = consistent_initial_conditions(kin, current, ind, rng.normal(size=len(ind)))
            jac = kin.phi_q(state.q)
            g = np.asarray(gamma(state.q, state.qd), dtype=float).reshape(-1)
            _, _, vt = np.linalg.svd(jac)
            null = vt[jac.shape[0]:].T
            qdd = np.linalg.lstsq(jac, g, rcond=None)[0] + null @ rng.normal(size=null.shape[1])
            qs.append(state.q), qds.append(state.qd), qdds.append(qdd), nulls.append(null)
        return Samples(values, np.array(qs), np.array(qds), np.array(qdds), np.array(nulls))

    def evaluate(self, ctx, exprs: Sequence[sp.Expr]) -> np.ndarray:
        """Values (S, len(exprs)) of expressions at the samples."""
        fn = sp.lambdify([list(ctx.q), list(ctx.qd), list(ctx.qdd)],
                         [sp.sympify(x).xreplace(self.values) for x in exprs], "numpy")
        return np.array([np.broadcast_to(np.asarray(fn(q, qd, qdd), dtype=float), (len(exprs),))
                         for q, qd, qdd in zip(self.q, self.qd, self.qdd)])

    def magnitude(self, ctx, exprs: Sequence[sp.Expr]) -> np.ndarray:
        """Sum of the absolute values of the terms of each expanded expression, at the samples."""
        return self.evaluate(ctx, [sum((sp.Abs(t) for t in sp.Add.make_args(sp.expand(x))), sp.Integer(0))
                                   for x in exprs])


