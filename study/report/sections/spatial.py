"""Report section: spatial mechanisms (study ``spatial``, :mod:`study.studies.spatial`).

The heavy top against the published Euler parameters and the independent minimal model; whether every stabilization
keeps the top's energy within the global-error rule (sliding mode does not); Bricard's mechanism (A04), its energy
over the benchmark's 10 s in-house and in Exudyn, both by the in-house run's rule, and the redundant row; Haug's spatial slider-crank; and the CPU of Exudyn against the
cheapest in-house run at least as accurate; the carriage with friction in its prismatic guide and its revolute axle:
the exact law's stick times and the regularized law's convergence in Exudyn. Every number is read from the study's
tables (``spatial_runs``, ``spatial_timing``, ``spatial_equal_accuracy_timing``, ``spatial_friction``,
``spatial_friction_orders``).
"""

from __future__ import annotations

import pandas as pd

from study.reference_data import tolerance
from study.report.context import ReportContext
from study.report.render import fmt_number, md_table
from study.report.sections.benchmark_overview import ENGINE
from study.studies.spatial_cases import BENCHMARK_ROLES

TITLE = "Spatial mechanisms"
LABELS = {"heavy_top": "heavy top", "bricard": "Bricard's mechanism (A04)",
          "spatial_slider_crank": "Haug's spatial slider-crank"}


def _runs(ctx: ReportContext) -> pd.DataFrame | None:
    """``spatial_runs`` with each run's CPU (``spatial_timing``) where it was saved."""
    runs, timing = ctx.table("spatial_runs"), ctx.table("spatial_timing")
    if runs is None or timing is None:
        return runs
    return runs.merge(timing, on=["mechanism", "engine", "group", "setting"], how="left")


def _run_table(rows: pd.DataFrame, columns: dict[str, str]) -> str:
    """A Markdown table of ``rows`` with the given columns (name -> header), numbers to 3 digits."""
    cells = [[fmt_number(v) if isinstance(v, float) else v for v in (r[c] for c in columns)]
             for _, r in rows.iterrows()]
    return md_table(list(columns.values()), cells)


def heavy_top(runs: pd.DataFrame) -> list[str]:
    top = runs[(runs["mechanism"] == "heavy_top") & (runs["group"] != "methods")]
    if top.empty:
        return ["No heavy-top run is saved.", ""]
    inhouse, exudyn = top[top["engine"] == "inhouse"], top[top["engine"] == "exudyn"]
    rounding = inhouse[inhouse["rounds_to_published"].astype(str) == "True"]
    lines = ["### Heavy top", "",
             "The top of Terze, Müller and Zlatar (2016) as in Exudyn's `TestModels/heavyTop.py` "
             "(`reference/spatial/heavy_top.toml`): one body on a spherical joint, spinning at 150 rad/s, over "
             "0.2 s. The criterion is the Euler parameters at 0.2 s against the independent minimal model "
             "(Euler's equations about the fixed point, written without `study.spatial`) and whether each rounds "
             "to its published digits (a MATLAB RK4 solution printed to 5 significant digits).", ""]
    if len(rounding):
        loosest = rounding.sort_values("error").iloc[-1]
        lines += [f"In-house, every run from {loosest['setting']} on rounds to every published digit "
                  f"(error {fmt_number(loosest['error'])} against the independent model)."]
    if len(exudyn):
        finest = exudyn.sort_values("error").iloc[0]
        rounds = "rounds" if str(finest["rounds_to_published"]) == "True" else "does not round"
        lines += [f"Exudyn's most accurate run ({finest['setting']}) is {fmt_number(finest['error'])} from the "
                  f"independent model and {fmt_number(finest['published_distance'])} from the published values: it "
                  f"{rounds} to every published digit."]
    return lines + ["", _run_table(top, {"engine": "engine", "setting": "setting",
                                         "error": "max abs(p − p_independent)",
                                         "published_distance": "max abs(p − p_published)",
                                         "rounds_to_published": "rounds to published", "energy_drift_J": "ΔE [J]",
                                         "cpu_s": "CPU [s]"}), ""]


def sliding_mode_energy(runs: pd.DataFrame) -> list[str]:
    methods = runs[(runs["mechanism"] == "heavy_top") & (runs["group"] == "methods")]
    if methods.empty:
        return []
    lines = ["### The top's energy under each stabilization", "",
             "Every stabilization at rtol = 1e-12 (DOP853) against the global-error rule applied to the energy, "
             "max abs(E − E(0)) ≤ energy_drift_factor × rtol × max K (`reference/tolerances.toml`):", ""]
    over = methods[methods["drift_over_bound"] > 1.0]
    for _, r in over.iterrows():
        lines += [f"**{r['setting']} does not conserve the top's energy to the bound**: drift "
                  f"{fmt_number(r['energy_drift_J'])} J, {fmt_number(r['drift_over_bound'], 2)} × its bound "
                  f"{fmt_number(r['energy_bound_J'])} J, while its Euler parameters are still "
                  f"{fmt_number(r['error'])} from the independent model. Its correction, a saturated sign of the "
                  f"constraint velocities' surface, does work whenever that velocity is not exactly zero.", ""]
    within = methods[methods["drift_over_bound"] <= 1.0]
    if len(within):
        lines += [f"The others stay within: at most {fmt_number(within['drift_over_bound'].max(), 2)} of the bound.",
                  ""]
    return lines + [_run_table(methods, {"setting": "setting", "error": "max abs(p − p_independent)",
                                         "energy_drift_J": "ΔE [J]", "energy_bound_J": "bound [J]",
                                         "drift_over_bound": "ΔE / bound", "max_abs_phi": "max abs(Φ)"}), ""]


def bricard(runs: pd.DataFrame) -> list[str]:
    rows = runs[runs["mechanism"] == "bricard"]
    if rows.empty:
        return []
    lines = ["### Bricard's mechanism (IFToMM A04)", "",
             "Five rods in a loop of six revolute joints: Grübler's count gives 0 degrees of freedom, the axes leave "
             "1, so one of the 30 joint rows depends on the others at every configuration. The description declares "
             "it; the in-house runs use the augmented Lagrangian, the one acceleration solver defined for a "
             "rank-deficient Φ_q, and **the joint reactions are then not unique** (the result's meta says so); "
             "Exudyn runs the same description with its own joints. The library's P3 trajectory was not available "
             "to this study: the runs are compared with the finest in-house run on the bodies' centres.", ""]
    verdicts = [verdict(r) if r["group"] in BENCHMARK_ROLES else "" for _, r in rows.iterrows()]
    return lines + bricard_energy(rows) + [
        _run_table(rows.assign(verdict=verdicts), {
            "engine": "engine", "setting": "setting", "t_end_s": "t_end [s]", "error": "max abs(r − r_ref) [m]",
            "energy_drift_J": "ΔE [J]", "energy_bound_J": "bound [J]", "drift_over_bound": "ΔE / bound",
            "verdict": "energy rule", "cpu_s": "CPU [s]"}), ""]


def verdict(row: pd.Series, bold: bool = False) -> str:
    """A benchmark run's verdict by the energy rule: 'within' or 'above' its bound."""
    return "within" if row["drift_over_bound"] <= 1.0 else ("**above**" if bold else "above")


def bricard_energy(rows: pd.DataFrame) -> list[str]:
    """The energy over the benchmark's horizon, in-house and in Exudyn, each against the in-house run's rule."""
    bench = rows[rows["group"].isin(BENCHMARK_ROLES)]
    if bench.empty:
        return []
    lines = [f"Over the benchmark's {fmt_number(bench['t_end_s'].max())} s each run is judged by the rule of the "
             "in-house run, max abs(E − E(0)) ≤ energy_drift_factor × rtol × max K over the output samples, with "
             "the in-house run's rtol (the library's energy limit was not available to this study) and the run's own "
             "max K; Exudyn's step is chosen for the rule (`reference/spatial/bricard.toml` [exudyn_energy_step]: "
             "its energy error is second order in h and returns towards zero, it does not accumulate):", ""]
    for _, r in bench.iterrows():
        cpu = f", in {fmt_number(r['cpu_s'])} s of CPU" if "cpu_s" in r and pd.notna(r["cpu_s"]) else ""
        lines += [f"- {ENGINE[r['engine']]} ({r['setting']}): max abs(E − E(0)) = "
                  f"{fmt_number(r['energy_drift_J'])} J, {fmt_number(r['drift_over_bound'], 2)} of its bound "
                  f"{fmt_number(r['energy_bound_J'])} J: {verdict(r, bold=True)} the rule{cpu}."]
    return lines + [""]


def slider_crank(runs: pd.DataFrame) -> list[str]:
    rows = runs[runs["mechanism"] == "spatial_slider_crank"]
    if rows.empty:
        return []
    return ["### Haug's spatial slider-crank", "",
            "The description of the user's example `examples/spatial_slider_crank/` (the study's copy: "
            "`study/spatial/slider_crank.py`; crank on a revolute joint about x, slider on a "
            "prismatic joint along x, coupler on a spherical and a universal joint; 21 coordinates, 20 rows) over "
            "one turn of the crank, 1 s, against the finest in-house run.", "",
            _run_table(rows, {"engine": "engine", "setting": "setting", "error": "max abs(r − r_ref) [m]",
                              "energy_drift_J": "ΔE [J]", "max_abs_phi": "max abs(Φ)", "cpu_s": "CPU [s]"}), ""]


def _orders_sentence(orders: pd.DataFrame) -> str:
    """Which quantities converge at order >= min_order (the range of their orders), which sit at their floor and
    which fall short."""
    parts = []
    for verdict, text in (("order >= min_order", "observed orders {lo} to {hi}"),
                          ("at floor", "no discretization error (every error at most its floor)"),
                          ("below min_order", "**below min_order**")):
        rows = orders[orders["verdict"] == verdict]
        if len(rows):
            names = ", ".join(dict.fromkeys(rows["quantity"]))
            lo, hi = fmt_number(rows["order"].min(), 3), fmt_number(rows["order"].max(), 3)
            parts.append(f"{names}: {text.format(lo=lo, hi=hi)}")
    return "; ".join(parts)


def _orders_table(orders: pd.DataFrame) -> str:
    """One row per solver and quantity: the errors from the coarsest step down, the orders, the verdict."""
    cells = []
    for (solver, quantity), rows in orders.groupby(["solver", "quantity"], sort=False):
        rows = rows.sort_values("h", ascending=False)
        cells.append([solver, quantity, ", ".join(fmt_number(e) for e in rows["max_abs_diff"]),
                      ", ".join(fmt_number(o, 3) for o in rows["order"].iloc[1:]), rows["verdict"].iloc[0]])
    return md_table(["solver", "quantity", "max abs(Exudyn − in-house), h to h/4", "orders", "verdict"], cells)


def joint_friction(ctx: ReportContext, timing: pd.DataFrame | None) -> list[str]:
    runs, orders = ctx.table("spatial_friction"), ctx.table("spatial_friction_orders")
    if runs is None or runs.empty:
        return []
    if timing is not None:
        runs = runs.merge(timing, on=["mechanism", "engine", "group", "setting"], how="left")
    lines = ["### Friction in spatial joints", "",
             "The carriage of `study/spatial/friction_carriage.py`: a carriage on an inclined prismatic guide "
             "carrying a wheel on a revolute axle, Coulomb friction in both (the guide's normal force the 2-vector of "
             "its two transverse rows, the axle's the transverse reaction; "
             "`reference/spatial/friction_carriage.toml`).",
             ""]
    for _, r in runs[runs["law"] == "exact"].iterrows():
        events = ", ".join(f"{j} at {fmt_number(float(t), 7)} s" for j, t in
                           zip(str(r["stuck_joints"]).split(";"), str(r["stick_times"]).split(";")) if j)
        lines += [f"The exact law in-house ({r['setting']}, {fmt_number(r['t_end'])} s) sticks {events}; its energy "
                  f"balance with the friction's work closes to {fmt_number(r['energy_balance_error'])} J "
                  f"({fmt_number(r['dissipated_J'])} J dissipated).", ""]
    reference = runs[runs["group"] == "friction_reference"]
    if orders is not None and len(orders) and len(reference):
        ref = reference.iloc[0]
        for solver, rows in orders.groupby("solver"):
            lines += [f"The regularized law ({ref['law'].partition(' ')[2]}, Exudyn's only one, which never sticks: "
                      f"the carriage slides back through the band) over {fmt_number(ref['t_end'])} s, Exudyn {solver} "
                      f"at h = "
                      f"{', '.join(fmt_number(h) for h in sorted(set(rows['h']), reverse=True))} s against the "
                      f"in-house run ({ref['setting']}): {_orders_sentence(rows)}. min_order = "
                      f"{fmt_number(tolerance('min_order', 'cross_validation'))} (cross_validation.toml); for the "
                      f"energy balance the error is Exudyn's own balance error.", ""]
    columns = {"engine": "engine", "setting": "setting", "law": "law", "t_end": "t_end [s]",
               "energy_balance_error": "energy balance error [J]", "dissipated_J": "dissipated by friction [J]"}
    if "cpu_s" in runs:
        columns["cpu_s"] = "CPU [s]"
    lines += [_run_table(runs, columns), ""]
    if orders is not None and len(orders):
        lines += [_orders_table(orders), ""]
    return lines


def equal_accuracy(ctx: ReportContext) -> list[str]:
    table = ctx.table("spatial_equal_accuracy_timing")
    if table is None or table.empty:
        return []
    lines = ["### CPU against Exudyn at equal accuracy", "",
             "For each Exudyn run, the cheapest in-house run (reference path, Python) of the same mechanism whose "
             "error by the criterion above is at most Exudyn's, and the ratio of their CPU seconds (timing: this "
             "machine's, `timing/`).", ""]
    cells = [[LABELS.get(r["mechanism"], r["mechanism"]), r["exudyn"], fmt_number(r["exudyn_error"]),
              fmt_number(r["exudyn_cpu_s"]), r["inhouse"], fmt_number(r["inhouse_error"]),
              fmt_number(r["inhouse_cpu_s"]), fmt_number(r["exudyn_over_inhouse_cpu"], 2)]
             for _, r in table.iterrows()]
    return lines + [md_table(["mechanism", "Exudyn", "error", "CPU [s]", "in-house", "error", "CPU [s]",
                              "Exudyn CPU / in-house CPU"], cells), ""]


def finding(ctx: ReportContext) -> str:
    """The findings' answer: the heavy top's error in-house and in Exudyn, Bricard's energy over the benchmark's
    10 s in-house and in Exudyn against the in-house run's bound, the carriage's stick times and Exudyn's orders
    with friction (when its tables have rows), and sliding mode's energy."""
    runs = ctx.table("spatial_runs")
    if runs is None:
        return "not computed: `spatial_runs` missing"
    top = runs[runs["mechanism"] == "heavy_top"]
    best = {e: top[top["engine"] == e]["error"].min() for e in ("inhouse", "exudyn")}
    over = top[top["drift_over_bound"] > 1.0]
    energy = "; ".join(f"{r['setting']} drifts {fmt_number(r['drift_over_bound'], 2)} × its energy bound"
                       for _, r in over.iterrows())
    bench = runs[(runs["mechanism"] == "bricard") & runs["group"].isin(BENCHMARK_ROLES)]
    parts = [f"the heavy top to {fmt_number(best['inhouse'])} in-house and {fmt_number(best['exudyn'])} in Exudyn "
             f"against the independent model"]
    if len(bench):
        shares = " and ".join(f"{ENGINE[r['engine']]} at {fmt_number(r['drift_over_bound'], 2)} of it "
                              f"({r['setting']})" for _, r in bench.iterrows())
        keeps = "keeps" if bool((bench["drift_over_bound"] <= 1.0).all()) else "**does not keep**"
        parts += [f"Bricard's mechanism (A04) {keeps} its energy over {fmt_number(bench['t_end_s'].max())} s "
                  f"within the in-house run's bound, {shares}"]
    friction, orders = ctx.table("spatial_friction"), ctx.table("spatial_friction_orders")
    if friction is not None and orders is not None and len(friction) and len(orders):
        exact = friction[friction["law"] == "exact"]
        sticks = "; ".join(f"{r['stuck_joints']} stick at "
                           + ";".join(fmt_number(float(t), 7) for t in str(r["stick_times"]).split(";")) + " s"
                           for _, r in exact.iterrows())
        judged = orders["order"].notna() & (orders["verdict"] != "at floor")
        parts += [f"with joint friction the exact law's {sticks.replace(';', ' and ')} and Exudyn's regularized runs "
                  f"converge at orders {fmt_number(orders.loc[judged, 'order'].min(), 3)} to "
                  f"{fmt_number(orders.loc[judged, 'order'].max(), 3)}"]
    return "; ".join(parts) + (f"; {energy}" if energy else "") + f" ([{TITLE}](#spatial-mechanisms))"


def section(ctx: ReportContext) -> list[str]:
    lines = [f"## {TITLE}", ""]
    runs = _runs(ctx)
    if runs is None:
        return lines + ["No saved table `tables/spatial_runs.csv`: the study `spatial` has not run.", ""]
    lines += ["Rigid bodies in 3D with Euler parameters (four per body, the unit-norm row one more constraint), "
              "in-house on the reference path and in Exudyn from the same description (`reference/cases/spatial."
              "toml`).", ""]
    return (lines + heavy_top(runs) + sliding_mode_energy(runs) + bricard(runs) + slider_crank(runs)
            + joint_friction(ctx, ctx.table("spatial_timing")) + equal_accuracy(ctx))
