"""Report section "Benchmarks beyond the papers": Andrews' squeezer, the IFToMM A01 pendulum and A02 N-four-bar,
and Exudyn's slider-crank and Bricard test models.

The section opens with one overview table of every benchmark by its own criterion
(:mod:`study.report.sections.benchmark_overview`). The Andrews subsection is :mod:`study.report.sections.andrews`.
The N-four-bar subsection reads the tables ``singular_four_bar_runs`` and ``singular_four_bar_x_B0`` (written by
:func:`study.studies.singular.summarize`) and, if present, ``singular_four_bar_scaling`` (written by
``python -m study.studies.n_four_bar_scaling``); A01 reads ``a01_runs`` and ``a01_timing``
(:func:`study.studies.a01.summarize`); the peer test models' subsection reads ``exudyn_test_models`` and
``exudyn_bricard_test_model`` (:func:`study.studies.peer_models.summarize`); never a run. The x_B0 figure is drawn from the saved N = 2 runs at
their full output rate.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from study.report.context import ReportContext
from study.report.sections import andrews, benchmark_overview
from study.reference_data import tolerance, values
from study.reference_solutions import richardson_second_order
from study.params import load_parameters
from study.report.render import fmt_int, fmt_number, md_table
from study.studies import singular

HEADING = "## Benchmarks beyond the papers"
REFERENCE_SAMPLES = 4001  # the exact motion drawn every 2.5 ms over 10 s: smooth at a crank period of about 1 s


INDEX3 = "ALI3P (index-3 augmented Lagrangian)"


def _runs_table(runs: pd.DataFrame) -> str:
    header = ["N", "engine", "method", "setting", "singular positions", "stopped at [s]", "error",
              "energy drift max|E − E0| [J]", "relative to E0", "largest change of E between samples [J]",
              "its distance from a crossing [s]", "solves at the iteration limit", "max|Φ|", "x_B0(t_end) [m]",
              "max|x_B0 − reference| [m]", "max|ẋ_B0 − reference| [m/s]", "A02 verdict", "CPU [s]"]
    rows = [[fmt_int(r.N), r.engine, r.method, r.setting, "**passed**" if str(r.passed) == "True" else "**stopped**",
             fmt_number(r.stopped_at_s, 6), r.error if isinstance(r.error, str) else "",
             fmt_number(r.energy_drift_J), fmt_number(r.energy_drift_relative), fmt_number(r.largest_energy_step_J, 2),
             fmt_number(r.largest_energy_step_to_crossing_s, 2), fmt_int(r.solves_at_iteration_limit),
             fmt_number(r.max_abs_phi, 2), fmt_number(r.x_B0_end_m, 4), fmt_number(r.x_B0_max_error_m, 3),
             fmt_number(r.vx_B0_max_error_m_s, 3),
             f"**{r.a02_verdict}**" if r.a02_verdict == "high precision" else r.a02_verdict, fmt_number(r.cpu_s, 2)]
            for r in runs.itertuples(index=False)]
    return md_table(header, rows, [True, False, False, False, False, True, False, True, True, True, True, True, True,
                                   True, True, True, False, True])


def _x_b0_figure(ctx: ReportContext) -> str:
    """x of B0 at every saved output sample of every N = 2 run that passed, over the exact motion (legend below)."""
    fig = Figure(figsize=(8.6, 6.2), layout="constrained")
    ax = fig.add_subplot()
    runs = [c for c in ctx.cases("singular") if load_parameters(c.mechanism, c.variant).values.N == 2 and ctx.has(c)]
    for case in runs:
        r = ctx.load(case)
        ax.plot(r.t, singular.b0(case, r)[0], lw=1.0, label=singular.run_label(case))
    if runs:
        t = np.linspace(0.0, runs[0].t_end, REFERENCE_SAMPLES)
        ax.plot(t, singular.reference_b0(runs[0], t)[0], color="black", linestyle="--", linewidth=1.2,
                label="reference (exact motion)", zorder=5)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("x of B0 [m]")
    ax.set_title("IFToMM A02, N = 2: x of B0 at every output sample of every run that passed", fontsize=10)
    ax.grid(alpha=0.3)
    fig.legend(loc="outside lower center", ncols=2, fontsize=7, frameon=False)
    return ctx.figure(fig, "singular_four_bar_x_B0", "x of B0 against time for every run that passed")


def section(ctx: ReportContext) -> list[str]:
    """Both benchmarks, each in its own subsection."""
    return ([HEADING, "", "Problems the multibody community uses to judge formulations, run through the same "
             "description → in-house + Exudyn path as the papers' mechanisms, each judged by its own criterion "
             "against its own reference: Andrews' squeezer (a published solution), the IFToMM A01 pendulum over a long "
             "horizon and A02 N-four-bar through rank-deficient positions (exact motions), and two test models "
             "of Exudyn's own (their published values).", ""]
            + benchmark_overview.overview(ctx) + andrews.subsection(ctx) + _a01(ctx) + _n_four_bar(ctx)
            + _peer_models(ctx) + _bricard_peer(ctx))


def _a01(ctx: ReportContext) -> list[str]:
    """IFToMM A01 by its own criterion (table ``a01_runs``, written by :func:`study.studies.a01.summarize`)."""
    runs, timing = ctx.table("a01_runs"), ctx.table("a01_timing")
    if runs is None:
        return []
    keys = ["engine", "method", "setting"]
    if timing is not None:
        runs = runs.merge(timing, on=keys, how="left")
    rows = [[r["engine"], r["method"], r["setting"], fmt_int(r["t_end_s"]), fmt_number(r["x_max_error_m"]),
             fmt_number(r["y_max_error_m"]), f"**{r['a01_verdict']}**" + (f" ({r['error']})" if r["error"] else ""),
             fmt_number(r["energy_drift_J"]), fmt_number(r["max_abs_phi"]), fmt_number(r.get("cpu_s", np.nan))]
            for _, r in runs.fillna({"error": ""}).iterrows()]
    high, low = (tolerance(k, table="benchmarks") for k in ("a01_high_precision", "a01_low_precision"))
    return ["### The simple pendulum over 2000 s (IFToMM benchmark A01)", "",
            "A lumped mass of 1 kg on a massless link of 1 m under gravity 9.81 N/kg, released at rest on the "
            "horizontal, in Cartesian coordinates: the mass is a body that does not turn, placed by its own x, y, and "
            "the link a distance constraint (`study/mechanisms/a01_pendulum.py`). The benchmark's criterion: the "
            f"largest error of x and y of P1 over 4000 output steps of 2000 s (about 850 swings), at most {high:g} m "
            f"for high precision and {low:g} m for low precision. The reference is the exact motion, Jacobi's "
            "elliptic sine with modulus sin 45° (`study/reference_solutions.py`; it matches an independent "
            "integration of the pendulum's angle to 3e-12 m over 20 s, `tests/test_reference_solutions.py`). "
            "Exudyn ran over the first 20 s only (2000 s at these steps costs 30–60 s of CPU), so its errors are "
            "not the benchmark's.", "",
            md_table(["engine", "method", "setting", "horizon [s]", "max|x − x_ref| [m]", "max|y − y_ref| [m]",
                      "verdict", "energy drift [J]", "max|Φ|", "CPU [s]"], rows,
                     [False, False, False, True, True, True, False, True, True, True]), ""]


def _peer_models(ctx: ReportContext) -> list[str]:
    """Exudyn's slider-crank test model against the value its file publishes (table ``exudyn_test_models``)."""
    table, verdict = ctx.table("exudyn_test_models"), ctx.table("exudyn_test_models_verdict")
    if table is None or verdict is None:
        return []
    rows = [[r["source"], *(fmt_number(r[c], 6) for c in ("x_slider_fixed_m", "x_slider_floating_m",
                                                           "sum_abs_x_slider_m")), fmt_number(r["minus_published_m"])]
            for _, r in table.iterrows()]
    return ["### A peer's test model: Exudyn's slider-crank on a floating frame", "",
            "Exudyn's test suite checks its solver with a slider-crank (`sliderCrankFloatingTest`): crank 0.1 m, "
            "rod 0.3 m, slider 0.4 kg, driven from rest by 0.1 N m, once on ground and once on a frame held by "
            "coordinate spring-dampers (5000 N/m, 50 N s/m); the file publishes |x_slider(0.3 s)| of the two cases "
            "summed, from its index-2 solver at h = 6e-5 s. Both cases are descriptions here "
            "(`study/mechanisms/exudyn_slider_crank.py`, the floating frame a free body), run in-house and "
            "through the generated Exudyn model at the published step and at half of it.", "",
            md_table(["source", "x_slider(0.3 s), fixed frame [m]", "floating frame [m]", "sum of |x| [m]",
                      "− published [m]"], rows, [False, True, True, True, True]), "",
            _agreement(verdict.iloc[0], "exudyn_slider_crank_agreement_factor", "_m", " m") + ".", ""]


def _bricard_peer(ctx: ReportContext) -> list[str]:
    """Exudyn's Bricard test model against the value its file publishes (table ``exudyn_bricard_test_model``)."""
    table, verdict = ctx.table("exudyn_bricard_test_model"), ctx.table("exudyn_bricard_test_model_verdict")
    if table is None or verdict is None:
        return []
    rows = [[r["source"], fmt_number(r["ode2_norm"], 6), fmt_int(r["dof"]), fmt_int(r["redundant_constraints"]),
             fmt_number(r["lowest_eigenvalue"]), fmt_number(r["test_value"], 6), fmt_number(r["minus_published"])]
            for _, r in table.iterrows()]
    return ["### A peer's test model: Exudyn's Bricard mechanism", "",
            "Exudyn's test suite also checks its solver on Bricard's mechanism (`TestModels/bricardMechanism.py`): "
            "IFToMM A04's five rods of 1 kg (cuboids 1 × 0.1 × 0.1 m) in a loop of six revolute joints, one row "
            "redundant, from rest under gravity for 1 s. The file publishes the norm of Exudyn's coordinates at 1 s "
            "(each rod's node, at its first joint, displaced from its start, and its Euler parameters' change) plus "
            "the degrees of freedom, the redundant constraints and the lowest eigenvalue, from generalized-α "
            "(index 3) at h = 1e-3 s. The mechanism is a description here in the file's own body frames "
            "(`study/spatial/bricard_peer.py`), its counts and eigenvalue the description's; it runs in-house "
            "(augmented Lagrangian) and through the generated Exudyn model at the published step and at half of "
            "it.", "",
            md_table(["source", "‖q(1 s)‖", "dof", "redundant", "lowest eigenvalue", "published quantity",
                      "− published"], rows, [False, True, True, True, True, True, True]), "",
            _agreement(verdict.iloc[0], "exudyn_bricard_agreement_factor", "", "") + ", the in-house "
            "run's own accuracy (its augmented Lagrangian solves to about 1e-9).", ""]


def _agreement(v: pd.Series, factor_key: str, suffix: str, unit: str) -> str:
    """The verdict row of a test model in words (its keys end in ``suffix``, its values are in ``unit``), without
    the closing period."""
    factor = tolerance(factor_key, table="benchmarks")
    return (f"The generated Exudyn model at the published settings reproduces the published value to "
            f"{fmt_number(abs(v['exudyn_published_step_minus_published' + suffix]))}{unit}. Richardson's rule puts "
            f"that run's own discretization error at {fmt_number(v['published_run_error_estimate' + suffix])}{unit}, "
            f"and the in-house reference lies {fmt_number(abs(v['inhouse_minus_published' + suffix]))}{unit} from the "
            f"published value: **{'within' if str(v['agrees']) == 'True' else 'not within'} {factor:g} times that "
            f"error** (`reference/benchmarks.toml` [{factor_key}]); the extrapolated Exudyn value and the in-house "
            f"reference differ by {fmt_number(abs(v['extrapolated_minus_inhouse' + suffix]))}{unit}")


def _original_size(n40: pd.DataFrame) -> list[str]:
    """N = 40 over 20 s, in-house and Exudyn side by side: verdict, CPU, and the CPU ratio of the runs that finished."""
    if not len(n40):
        return []

    def run(r) -> str:
        name = f"{'in-house' if r.engine == 'inhouse' else 'Exudyn'} {r.method}, {r.setting}"
        if str(r.passed) != "True":
            where = f" at t = {fmt_number(r.stopped_at_s, 4)} s" if np.isfinite(r.stopped_at_s) else ""
            return f"{name}: stops{where} ({r.error})"
        return (f"{name}: {fmt_number(r.x_B0_max_error_m, 3)} m, {fmt_number(r.vx_B0_max_error_m_s, 3)} m/s "
                f"(**{r.a02_verdict}**), CPU {fmt_number(r.cpu_s, 3)} s")

    done = n40[(n40["passed"].astype(str) == "True") & n40["cpu_s"].notna()]
    ratio = ""
    if {"inhouse", "exudyn"} <= set(done["engine"]):
        best = {e: done[done["engine"] == e].sort_values("cpu_s").iloc[0] for e in ("inhouse", "exudyn")}
        smaller = {e: np.sqrt(max(r.x_B0_max_error_m, r.vx_B0_max_error_m_s) / 1e-6) for e, r in best.items()}
        ratio = (f" In this run the in-house method took {fmt_number(best['inhouse'].cpu_s / best['exudyn'].cpu_s, 2)} "
                 f"times Exudyn's CPU ({best['inhouse'].a02_verdict} against {best['exudyn'].a02_verdict}). An error "
                 "of 1e-6 is not run: at both methods' order 2 it needs a step sqrt(error / 1e-6) times smaller, "
                 f"{fmt_number(smaller['inhouse'], 2)} times (in-house) and {fmt_number(smaller['exudyn'], 2)} times "
                 "(Exudyn), and about that many times the CPU.")
    return ["The benchmark's original size side by side, N = 40 over 20 s (B0 sampled every 0.05 s): "
            + "; ".join(run(r) for r in n40.itertuples(index=False)) + "." + ratio, ""]


def _four_bar_runs(ctx: ReportContext) -> pd.DataFrame | None:
    """The table ``singular_four_bar_runs`` with each run's CPU from ``singular_four_bar_timing`` (NaN without it)."""
    runs = ctx.table("singular_four_bar_runs")
    timing = ctx.table("singular_four_bar_timing")
    if runs is not None:   # CPU from timing/ (machine-dependent), matched on the run's identity
        keys = ["N", "engine", "method", "setting"]
        runs = runs.merge(timing, on=keys, how="left") if timing is not None else runs.assign(cpu_s=float("nan"))
    return runs


def _stopped_lines(stopped: pd.DataFrame) -> list[str]:
    """Where the in-house methods that need a full-rank Φ_q stop."""
    inhouse_stop = stopped[stopped["engine"] == "inhouse"]
    if not len(inhouse_stop):
        return []
    return [f"Every in-house method that needs a full-rank Φ_q ({', '.join(sorted(set(inhouse_stop['method'])))}) "
            f"stops at the first horizontal position, between t = {fmt_number(inhouse_stop['stopped_at_s'].min(), 6)} "
            f"and {fmt_number(inhouse_stop['stopped_at_s'].max(), 6)} s, with a SingularConfigurationError naming "
            "the time, the pose and the rank; this includes the papers' own R/D partitioning, whose Φ_v "
            "becomes singular there for every choice of dependent coordinates.", ""]


def _augmented_lagrangian_lines(passed: pd.DataFrame) -> list[str]:
    """The acceleration-level augmented Lagrangian through the crossings: its energy jumps and why."""
    al = passed[passed["method"].str.startswith("augmented_lagrangian")]
    if not len(al):
        return []
    by_setting = "; ".join(f"{fmt_number(r.energy_drift_J)} J at {r.setting} (largest change between two samples "
                           f"{fmt_number(r.largest_energy_step_J, 2)} J, {fmt_number(r.largest_energy_step_to_crossing_s, 2)} s "
                           f"from a crossing; {fmt_int(r.solves_at_iteration_limit)} acceleration solves at the "
                           f"iteration limit)" for r in al.itertuples(index=False))
    al_verdicts = "; ".join(f"{r.setting}: {fmt_number(r.x_B0_max_error_m, 3)} m, "
                            f"{fmt_number(r.vx_B0_max_error_m_s, 3)} m/s (**{r.a02_verdict}**)"
                            for r in al.itertuples(index=False))
    return [f"The acceleration-level augmented Lagrangian (with post-step projection) runs through every "
            f"singular position and stays on the parallelogram branch (crank spread ≤ "
            f"{fmt_number(al['crank_spread_max_rad'].max(), 2)} rad, max|Φ| ≤ "
            f"{fmt_number(al['max_abs_phi'].max(), 2)}), but it changes the energy in jumps, each within one "
            f"output sample (0.01 s) of a crossing: {by_setting}. The drift does not shrink as the tolerance "
            "tightens. Why: the method integrates the acceleration constraints Φ_q q̈ = γ only. Near a crossing "
            "N singular values σ of Φ_q go to zero. A state off the constraints by δ (the integrator's local "
            "error, and the projection's tolerance) makes these equations inconsistent by O(δ) in the "
            "directions in which the mobility jumps, and they can absorb it only by accelerations of O(δ/σ) "
            "there; the augmented Lagrangian's multiplier iteration, whose rate tends to 1 as σ → 0, stops "
            "at its limit (the solves counted above). Nothing at acceleration level pulls the motion back: "
            "the post-step projection puts q and q̇ back on the constraints, but the kinetic energy lost or "
            "gained in the crossing steps stays lost or gained. By the benchmark's criterion (errors of x_B0 "
            f"and of its rate against the exact motion, below): {al_verdicts}.", ""]


def _index3_lines(passed: pd.DataFrame) -> list[str]:
    """ALI3P through the crossings: its errors as the step is halved, their observed orders, and N = 40."""
    i3 = passed[passed["method"] == INDEX3]
    if not len(i3):
        return []
    n2, n40 = i3[i3["N"] == 2], i3[i3["N"] == 40]
    n2 = n2.assign(h=[float(x.split("=")[1]) for x in n2["setting"]]).sort_values("h", ascending=False)
    per_step = "; ".join(f"{r.setting}: {fmt_number(r.x_B0_max_error_m, 3)} m, {fmt_number(r.vx_B0_max_error_m_s, 3)} "
                         f"m/s, drift {fmt_number(r.energy_drift_J, 2)} J" for r in n2.itertuples(index=False))
    ratio = np.log(n2["h"].to_numpy()[:-1] / n2["h"].to_numpy()[1:])
    orders = {name: ", ".join(fmt_number(o, 3) for o in np.diff(-np.log(n2[column].to_numpy())) / ratio)
              for name, column in (("x", "x_B0_max_error_m"), ("rate", "vx_B0_max_error_m_s"),
                                   ("drift", "energy_drift_J"))}
    big = "; ".join(f"{r.setting}: {fmt_number(r.x_B0_max_error_m, 3)} m, {fmt_number(r.vx_B0_max_error_m_s, 3)} m/s "
                    f"(**{r.a02_verdict}**), drift "
                    f"{fmt_number(r.energy_drift_J, 2)} J, CPU {fmt_number(r.cpu_s, 2)} s"
                    for r in n40.itertuples(index=False))
    return ["The index-3 augmented Lagrangian with mass-orthogonal projections (ALI3P: Bayo and Ledesma; the "
            "trapezoidal rule with the position constraints Φ = 0 held by a penalised Newton iteration at every "
            "step, then q̇ and q̈ projected in the metric M + κ Φ_qᵀΦ_q, which stays positive-definite at the "
            "singular positions) runs through every crossing"
            + (" at the benchmark's high precision" if (i3["a02_verdict"] == "high precision").all() else
               ", judged run by run below") + ". Halving the step, "
            f"N = 2 (errors of B0's x and of its rate): {per_step}. Observed orders between successive steps: "
            f"{orders['x']} (x), {orders['rate']} (rate), {orders['drift']} (drift), against the trapezoidal "
            f"rule's 2. Steps at the Newton iteration's limit (accepted at round-off, "
            f"`study.solver.index3.ALI3P`): {', '.join(fmt_int(v) for v in n2['solves_at_iteration_limit'])}. "
            f"No energy jump stands out at the crossings: the largest change between two samples, "
            f"{fmt_number(n2['largest_energy_step_J'].max(), 2)} J, lies "
            f"{fmt_number(n2['largest_energy_step_to_crossing_s'].min(), 2)} s or more from a crossing. "
            + (f"The original size, N = 40 over 20 s (steps at the iteration limit: "
               f"{', '.join(fmt_int(v) for v in n40['solves_at_iteration_limit'])}): {big}." if len(n40) else ""),
            ""]


def _criterion_lines(passed: pd.DataFrame, traj: pd.DataFrame | None) -> list[str]:
    """The benchmark's own criterion (B0 against the exact motion) and every judged run's verdict."""
    judged = passed[passed["x_B0_max_error_m"].notna()]
    if not (len(judged) and traj is not None and "reference (exact motion)" in traj):
        return []
    end = traj.iloc[-1]
    extrapolated = richardson_second_order(*(values(f"a02_exudyn_b0_10s_{h}", table="benchmarks")
                                             for h in ("h2_5e-4", "h1_25e-4")))[0]
    errors = "; ".join(f"N = {r.N}, {r.method} {r.setting} ({r.engine}): {fmt_number(r.x_B0_max_error_m, 3)} m, "
                       f"{fmt_number(r.vx_B0_max_error_m_s, 3)} m/s, **{r.a02_verdict}**"
                       for r in judged.itertuples(index=False))
    return [f"The benchmark's own criterion judges the position and velocity of B0 (here along x) against the "
            f"exact motion: along the parallelogram "
            f"branch the mechanism has one degree of freedom, the cranks' angle θ, with 2aLθ'' + bg cos θ = 0 "
            f"(a = (N + 1)/6 + N/2, b = (N + 1)/2 + N), integrated to rtol 1e-13 independently of the study's "
            f"model (`study/reference_solutions.py`; it gives x_B0({fmt_number(end['t_s'])} s) = "
            f"{fmt_number(end['reference (exact motion)'], 6)} m, Exudyn's own IFToMM test model prints "
            f"{fmt_number(tolerance('a02_published_x_b0_10s', table='benchmarks'), 5)} m; the step sequence "
            f"that model lists extrapolates to x_B0 = {fmt_number(extrapolated[0], 8)} m, ẋ_B0 = "
            f"{fmt_number(extrapolated[1], 8)} m/s at 10 s, which the exact motion matches within the "
            "finest run's estimated error, `tests/test_reference_solutions.py`). High precision is "
            f"max|x_B0 − reference| and max|ẋ_B0 − reference| ≤ "
            f"{fmt_number(tolerance('a02_high_precision', table='benchmarks'))} (m, m/s), low precision ≤ "
            f"{fmt_number(tolerance('a02_low_precision', table='benchmarks'))}, here over every output "
            f"sample (0.01 s for N = 2, 0.05 s for N = 40): {errors}. The true motion is smooth: Exudyn and "
            "ALI3P follow it, and the acceleration-level method's error is made by the method at the "
            "crossings, not by the problem's conditioning. Its size depends on where the steps land around "
            "each crossing, so that method's values are one host's (measured at DOP853 rtol 1e-12: x_B0(10 s) "
            "= -0.615 m on one host, -0.117 m on another; section \"How far the numbers reproduce\").", ""]


def _exudyn_lines(passed: pd.DataFrame) -> list[str]:
    """Exudyn's solvers at N = 2 through the crossings."""
    ex = passed[(passed["engine"] == "exudyn") & (passed["N"] == 2)]
    if not len(ex):
        return []
    drift = "; ".join(f"{fmt_number(d)} J at {setting}" for setting, d in
                      ex.groupby("setting", sort=False)["energy_drift_J"].max().items())
    return [f"Exudyn's index-3 generalized-α runs through every singular position with or without "
            f"`linearSolver.ignoreSingularJacobian` (energy drift {drift}; its verdicts by the benchmark's "
            f"criterion are listed above); its index-2 (trapezoidal) solver stops.", ""]


def _scaling_lines(scaling: pd.DataFrame | None) -> list[str]:
    """Cost against the number of windows (table ``singular_four_bar_scaling``), or nothing without it."""
    if scaling is None:
        return []
    header = ["N", "derivation [s]", "derivation + code generation [s]", "one evaluation [ms]",
              "in-house CPU per simulated s", "in-house energy drift [J]", "Exudyn CPU per simulated s",
              "Exudyn energy drift [J]", "horizon [s]"]
    rows = [[fmt_int(r.N), fmt_number(r.derive_s, 2), fmt_number(r.derive_and_codegen_s, 2),
             fmt_number(1e3 * r.eval_s, 2), fmt_number(r.inhouse_cpu_per_s, 2), fmt_number(r.inhouse_drift, 2),
             fmt_number(r.exudyn_cpu_per_s, 2), fmt_number(r.exudyn_drift, 2), fmt_number(r.t_sim, 3)]
            for r in scaling.itertuples(index=False)]
    return ["Scaling with the number of windows (in-house: augmented Lagrangian + projection, DOP853 rtol 1e-8; "
            "Exudyn: index 3, h = 1e-3 s):", "", md_table(header, rows, [True] * len(header)), "",
            "CPU times are process times measured on the shared 2-core machine (`python -m "
            "study.studies.n_four_bar_scaling`, each size in a fresh process with an empty code cache), with "
            "one BLAS thread as every simulation here runs (`study.engines.runner.one_blas_thread`): from N = 40 "
            "OpenBLAS would split the augmented Lagrangian's Φ_qᵀΦ_q over two threads, whose waiting for a "
            "busy core counts as process time and made one evaluation an order of magnitude slower. "
            "The horizons hold one or two singular positions, whose neighbourhoods take most of the "
            "in-house steps, so the CPU per simulated second is not monotonic in N.", ""]


def _n_four_bar(ctx: ReportContext) -> list[str]:
    """IFToMM A02 (tables ``singular_four_bar_*``): each method through the singular positions, then the criterion."""
    lines = ["### The N-four-bar through singular positions (IFToMM benchmark A02)", "",
             "N square windows of unit links (1 m, 1 kg, gravity 9.81 N/kg along −y), started with every crank "
             "vertical and B0 moving along +x at 1 m/s (the specification's figure). Whenever the cranks lie along "
             "the ground line, rank Φ_q drops from 2N to N and the mobility jumps from 1 to N + 1; the motion "
             "passes such a position every half turn. The reduced form N = 2 over 10 s, and the benchmark's "
             "original size N = 40 over 20 s.", ""]
    runs = _four_bar_runs(ctx)
    if runs is None:
        return lines + ["The singular study has not been run (`python -m study run singular`).", ""]
    passed = runs[runs["passed"].astype(str) == "True"]
    stopped = runs[runs["passed"].astype(str) != "True"]
    lines += [_runs_table(runs), ""]
    lines += _stopped_lines(stopped) + _augmented_lagrangian_lines(passed) + _index3_lines(passed)
    lines += _original_size(runs[runs["N"] == 40])
    traj = ctx.table("singular_four_bar_x_B0")
    lines += _criterion_lines(passed, traj) + _exudyn_lines(passed)
    if traj is not None and len(traj.columns) > 1:
        lines += [_x_b0_figure(ctx), ""]
    return lines + _scaling_lines(ctx.table("singular_four_bar_scaling"))
