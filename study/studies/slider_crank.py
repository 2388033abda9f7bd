"""Mechanism A (paper 000): the slider-crank with Coulomb friction in the slider guide.

The friction study, as data: the case list ``reference/cases/slider_crank.toml`` (the variants
``seed``, ``sustained_sliding``, ``slip_then_stick`` and ``alpha_damping`` with each friction
treatment, 000's printed (inconsistent) initial conditions, and a sweep of the regularization
width eps), run by :mod:`study.pipeline`, and :func:`summarize`, which turns the saved runs
into the tables ``slider_crank_summary``, ``seed_holding_forces``, ``slider_crank_holding_forces``,
``slider_crank_eps_sweep`` and their ``*_timing`` companions. 000's own method, corrected, and the
hand-derived holding forces are in :mod:`study.studies.slider_crank_paper`.

What happens in the seed case (000's data, consistent initial conditions q1 = pi/6,
q1' = 0.001 rad/s; numbers from the tables ``seed_holding_forces`` and ``slider_crank_summary``): the mechanism does
not run. The slider starts sliding at x_B' = -4.6e-4 m/s (crank turning forward); the resistance
and the friction, F + f|N| = 5.5 + 0.25 * 15.51 = 9.38 N, stop it after 3.6 ms, when it has moved
0.8 micrometre and the crank 1.9e-6 rad. From then on it sticks for the whole 20 s.

What holds it: at rest the loads' torques about the crank axis (along the motion, D = [1, d12]) are
the drive M = +0.5 N m, the spring -alpha q1 = -0.0052 N m and the rod's weight -0.4330 N m (the
slider's weight acts along the guide's normal and has no component along the motion). Their sum,
+0.0618 N m, pushes the slider towards -x through the lever dx_B/dq1 = -0.457 m. To hold it the
guide supplies f_req = +0.135 N, 1.4 % of its static limit of 9.38 N. The spring is negligible:
the drive and the rod's weight nearly cancel. Breaking away at this pose needs M = 4.77 N m
(:func:`study.studies.slider_crank_paper.breakaway_torque`). ``slip_then_stick`` uses M = 5 N m: the slider slides, slows as the crank's
lever on it grows, and sticks at t = 4.43 s. ``sustained_sliding`` uses M = 10 N m: it never sticks,
and it reverses only at the crank's dead centres, where it cannot be held.

The paper's figures show motion over 20 s, which a correct model cannot produce from these data.
The printed initial state is also 5.2 m off the guide (see the ``printed_*`` runs).

The printed state cannot be used as is: post-step projection jumps to the nearest assembled
configuration (minimum norm: a different crank angle); Baumgarte pulls the slider onto the guide
over ~1 s with a normal force ~100 times the physical one, hence a friction force ~40 times too large
and a spurious dissipation; the two end in different rest positions, neither the consistent run's.

Where the exact treatment sticks, the other two do not. ``regularized`` creeps at
v ~ eps atanh(|f_req| / limit); in ``slip_then_stick``, where f_req is close to the limit, the crank
keeps turning (the ``slider_crank_eps_sweep`` table gives the creep for each eps). ``sign`` (RK4)
neither sticks nor creeps smoothly: its stages straddle v = 0, so the velocity chatters or settles
on a spurious fixed point of the step map (v ~ h a). Its friction work is then not the energy the
model loses: the energy-balance error is about the whole reported dissipation.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.compare import common_samples, max_deviation
from study.params import load_parameters
from study.pipeline import Case, find, find_one
from study.results import SimulationResult
from study.studies.slider_crank_paper import (breakaway_readings, breakaway_torque, holding_forces,
                                               slider_position, static_resistance_fraction)

Array = np.ndarray


# --- the study's tables (cases: reference/cases/slider_crank.toml) ---------------------------------
REPORT_TIMES = (1.0, 5.0, 10.0, 20.0)
Load = Callable[[Case], SimulationResult]


def phase_times(result: SimulationResult) -> dict:
    """Stick onsets, slip onsets (leaving stick) and direction reversals of the guide contact.

    Exact treatment: the located transitions. Regularized and sign: apparent stick |v_t| <= eps on
    the output samples (no reversals are reported).
    """
    if result.meta.get("friction") == "exact":
        tr = [x for x in result.stats.get("friction_transitions", []) if x.get("contact")]
        stick = [x["t"] for x in tr if x["to"] == "stick"]
        slip = [x["t"] for x in tr if x["from"] == "stick"]
        rev = [x["t"] for x in tr if x["from"] != "stick" and x["to"] != "stick"]
        first = result.stats["friction_transitions"][0]["initial"]["guide"]
        final = tr[-1]["to"] if tr else first
    else:
        flag = result.forces["stick_guide"]
        change = np.flatnonzero(np.diff(flag) != 0) + 1
        stick = [float(result.t[i]) for i in change if flag[i] > 0]
        slip = [float(result.t[i]) for i in change if flag[i] == 0]
        rev = []
        first = "stick" if flag[0] > 0 else "slip"
        final = "stick" if flag[-1] > 0 else "slip"
    return {"initial_phase": first, "final_phase": final, "stick_times": stick, "slip_times": slip,
            "reversals": rev}


def stick_intervals(result: SimulationResult) -> list[tuple[float, float]]:
    """(start, end) of every stick phase [s]: located ones (exact) or apparent ones (others)."""
    if result.meta.get("friction") == "exact":
        tr = [x for x in result.stats.get("friction_transitions", []) if x.get("contact")]
        phase = result.stats["friction_transitions"][0]["initial"]["guide"]
        out, start = [], float(result.t[0]) if phase == "stick" else None
        for x in tr:
            if x["to"] == "stick":
                start = x["t"]
            elif x["from"] == "stick" and start is not None:
                out.append((start, x["t"]))
                start = None
        if start is not None:
            out.append((start, float(result.t[-1])))
        return out
    flag = np.asarray(result.forces["stick_guide"]) > 0
    edges = np.flatnonzero(np.diff(np.concatenate([[0], flag.astype(int), [0]])))
    return [(float(result.t[a]), float(result.t[min(b, len(result.t) - 1)])) for a, b in zip(edges[::2], edges[1::2])]


def _fmt(times, limit=12):
    shown = ";".join(f"{t:.6g}" for t in times[:limit])
    return shown + (f";...(+{len(times) - limit})" if len(times) > limit else "")


def _at(result: SimulationResult, t: float, values: Array) -> float:
    i = int(np.argmin(np.abs(result.t - t)))
    return float(values[i]) if abs(result.t[i] - t) < 1e-9 else float("nan")


def summary_row(name: str, result: SimulationResult, **labels) -> dict:
    """One row of ``slider_crank_summary``: phases, q1 / friction / normal force at REPORT_TIMES,
    dissipation, energy balance, constraint violation and (deterministic) work counts."""
    phases = phase_times(result)
    row = {"case": name, **labels, "initial_phase": phases["initial_phase"],
           "n_stick": len(phases["stick_times"]), "stick_times": _fmt(phases["stick_times"]),
           "n_slip_from_stick": len(phases["slip_times"]), "slip_times": _fmt(phases["slip_times"]),
           "n_reversals": len(phases["reversals"]), "reversal_times": _fmt(phases["reversals"])}
    for tr in REPORT_TIMES:
        row[f"q1_t{tr:g}"] = _at(result, tr, result.q[:, 0])
        row[f"friction_t{tr:g}"] = _at(result, tr, result.forces["friction_guide"])
        row[f"normal_t{tr:g}"] = _at(result, tr, result.forces["normal_guide"])
    s = result.summary()
    row.update({
        "final_phase": phases["final_phase"],
        "max_abs_normal": float(np.abs(result.forces["normal_guide"]).max()),
        "max_abs_friction": float(np.abs(result.forces["friction_guide"]).max()),
        "dissipated_energy": float(-result.energies["work_friction_guide"][-1]),
        "energy_balance_error": s["energy_error"],
        "max_abs_phi": s["max_abs_phi"],
        "nfev": result.stats.get("nfev"),
        "steps": result.stats.get("steps"),
        "events": result.stats.get("events"),
    })
    return row


def _describe(case: Case) -> dict:
    o = case.kwargs
    v = load_parameters(case.mechanism, case.variant).values
    return {"variant": case.variant, "treatment": o["friction"], "initial": o.get("initial", "consistent"),
            "method": o.get("method", "none"), "integrator": o["integrator"],
            "resistance_reading": o.get("resistance_reading", v.resistance_reading)}


def _case_name(case: Case) -> str:
    if case.group == "printed":
        return f"printed_{case.kwargs['method']}_{case.kwargs['friction']}"
    if case.group == "resistance_sliding_only":
        return f"{case.variant}_{case.kwargs['friction']}_sliding_only"
    return f"{case.variant}_{case.kwargs['friction']}"


def holding_row(case: Case, result: SimulationResult) -> dict:
    """What holds a run that ends stuck: the static balance at its final state, and the breakaway torque."""
    ps = load_parameters(case.mechanism, case.variant)
    v = ps.values
    reading = case.kwargs.get("resistance_reading", v.resistance_reading)
    i = len(result.t) - 1
    q = result.q[i]
    row = {"case": _case_name(case), "variant": case.variant, "t": float(result.t[i]), "q1": float(q[0]),
           "q2": float(q[1]), "M": v.M}
    row.update(holding_forces(v, q))
    normal = float(result.forces["normal_guide"][i])
    row.update({"normal_N": normal, "friction_solver": float(result.forces["friction_guide"][i]),
                "static_limit": float(static_resistance_fraction(v, reading) * v.F + v.mu * abs(normal))})
    row["holding_fraction"] = abs(row["f_required"]) / row["static_limit"]
    row["resistance_reading"] = reading
    row.update(breakaway_torque(v, q, reading))
    x = slider_position(v, result.q[[0, i]])
    row["slide_distance"] = float(abs(x[1] - x[0]))
    row["crank_rotation"] = float(result.q[i, 0] - result.q[0, 0])
    return row


def eps_row(case: Case, result: SimulationResult, exact_case: Case, exact: SimulationResult) -> dict:
    """One row of ``slider_crank_eps_sweep``: a regularized run against the exact run of its variant.

    creep: where the exact run ends stuck (from its last stick onset t_s to t_end), the crank angle
    the regularized run still turns, q1(t_end) - q1(t_s) [rad] (t_s rounded up to the next sample),
    and that angle per second.
    """
    v = load_parameters(case.mechanism, case.variant).values
    ia, ib = common_samples(result, exact)
    dq1 = result.q[ia, 0] - exact.q[ib, 0]
    xb = slider_position(v, result.q[ia]) - slider_position(v, exact.q[ib])
    phases = phase_times(exact)
    row = {"variant": case.variant, "friction_eps": case.kwargs["friction_eps"],
           "friction_sgn": case.kwargs["friction_sgn"], "exact_final_phase": phases["final_phase"],
           "max_abs_dq1_vs_exact": float(np.abs(dq1).max()),
           "final_dq1_vs_exact": float(dq1[-1]),
           "max_abs_dxB_vs_exact": float(np.abs(xb).max()),
           "max_abs_dfriction_vs_exact": max_deviation(result, exact, "friction_guide"),
           "max_abs_dnormal_vs_exact": max_deviation(result, exact, "normal_guide")}
    if phases["final_phase"] == "stick" and phases["stick_times"]:
        t_s = phases["stick_times"][-1]
        i = int(np.searchsorted(result.t, t_s - 1e-12))
        creep = float(result.q[-1, 0] - result.q[i, 0])
        row.update({"exact_stick_from": t_s, "creep_q1": creep, "creep_rate_q1": creep / (result.t[-1] - result.t[i])})
    else:
        row.update({"exact_stick_from": float("nan"), "creep_q1": float("nan"), "creep_rate_q1": float("nan")})
    d_reg = -result.energies["work_friction_guide"][-1]
    d_ex = -exact.energies["work_friction_guide"][-1]
    row.update({"dissipated_energy": float(d_reg), "dissipated_energy_exact": float(d_ex),
                "energy_balance_error": result.summary()["energy_error"],
                "nfev": result.stats.get("nfev"), "steps": result.stats.get("steps"),
                "nfev_exact": exact.stats.get("nfev")})
    return row


def eps_sweep_cases(cases: Sequence[Case]) -> list[Case]:
    """The regularized runs of the eps sweep: the group 'eps_sweep' plus the 'treatments' run of each
    of its variants (eps = 1e-3), by variant in list order, then eps from wide to narrow."""
    sweep = find(cases, group="eps_sweep")
    variants = list(dict.fromkeys(c.variant for c in sweep))
    out = []
    for variant in variants:
        runs = find(sweep, variant=variant) + find(cases, group="treatments", variant=variant, friction="regularized")
        out += sorted(runs, key=lambda c: -c.kwargs["friction_eps"])
    return out


def summarize(cases: Sequence[Case], load: Load) -> dict[str, pd.DataFrame]:
    """The study's tables from its saved runs (rows in case-list order).

    - ``slider_crank_summary``: one row per run of the groups 'treatments', 'alpha_damping' and
      'printed' (:func:`summary_row`); ``slider_crank_timing``: their CPU seconds.
    - ``slider_crank_holding_forces``: :func:`holding_row` for every exact run from the consistent
      state that ends stuck; ``seed_holding_forces``: its seed row.
    - ``slider_crank_eps_sweep``: :func:`eps_row` for each run of the group 'eps_sweep';
      ``slider_crank_eps_sweep_timing``: their CPU seconds and those of the exact runs.
    """
    rows, timing, held = [], [], []
    for case in cases:
        if case.group not in ("treatments", "alpha_damping", "printed", "resistance_sliding_only"):
            continue
        result = load(case)
        name = _case_name(case)
        rows.append(summary_row(name, result, **_describe(case)))
        timing.append({"case": name, "cpu_seconds": result.stats.get("cpu_seconds"),
                       "nfev": result.stats.get("nfev")})
        if (case.kwargs["friction"] == "exact" and case.group != "printed"
                and phase_times(result)["final_phase"] == "stick"):
            held.append(holding_row(case, result))
    tables = {"slider_crank_summary": pd.DataFrame(rows), "slider_crank_timing": pd.DataFrame(timing)}
    if held:
        held_table = pd.DataFrame(held)
        tables["slider_crank_holding_forces"] = held_table
        seed = held_table[(held_table["variant"] == "seed") & (held_table["case"] == "seed_exact")]
        tables["seed_holding_forces"] = seed.reset_index(drop=True)
        seed_case = find_one(cases, group="treatments", variant="seed", friction="exact")
        seed_pose = load(seed_case).q[-1]
        tables["seed_breakaway_readings"] = breakaway_readings(load_parameters("slider_crank", "seed").values, seed_pose)

    eps_rows, eps_timing = [], []
    for case in eps_sweep_cases(cases):
        exact_case = find_one(cases, group="treatments", variant=case.variant, friction="exact")
        result, exact = load(case), load(exact_case)
        eps_rows.append(eps_row(case, result, exact_case, exact))
        eps_timing.append({"variant": case.variant, "friction_eps": case.kwargs["friction_eps"],
                           "cpu_seconds": result.stats.get("cpu_seconds"),
                           "cpu_seconds_exact": exact.stats.get("cpu_seconds"), "nfev": result.stats.get("nfev")})
    if eps_rows:
        tables["slider_crank_eps_sweep"] = pd.DataFrame(eps_rows)
        tables["slider_crank_eps_sweep_timing"] = pd.DataFrame(eps_timing)
    return tables
