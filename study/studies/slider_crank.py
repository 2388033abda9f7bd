"""Mechanism A (paper 000): the slider-crank with Coulomb friction in the slider guide.

Two things live here:

1. :func:`paper_method`, 000's own method written out for this mechanism with its misprints
   corrected: multipliers eliminated with D = [1, d12] (eqs. 24-25), the acceleration constraint
   (eq. 28, corrected to y_B'' = 0), and N from the moment balance of rod + slider about A
   (eqs. 31/34, corrected), with F_fr = -f |N| sgn(x_B') - F sgn(x_B'). It is a pure function of
   the parameters, the state and the sign hypotheses, independent of the builder and the solver,
   and the tests check it against the multiplier-based contact of ``study.solver.friction``.

2. :func:`run_study`, the friction study: the variants ``seed``, ``sustained_sliding`` and
   ``slip_then_stick`` with each friction treatment, plus the paper's printed (inconsistent)
   initial conditions.

What happens in the seed case (000's data, consistent initial conditions q1 = pi/6,
q1' = 0.001 rad/s; numbers from ``seed_holding_forces.csv`` and ``summary.csv``): the mechanism does
not run. The slider starts sliding at x_B' = -4.6e-4 m/s (crank turning forward); the resistance
and the friction, F + f|N| = 5.5 + 0.25 * 15.51 = 9.38 N, stop it after 3.6 ms, when it has moved
0.8 micrometre and the crank 1.9e-6 rad. From then on it sticks for the whole 20 s.

What holds it: at rest the loads' torques about the crank axis (along the motion, D = [1, d12]) are
the drive M = +0.5 N m, the spring -alpha q1 = -0.0052 N m and the rod's weight -0.4330 N m (the
slider's weight acts along the guide's normal and has no component along the motion). Their sum,
+0.0618 N m, pushes the slider towards -x through the lever dx_B/dq1 = -0.457 m. To hold it the
guide supplies f_req = +0.135 N, 1.4 % of its static limit of 9.38 N. The spring is negligible:
the drive and the rod's weight nearly cancel. Breaking away at this pose needs M = 4.77 N m (from
the stick margin). ``slip_then_stick`` uses M = 5 N m: the slider slides, slows as the crank's
lever on it grows, and sticks at t = 4.43 s. ``sustained_sliding`` uses M = 10 N m: it never sticks,
and it reverses only at the crank's dead centres, where it cannot be held.

The paper's figures show motion over 20 s, which a correct model cannot produce from these data.
The printed initial state is also 5.2 m off the guide (see the ``printed_*`` runs).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from study.mechanisms import load
from study.params import SliderCrankParameters
from study.results import SimulationResult
from study.simulate import simulate

Array = np.ndarray


# --- 000's method, corrected --------------------------------------------------------------------
@dataclass(frozen=True)
class PaperSolution:
    """Result of :func:`paper_method` for one sign hypothesis.

    qdd : (2,) accelerations; normal : N, the guide's force on the slider along +y [N];
    friction : F_fr, the guide's tangential force on the slider along +x, resistance F included [N];
    consistent : whether sigma * N >= 0 (the assumed sign of N holds).
    """

    qdd: Array
    normal: float
    friction: float
    consistent: bool


def _paper_terms(v: SliderCrankParameters, q, qd):
    q1, q2 = float(q[0]), float(q[1])
    w1, w2 = float(qd[0]), float(qd[1])
    th, wth = q1 + q2, w1 + w2
    s1, c1, sth, cth, s2, cq2 = math.sin(q1), math.cos(q1), math.sin(th), math.cos(th), math.sin(q2), math.cos(q2)
    # eq. (14), corrected: a22 = J2 + m2 c2^2 + m3 l2^2 (printed m2 c2 l1), a12 ends in J2 (printed J3)
    a11 = v.J1 + v.J2 + v.m2 * (v.l1**2 + v.c2**2 - 2 * v.l1 * v.c2 * cq2) + v.m3 * (v.l1**2 + v.l2**2 - 2 * v.l1 * v.l2 * cq2)
    a12 = v.J2 + v.m2 * (v.c2**2 - v.l1 * v.c2 * cq2) + v.m3 * (v.l2**2 - v.l1 * v.l2 * cq2)
    a22 = v.J2 + v.m2 * v.c2**2 + v.m3 * v.l2**2
    A = np.array([[a11, a12], [a12, a22]])
    # eq. (27), corrected: Q1^qt = -k sin q2 (2 q1' q2' + q2'^2) (printed q1'^2 + 2 q1' q2')
    k = (v.m2 * v.c2 + v.m3 * v.l2) * v.l1
    Qqt = np.array([-k * s2 * (2 * w1 * w2 + w2**2), k * s2 * w1**2])
    # eq. (18): pi = m2 g y_C2 (+ alpha q1^2 / 2 for the spring reading of '-alpha q1')
    grad_pi = np.array([v.m2 * v.g * (v.l1 * c1 - v.c2 * cth), -v.m2 * v.g * v.c2 * cth])
    Q = np.array([v.M, 0.0]) - grad_pi + Qqt
    Q[0] -= v.alpha * (q1 if v.alpha_law == "spring" else w1)
    # eq. (19): dx_B/dq; the slider's horizontal force F_fr has generalized force F_fr * dx_B/dq
    # (eq. 20 and the separate '-F' in Q2 of eq. 26 are replaced by this: F is part of F_fr)
    dxB = np.array([v.l2 * sth - v.l1 * s1, v.l2 * sth])
    d12 = v.l1 * c1 / (v.l2 * cth) - 1.0  # eq. (24)
    return dict(q1=q1, w1=w1, th=th, wth=wth, s1=s1, c1=c1, sth=sth, cth=cth, A=A, Q=Q, dxB=dxB,
                D=np.array([1.0, d12]))


def paper_method(v: SliderCrankParameters, q, qd, s: float, sigma: float) -> PaperSolution:
    """000's method for the slider-crank (eqs. 24-34, corrected), one sign hypothesis.

    Unknowns qdd1, qdd2 and N, from three equations linear in them once s = sgn(x_B') and
    sigma = sgn(N) are assumed, with F_fr = -s (F + f sigma N) (eq. 32 with the resistance F):

    - eq. (25):  D (A qdd - Q - F_fr dx_B/dq) = 0, D = [1, d12]  (the ideal N drops out: D dy_B/dq = 0);
    - eq. (28), corrected to the constraint's second derivative, y_B'' = 0 (the printed one is x_B'');
    - eqs. (31)/(34), corrected: moments about A of rod + slider, with the inertial forces of the rod
      at C2 (-m2 a_C2, -J2 eps2), the rod's weight at C2, and at B the slider's weight, inertia
      -m3 a_B, N and F_fr, each with its own lever arm (the printed eq. 31 uses B's arm for the rod's
      inertial force and omits the rod's weight).

    Parameters
    ----------
    v : SliderCrankParameters
    q, qd : (2,) state on the constraint manifold
    s : sliding direction, +-1 (0: no friction or resistance)
    sigma : assumed sign of N, +-1
    """
    T = _paper_terms(v, q, qd)
    l1, l2, c2 = v.l1, v.l2, v.c2

    def residual(x):
        qdd, N = x[:2], x[2]
        F_fr = -s * (v.F + v.mu * sigma * N)
        r25 = T["D"] @ (T["A"] @ qdd - T["Q"] - F_fr * T["dxB"])
        th_dd = qdd[0] + qdd[1]
        r28 = ((l1 * T["c1"] - l2 * T["cth"]) * qdd[0] - l2 * T["cth"] * qdd[1]
               - l1 * T["s1"] * T["w1"] ** 2 + l2 * T["sth"] * T["wth"] ** 2)

        def accel(length):  # acceleration of the rod point at distance `length` from A (eq. 30)
            ax = (-l1 * T["s1"] + length * T["sth"]) * qdd[0] + length * T["sth"] * qdd[1] \
                - l1 * T["c1"] * T["w1"] ** 2 + length * T["cth"] * T["wth"] ** 2
            ay = (l1 * T["c1"] - length * T["cth"]) * qdd[0] - length * T["cth"] * qdd[1] \
                - l1 * T["s1"] * T["w1"] ** 2 + length * T["sth"] * T["wth"] ** 2
            return ax, ay

        def moment(arm, fx, fy):  # z-moment about A of a force at A + arm * (-cos th, -sin th)
            rx, ry = -arm * T["cth"], -arm * T["sth"]
            return rx * fy - ry * fx

        axC, ayC = accel(c2)
        axB, ayB = accel(l2)
        r31 = (-v.J2 * th_dd
               + moment(c2, -v.m2 * axC, -v.m2 * ayC - v.m2 * v.g)
               + moment(l2, F_fr - v.m3 * axB, N - v.m3 * v.g - v.m3 * ayB))
        return np.array([r25, r28, r31])

    r0 = residual(np.zeros(3))
    K = np.column_stack([residual(e) - r0 for e in np.eye(3)])  # the residuals are affine in x
    x = np.linalg.solve(K, -r0)
    N = float(x[2])
    return PaperSolution(x[:2], N, float(-s * (v.F + v.mu * sigma * N)), bool(sigma * N >= 0))


def paper_method_consistent(v: SliderCrankParameters, q, qd, s: float) -> PaperSolution:
    """The consistent sign hypothesis of :func:`paper_method` (exactly one expected; else ValueError)."""
    sols = [paper_method(v, q, qd, s, sigma) for sigma in (1.0, -1.0)]
    good = [p for p in sols if p.consistent]
    if len(good) != 1 and not (len(good) == 2 and abs(good[0].normal) < 1e-12 * (1 + abs(good[1].normal))):
        raise ValueError(f"{len(good)} consistent signs of N at q = {list(q)}, qd = {list(qd)}, s = {s}")
    return good[0]


def holding_forces(v: SliderCrankParameters, q) -> dict[str, float]:
    """Static balance of the stuck mechanism at q (qd = 0), from 000's D = [1, d12].

    Each load's generalized force along the motion, R^T Q with R = [1, d12]^T, is a torque about
    the crank axis [N m]; the guide must supply f_req = -(sum) / (R^T dx_B/dq) along +x [N].
    """
    T = _paper_terms(v, q, np.zeros(2))
    R = T["D"]
    grad_rod = np.array([v.m2 * v.g * (v.l1 * T["c1"] - v.c2 * T["cth"]), -v.m2 * v.g * v.c2 * T["cth"]])
    terms = {"drive_M": v.M, "alpha_term": -v.alpha * T["q1"] if v.alpha_law == "spring" else 0.0,
             "rod_weight": float(-R @ grad_rod), "slider_weight": 0.0}
    lever = float(R @ T["dxB"])
    total = sum(terms.values())
    f_req = -total / lever
    return {**{f"torque_{k}": val for k, val in terms.items()}, "torque_sum": total,
            "lever_dxB_dq1": lever, "f_required": f_req}


# --- the study -----------------------------------------------------------------------------------
VARIANTS = ("seed", "sustained_sliding", "slip_then_stick")
# Treatments and their integrator settings (study's own choices):
# exact: DOP853, rtol 1e-10 / atol 1e-12, the tightest setting that keeps every run well under a second per
#   simulated second; its events are located to 1e-14 s, so it is the reference for the other two.
# regularized: tanh(v/eps) with eps = 1e-3 m/s (about 0.1 % of the sliding speeds of the moving variants),
#   RK45 at the solver's default tolerances.
# sign: the paper's plain sgn with fixed-step RK4, h = 1e-3 s (what a MATLAB-style script would use).
TREATMENTS = {
    "exact": dict(friction="exact", integrator="DOP853", rtol=1e-10, atol=1e-12),
    "regularized": dict(friction="regularized", friction_eps=1e-3, friction_sgn="tanh", integrator="RK45"),
    "sign": dict(friction="sign", friction_eps=1e-3, integrator="RK4", step=1e-3),
}
REPORT_TIMES = (1.0, 5.0, 10.0, 20.0)


def _phase_times(result: SimulationResult) -> dict:
    """Stick onsets, slip onsets (leaving stick) and direction reversals of the guide contact."""
    if result.meta.get("friction") == "exact":
        tr = [x for x in result.stats.get("friction_transitions", []) if x.get("contact")]
        stick = [x["t"] for x in tr if x["to"] == "stick"]
        slip = [x["t"] for x in tr if x["from"] == "stick"]
        rev = [x["t"] for x in tr if x["from"] != "stick" and x["to"] != "stick"]
        first = result.stats["friction_transitions"][0]["initial"]["guide"]
    else:  # apparent stick |v_t| <= eps on the output samples
        flag = result.forces["stick_guide"]
        change = np.flatnonzero(np.diff(flag) != 0) + 1
        stick = [float(result.t[i]) for i in change if flag[i] > 0]
        slip = [float(result.t[i]) for i in change if flag[i] == 0]
        rev = []
        first = "stick" if flag[0] > 0 else "slip"
    return {"initial_phase": first, "stick_times": stick, "slip_times": slip, "reversals": rev}


def _fmt(times, limit=12):
    shown = ";".join(f"{t:.6g}" for t in times[:limit])
    return shown + (f";...(+{len(times) - limit})" if len(times) > limit else "")


def summarize(name: str, result: SimulationResult, **labels) -> dict:
    """One summary row: phase times, q1 and friction at REPORT_TIMES, dissipation, energy balance."""
    phases = _phase_times(result)
    row = {"case": name, **labels, "initial_phase": phases["initial_phase"],
           "n_stick": len(phases["stick_times"]), "stick_times": _fmt(phases["stick_times"]),
           "n_slip_from_stick": len(phases["slip_times"]), "slip_times": _fmt(phases["slip_times"]),
           "n_reversals": len(phases["reversals"]), "reversal_times": _fmt(phases["reversals"])}
    for tr in REPORT_TIMES:
        i = int(np.argmin(np.abs(result.t - tr)))
        ok = abs(result.t[i] - tr) < 1e-9
        row[f"q1_t{tr:g}"] = float(result.q[i, 0]) if ok else float("nan")
        row[f"friction_t{tr:g}"] = float(result.forces["friction_guide"][i]) if ok else float("nan")
        row[f"normal_t{tr:g}"] = float(result.forces["normal_guide"][i]) if ok else float("nan")
    s = result.summary()
    row.update({
        "dissipated_energy": float(-result.energies["work_friction_guide"][-1]),
        "energy_balance_error": s["energy_error"],
        "max_abs_phi": s["max_abs_phi"],
        "cpu_seconds": s["cpu_seconds"],
        "nfev": result.stats.get("nfev"),
        "steps": result.stats.get("steps"),
        "events": result.stats.get("events"),
    })
    return row


def run_study(out_dir, t_end: float = 20.0, progress=print) -> pd.DataFrame:
    """Run the slider-crank friction study and save every result plus ``summary.csv``.

    Runs: each of ``VARIANTS`` (consistent initial conditions) with each of ``TREATMENTS``; and the
    seed variant from 000's printed, inconsistent initial state (q2 = 0.0834 puts the slider 5.2 m
    below its guide and q' violates the velocity constraint) with the exact treatment, once with
    post-step projection and once with Baumgarte stabilization. Those two show that the printed
    state cannot be used as is: projection jumps to the nearest assembled configuration (minimum
    norm: a different crank angle), Baumgarte pulls the slider onto the guide over ~1 s with a
    normal force ~100 times the physical one, hence a friction force ~40 times too large and a
    spurious dissipation; the two end in different rest positions, neither the one of the consistent run.

    Where the exact treatment sticks, the other two do not. ``regularized`` creeps at
    v ~ eps atanh(|f_req| / limit); in ``slip_then_stick``, where f_req is close to the limit, the crank
    gains 0.05 rad over 15 s. ``sign`` (RK4) neither sticks nor creeps smoothly: its stages straddle
    v = 0, so the velocity chatters or settles on a spurious fixed point of the step map (v ~ h a).
    Its friction work is then not the energy the model loses: the energy-balance error equals the
    whole reported dissipation (seed: 0.012 J against 8e-6 J for the exact run).

    Parameters
    ----------
    out_dir : path
        Results go to ``<out_dir>/<case>.csv/.json``; also ``summary.csv`` and ``seed_holding_forces.csv``.
    t_end : float
        Horizon [s]; 000's is 20 s.

    Returns
    -------
    pandas.DataFrame, the summary table.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = []

    def run(name, eom_or_mech, q0=None, qd0=None, variant=None, **options):
        wall = time.perf_counter()
        result = simulate(eom_or_mech, q0, qd0, t_end=t_end, variant=variant, **options)
        result.meta["case"] = name
        result.save(out / name)
        if progress:
            progress(f"{name}: {time.perf_counter() - wall:.1f} s wall, {result.stats['nfev']} evaluations")
        return result

    seed_exact = None
    for variant in VARIANTS:
        for treatment, options in TREATMENTS.items():
            name = f"{variant}_{treatment}"
            result = run(name, "slider_crank", variant=variant, method="none", **options)
            if variant == "seed" and treatment == "exact":
                seed_exact = result
            rows.append(summarize(name, result, variant=variant, treatment=treatment, initial="consistent",
                                  method="none", integrator=options["integrator"]))

    ps, eom = load("slider_crank", "seed")
    for method in ("projection", "baumgarte"):
        name = f"printed_{method}_exact"
        options = TREATMENTS["exact"]
        result = run(name, eom, ps.initial.printed_q, ps.initial.printed_qd, method=method, **options)
        rows.append(summarize(name, result, variant="seed", treatment="exact", initial="printed", method=method,
                              integrator=options["integrator"]))

    summary = pd.DataFrame(rows)
    summary.to_csv(out / "summary.csv", index=False, float_format="%.10g")

    # what holds the seed case: the static balance at its computed rest state
    held = holding_forces(ps.values, seed_exact.q[-1])
    i_end = len(seed_exact.t) - 1
    held.update({"t": float(seed_exact.t[i_end]), "q1": float(seed_exact.q[i_end, 0]), "q2": float(seed_exact.q[i_end, 1]),
                 "normal_N": float(seed_exact.forces["normal_guide"][i_end]),
                 "friction_solver": float(seed_exact.forces["friction_guide"][i_end]),
                 "static_limit": float(ps.values.F + ps.values.mu * abs(seed_exact.forces["normal_guide"][i_end])),
                 "slide_distance": float(abs(ps.values.l1 * math.cos(seed_exact.q[i_end, 0])
                                             - ps.values.l2 * math.cos(seed_exact.q[i_end].sum())
                                             - ps.values.l1 * math.cos(seed_exact.q[0, 0])
                                             + ps.values.l2 * math.cos(seed_exact.q[0].sum())))})
    pd.DataFrame([held]).to_csv(out / "seed_holding_forces.csv", index=False, float_format="%.10g")
    return summary
