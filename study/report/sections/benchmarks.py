"""Report section: performance of the in-house solver, side by side with Exudyn.

Reads the benchmark's saved files in ``reports/benchmarks/`` (written by ``make bench``, i.e.
``python -m study.bench``): ``targets.csv``, ``ratio_inhouse_exudyn.csv``, ``cpu_to_accuracy.csv``,
``quick_return_20s.csv``, ``references.csv``, ``acceleration_evaluation.csv``,
``scaling_simulated_time.csv``, ``scaling_output_density.csv``, ``peak_memory.csv``,
``compile_time.csv``, ``work_precision.csv`` and ``machine.json``. Never a run. The work-precision
figure is redrawn from ``work_precision.csv`` by
:func:`study.report.figures.benchmark_work_precision_figure`, the function the benchmark itself
uses. Every number in the text is read from those files.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd

from study.report import figures
from study.report.context import ReportContext
from study.report.render import fmt_int, fmt_number, md_table

HEADING = "## Performance: accuracy per CPU second"
FOLDER = "benchmarks"


def _read(ctx: ReportContext, name: str) -> pd.DataFrame | None:
    """``reports/benchmarks/<name>`` as a frame (registered in ``ctx.inputs``), or None if absent."""
    return ctx.read(f"{FOLDER}/{name}")


def _machine(ctx: ReportContext) -> dict:
    path = ctx.reports_dir / FOLDER / "machine.json"
    if not path.exists():
        return {}
    ctx.inputs.append(path)
    return json.loads(path.read_text())


def _met(value) -> str:
    """The verdict of a target row: met / missed, or the row's own word ('reported', 'not measured')."""
    word = str(value).strip().lower()
    return {"true": "**met**", "false": "**missed**"}.get(word, word)


def _targets_table(targets: pd.DataFrame) -> str:
    header = ["target", "threshold", "measured", "unit", "verdict", "how measured", "timings", "note"]
    rows = [[t.target, fmt_number(t.threshold), fmt_number(t.measured), t.unit, _met(t.met), t.how_measured,
             fmt_int(t.repeats), t.note if isinstance(t.note, str) else ""] for t in targets.itertuples(index=False)]
    return md_table(header, rows, [False, True, True, False, False, False, True, False])


def _ratio_table(ratio: pd.DataFrame) -> str:
    if "comparison" not in ratio:
        ratio = ratio.assign(comparison="in-house / Exudyn")
    header = ["comparison", "mechanism", "max|Δq| ≤ [rad]", "in-house compiled (setting)", "CPU [s]", "timings",
              "Exudyn (h [s])", "CPU [s]", "timings", "ratio", "ratio, Exudyn scaled to the level (order 2)",
              "note"]
    rows = []
    ratio = ratio.sort_values(["comparison", "mechanism", "level"], ascending=[True, True, False])
    for r in ratio.itertuples(index=False):
        ours = f"{r.inhouse_method} ({fmt_number(r.inhouse_setting)})" if isinstance(r.inhouse_method, str) else "not reached"
        exu = f"{r.exudyn_method} ({fmt_number(r.exudyn_setting, 4)})" if isinstance(r.exudyn_method, str) else "not reached"
        rows.append([r.comparison, f"{r.mechanism} ({r.variant}, {fmt_number(r.t_end)} s)", fmt_number(r.level), ours,
                     fmt_number(r.inhouse_cpu_s), fmt_int(r.inhouse_repeats), exu, fmt_number(r.exudyn_cpu_s),
                     fmt_int(r.exudyn_repeats), fmt_number(r.ratio_inhouse_over_exudyn), fmt_number(r.ratio_order2),
                     r.note if isinstance(r.note, str) else ""])
    return md_table(header, rows, [False, False, True, False, True, True, False, True, True, True, True, False])


def _cpu_to_accuracy_table(per_level: pd.DataFrame) -> str:
    levels = sorted(per_level["level"].unique(), reverse=True)
    header = ["mechanism", "engine", "method"] + [f"CPU [s] to ≤ {fmt_number(lv)} rad (setting)" for lv in levels]
    rows = []
    for (mech, engine, method), g in per_level.groupby(["mechanism", "engine", "method"], sort=True):
        row = [mech, engine, method]
        for lv in levels:
            r = g[np.isclose(g["level"], lv, rtol=1e-9, atol=0)]
            if r.empty:
                row.append("–")
            elif bool(r["reached"].iloc[0]):
                row.append(f"{fmt_number(r['cpu_s'].iloc[0])} ({fmt_number(r['setting'].iloc[0], 4)})")
            else:
                failed = r["failed_settings"].iloc[0] if "failed_settings" in r else ""
                failed = f"; fails at {failed}" if isinstance(failed, str) and failed else ""
                row.append(f"not reached (best {fmt_number(r['best_error'].iloc[0])} at "
                           f"{fmt_number(r['finest_setting_tried'].iloc[0], 4)}{failed})")
        rows.append(row)
    return md_table(header, rows, [False, False, False] + [True] * len(levels))


def _qr20_table(qr20: pd.DataFrame) -> str:
    header = ["cutting law", "t_end [s]", "integrator", "rtol", "max|Δq| [rad]", "median CPU [s]", "timings",
              "steps", "located switches"]
    rows = [[r.variant, fmt_number(r.t_end), r.integrator, fmt_number(r.rtol), fmt_number(r.error),
             fmt_number(r.cpu_s), fmt_int(r.repeats), fmt_int(r.steps), fmt_int(r.events)]
            for r in qr20.itertuples(index=False)]
    return md_table(header, rows, [False, True, False, True, True, True, True, True, True])


def _qr20_reading(qr20: pd.DataFrame) -> list[str]:
    """Where the error does not fall as rtol is tightened (numbers from the table)."""
    items = []
    for variant, g in qr20.groupby("variant", sort=False):
        g = g.sort_values("rtol", ascending=False)
        e, r = g["error"].to_numpy(float), g["rtol"].to_numpy(float)
        up = [f"rtol {fmt_number(r[k + 1])}: {fmt_number(e[k + 1])} after {fmt_number(e[k])}"
              for k in range(len(e) - 1) if e[k + 1] >= e[k]]
        if up:
            items.append(f"- {variant}: the error does not fall with every tightening of rtol ({'; '.join(up)}): the "
                         "trajectory is sensitive to small perturbations, so the error at a given rtol is partly "
                         "chance.")
    return items + [""] if items else []


def _references_table(refs: pd.DataFrame) -> str:
    header = ["mechanism", "variant", "t_end [s]", "reference rtol", "check rtol", "max|Δq| check vs reference [rad]"]
    rows = [[r.mechanism, r.variant, fmt_number(r.t_end), fmt_number(r.reference_rtol), fmt_number(r.check_rtol),
             fmt_number(r.max_abs_dq_check_vs_reference)] for r in refs.itertuples(index=False)]
    return md_table(header, rows, [False, False, True, True, True, True])


def _accel_table(accel: pd.DataFrame) -> str:
    header = ["mechanism", "variant", "friction solve", "path", "µs per evaluation", "calls per timing", "timings"]
    rows = [[r.mechanism, r.variant, "yes" if bool(r.friction_solve) else "no", r.path, fmt_number(r.us_per_evaluation),
             fmt_int(getattr(r, "calls_per_timing", np.nan)), fmt_int(getattr(r, "repeats", np.nan))]
            for r in accel.itertuples(index=False)]
    return md_table(header, rows, [False, False, False, False, True, True, True])


def _frame_table(frame: pd.DataFrame, columns: dict[str, str], ints: set[str] = frozenset()) -> str:
    """A table of selected columns (column -> header), numbers formatted, numeric columns right-aligned."""
    cols = [c for c in columns if c in frame.columns]
    rows = []
    for _, r in frame.iterrows():
        rows.append([fmt_int(r[c]) if c in ints else (fmt_number(r[c]) if pd.api.types.is_number(r[c]) else str(r[c]))
                     for c in cols])
    right = [pd.api.types.is_numeric_dtype(frame[c]) for c in cols]
    return md_table([columns[c] for c in cols], rows, right)


def _machine_text(info: dict) -> str:
    if not info:
        return "Machine: `machine.json` is missing."
    versions = ", ".join(f"{k} {info[k]}" for k in ("python", "numpy", "scipy", "numba", "exudyn", "sympy") if k in info)
    wall = f"; the whole benchmark took {fmt_number(info['benchmark_wall_s'])} s wall time" if "benchmark_wall_s" in info else ""
    quick = " **This is a `--quick` smoke run (short horizons), not the benchmark's numbers.**" if info.get("quick") else ""
    return (f"Machine: {info.get('platform', '?')}, {info.get('processor', '?')}, {info.get('cpu_count', '?')} CPUs; "
            f"{versions}. Timings are medians of {info.get('repeats', '?')} repeats (runs longer than "
            f"{fmt_number(info.get('long_run_s', np.nan))} s fewer, as counted in each table){wall}.{quick}")


def _intro_lines(info: dict) -> list[str]:
    """What the benchmark measures and how, and the machine it ran on."""
    return ["The benchmark (`study/bench/`, `make bench`) measures, in one process on one machine, the "
            "in-house solver's compiled path (generated numba code, compiled integration loop), its reference "
            "path (Python + scipy) and Exudyn's index-3 and index-2 fixed-step solvers in two configurations: "
            "*tuned* (as Exudyn's documentation recommends for speed: state-dependent load laws as symbolic user "
            "functions of connectors, constant loads as plain loads, no numerical load Jacobian unless a Python "
            "load needs it, one Newton Jacobian per step; the friction reading a joint reaction stays a Python "
            "user function, as no Exudyn element exposes the reaction otherwise) and *Python user functions* "
            "(every state-dependent law a Python callback, full Newton). Accuracy is max |Δq| over "
            "the 0.01 s output samples and the coordinates against a compiled DOP853 reference at a tighter "
            "tolerance; CPU time is the process time of the integration (Exudyn: of SolveDynamic; its own timer "
            "is wall-clock time). Every Exudyn run entering a ratio is timed at least 3 times (median). Absolute "
            "times depend on the host and its load; the targets are ratios taken within one run.", "",
            _machine_text(info), ""]


def _targets_lines(targets: pd.DataFrame) -> list[str]:
    """The targets' table and a count of the rows met, missed and without a verdict."""
    lines = ["### Targets", "", _targets_table(targets), ""]
    verdict = targets["met"].astype(str).str.lower()
    missed = targets[verdict.eq("false")]
    judged = int(verdict.isin(["true", "false"]).sum())
    other = len(targets) - judged
    if other:
        lines += [f"{other} row(s) carry no verdict (reported without a target, or not measured in this branch).", ""]
    if len(missed):
        lines += [f"{len(missed)} of {judged} target rows missed: " +
                  "; ".join(f"{t.target} (measured {fmt_number(t.measured)} {t.unit} against {fmt_number(t.threshold)})"
                            for t in missed.itertuples(index=False)) + ".", ""]
    else:
        lines += [f"All {judged} target rows met.", ""]
    return lines


def _accuracy_lines(ctx: ReportContext) -> list[str]:
    """Work–precision: the figure, the in-house / Exudyn ratios and the CPU to each accuracy."""
    lines = []
    wp = _read(ctx, "work_precision.csv")
    if wp is not None and len(wp):
        lines += ["### Work–precision", "",
                  ctx.figure(figures.benchmark_work_precision_figure(wp), "benchmark_work_precision",
                             "CPU time against max |q − q_ref|, in-house methods and Exudyn solvers, both mechanisms"),
                  ""]
    ratio = _read(ctx, "ratio_inhouse_exudyn.csv")
    if ratio is not None:
        lines += ["### In-house / Exudyn at equal accuracy", "",
                  "Two comparisons, like with like: the cheapest compiled in-house method against the cheapest "
                  "tuned Exudyn solver, and the in-house reference path against Exudyn with Python user functions, "
                  "each reaching the same accuracy. "
                  "Exudyn's step is halved from 0.01 s and then set by its measured order-2 error decrease; the "
                  "last column scales Exudyn's CPU to the step that would give exactly the level (error ∝ h², cost ∝ "
                  "1/h), which favours Exudyn.", "", _ratio_table(ratio), ""]
    per_level = _read(ctx, "cpu_to_accuracy.csv")
    if per_level is not None:
        lines += ["CPU time of the cheapest setting of every method reaching each accuracy (setting: rtol, or the "
                  "step h [s]):", "", _cpu_to_accuracy_table(per_level), ""]
    return lines


def _long_run_lines(ctx: ReportContext) -> list[str]:
    """The compiled loop's time split, the quick-return over 20 s, and the references' errors."""
    lines = []
    profile = _read(ctx, "overhead_profile.csv")
    if profile is not None and len(profile):
        lines += ["### Where the compiled loop's time goes", "",
                  "Each run behind a loop-overhead row, its CPU split into measured parts (numba code has no "
                  "profiler hooks): start-up (the same run stopped after one output step), the model's evaluations "
                  "(count × the cost of one inside the compiled loop), the located switches (count × one Python → "
                  "compiled call: after a switch the loop returns to Python) and the rest, the integrator's own work "
                  "per step.", "",
                  _frame_table(profile, {"mechanism": "mechanism", "variant": "variant", "t_end": "t_end [s]",
                                         "rtol": "rtol", "cpu_s": "CPU [s]", "steps": "steps", "nfev": "evaluations",
                                         "events": "switches", "startup_s": "start-up [s]",
                                         "evaluations_s": "evaluations [s]", "events_s": "switches [s]",
                                         "loop_s": "rest [s]", "loop_us_per_step": "rest per step [µs]",
                                         "overhead": "overhead"}, ints={"steps", "nfev", "events"}), ""]
    qr20 = _read(ctx, "quick_return_20s.csv")
    if qr20 is not None:
        lines += ["### Quick-return over 20 s to 1e-8", "",
                  "Compiled DOP853 (atol = rtol/100) on both cutting laws: the smooth law (tanh ramps) and the "
                  "seed's on/off law, whose switches the compiled loop locates. Each is compared with its own "
                  "reference; a setting counts for target 2 only if its error plus the reference's estimated error "
                  "stays within 1e-8.", "", _qr20_table(qr20), ""] + _qr20_reading(qr20)
    refs = _read(ctx, "references.csv")
    if refs is not None:
        lines += ["References and their estimated error (difference from runs at other tolerances; tighter "
                  "tolerances than the reference's are not more accurate: round-off sets the floor):", "",
                  _references_table(refs), ""]
    return lines


def _cost_lines(ctx: ReportContext) -> list[str]:
    """One evaluation's cost, the scaling with simulated time and output density, memory and compile time."""
    lines = []
    accel = _read(ctx, "acceleration_evaluation.csv")
    if accel is not None:
        lines += ["### Cost of one acceleration evaluation", "",
                  "Accelerations with the multipliers λ (slider-crank: with the coupled normal-force/friction "
                  "solve). 'In compiled loop' is the cost inside the integrator; 'one call from Python' adds the "
                  "call overhead.", "", _accel_table(accel), ""]
    scaling = _read(ctx, "scaling_simulated_time.csv")
    if scaling is not None:
        lines += ["### Scaling", "", "CPU time against simulated time (quick-return smooth_cutting, DOP853 rtol 1e-10):",
                  "", _frame_table(scaling, {"backend": "backend", "t_end": "t_end [s]", "cpu_s": "CPU [s]",
                                             "steps": "steps", "cpu_per_simulated_s": "CPU per simulated s [s/s]",
                                             "repeats": "timings"}, {"steps", "repeats"}), ""]
    density = _read(ctx, "scaling_output_density.csv")
    if density is not None:
        lines += ["CPU time against output density (compiled):", "",
                  _frame_table(density, {"t_end": "t_end [s]", "output_step": "output step [s]", "samples": "samples",
                                         "cpu_s": "CPU [s]", "steps": "steps", "nfev": "evaluations",
                                         "repeats": "timings"}, {"samples", "steps", "nfev", "repeats"}), ""]
    memory = _read(ctx, "peak_memory.csv")
    if memory is not None:
        lines += ["Peak traced memory (tracemalloc) against output size:", "",
                  _frame_table(memory, {"backend": "path", "t_end": "t_end [s]", "output_step": "output step [s]",
                                        "samples": "samples", "steps": "steps", "peak_traced_bytes": "peak [bytes]",
                                        "bytes_per_sample": "bytes per sample"},
                               {"samples", "steps", "peak_traced_bytes"}), ""]
    compile_df = _read(ctx, "compile_time.csv")
    if compile_df is not None:
        lines += ["Time to the first result (a new process per row; a cold cache generates and compiles, a warm one "
                  "loads; CPU is the child's, less sensitive to a shared machine than wall time; the pace is the "
                  "host's µs per compiled quick-return evaluation, and CPU / pace compares hosts of different "
                  "speed):", "",
                  _frame_table(compile_df, {"path": "path", "cache": "cache", "mechanism": "mechanism",
                                            "repeat": "repeat", "first_call_wall_s": "first result, wall [s]",
                                            "cpu_s": "CPU [s]", "pace_us": "pace [µs per evaluation]",
                                            "cpu_s_at_pace_1us": "CPU at a pace of 1 µs [s]"}, {"repeat"}), ""]
    return lines


def section(ctx: ReportContext) -> list[str]:
    """The report's performance section (see the module docstring)."""
    lines = [HEADING, ""]
    folder = ctx.reports_dir / FOLDER
    targets = _read(ctx, "targets.csv") if folder.is_dir() else None
    if targets is None:
        return lines + [f"No benchmark results in `{folder.name}/` (`reports/{FOLDER}/targets.csv` is missing): run "
                        "`make bench` (`python -m study.bench`, about 10 minutes on 2 cores) to measure them.", ""]
    lines += _intro_lines(_machine(ctx)) + _targets_lines(targets)
    lines += _accuracy_lines(ctx) + _long_run_lines(ctx) + _cost_lines(ctx)
    lines += [f"All files: `reports/{FOLDER}/` (CSV, `machine.json`, the benchmark's own `work_precision.png/.svg`).", ""]
    return lines
