"""The benchmark's command (``python -m study bench``, ``python -m study.bench``): its sections, in order.

Runs the sections (or some of them, ``--only``; the others' tables are read from the output folder)
and writes every table to ``reports/benchmarks/*.csv``, ``targets.csv`` last, and ``machine.json``.
Its runs are the cases of ``reference/cases/bench.toml``, saved in the benchmark's own store (see
:mod:`study.bench.harness`): a rerun of the same code reuses their saved timings (an interrupted
benchmark resumes); ``--remeasure`` discards them first. A timing is a property of the process that
made it: the loop overhead divides a run's CPU by one evaluation's cost timed in this process, so
compare like with like after a partial rerun (or use ``--remeasure``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import time
from pathlib import Path

import pandas as pd

from study.bench.accuracy import cheapest, ratios
from study.bench.compile_time import compile_time
from study.bench.evaluations import accel_costs
from study.bench.figure import save_work_precision_figure
from study.bench.harness import bench_store, log, machine
from study.bench.profile import overhead_profile
from study.bench.quick_return import quick_return_20s
from study.bench.scaling import scaling
from study.bench.settings import (CASES, EXUDYN_REPEATS, EXUDYN_RUN_BUDGET, LINEAR_REPEATS, LONG_RUN, OUT,
                                  REF_CHECK_RTOLS, REF_RTOL, T2_T_END, repeats)
from study.bench.summary import summarize
from study.bench.sweeps import sweep
from study.bench.targets import evaluate_targets
from study.integrity import atomic_write
from study.output_folder import claim_output_folder
from study.pipeline.tables import read_table, write_table
from study.simulate import simulate


DESCRIPTION = "Benchmark: accuracy per CPU second of the in-house solver, side by side with Exudyn."


def add_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The benchmark's options (shared by ``python -m study.bench`` and ``python -m study bench``)."""
    parser.add_argument("--quick", action="store_true", help="short smoke run (1-2 s horizons, few repeats)")
    parser.add_argument("--out", type=Path, default=OUT, help=f"output folder (default {OUT})")
    parser.add_argument("--remeasure", action="store_true",
                        help="discard the benchmark's saved runs first, so every timing is measured again (by default a "
                             "run saved by an earlier benchmark of the same code is reused, so an interrupted benchmark "
                             "resumes)")
    parser.add_argument("--skip-compile", action="store_true", help="do not measure the one-off compile time")
    parser.add_argument("--only", nargs="+", metavar="SECTION",
                        help="run only these sections (accel, qr20, sweep, scaling, profile, studies, compile); the others' tables "
                             "are read from the output folder")
    parser.add_argument("--mechanisms", nargs="+", metavar="MECHANISM",
                        help=f"run the per-mechanism sections (accel, sweep, profile) for these mechanisms only "
                             f"({', '.join(CASES)}); the other mechanisms' rows are kept from the output folder's tables")
    return parser


def _merge(new: pd.DataFrame, old: pd.DataFrame | None, mechanisms: list[str]) -> pd.DataFrame:
    """``new`` (rows of ``mechanisms``) with the rows of the other mechanisms kept from ``old``."""
    if old is None or old.empty:
        return new
    return pd.concat([old[~old.mechanism.isin(mechanisms)], new], ignore_index=True)


def write_csv(frame: pd.DataFrame, path: Path) -> None:
    """A table of the benchmark (pandas' default CSV format), written and recorded by the one table writer."""
    out = "" if Path(path).parent.resolve() == OUT.resolve() else f" --out {Path(path).parent}"
    write_table(path, frame.to_csv(index=False, lineterminator="\n"), f"python -m study bench{out}")


def main(argv=None) -> int:
    """Command line entry point (see the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m study.bench", description=DESCRIPTION)
    return run(add_arguments(parser).parse_args(argv))


SECTIONS = ("accel", "qr20", "sweep", "scaling", "profile", "studies", "compile")


def _selection(args: argparse.Namespace) -> tuple[set[str], list[str]]:
    """The sections (``--only``) and mechanisms (``--mechanisms``) to run; ValueError naming an unknown one."""
    only = set(args.only or SECTIONS)
    unknown = only - set(SECTIONS)
    if unknown:
        raise ValueError(f"--only {', '.join(sorted(unknown))}: unknown section(s); valid: {', '.join(SECTIONS)}")
    mechs = list(args.mechanisms or CASES)
    unknown = set(mechs) - set(CASES)
    if unknown:
        raise ValueError(f"--mechanisms {', '.join(sorted(unknown))}: no such mechanism in the benchmark's case list; "
                         f"valid: {', '.join(CASES)}")
    return only, mechs


def _machine_info(args: argparse.Namespace, only: set[str], mechs: list[str], out: Path) -> dict:
    """The record of the machine and of this run's settings (``machine.json``), logged."""
    info = machine()
    info.update({"repeats": repeats(args.quick), "quick": args.quick, "long_run_s": LONG_RUN, "reference_rtol": REF_RTOL,
                 "reference_check_rtols": list(REF_CHECK_RTOLS), "exudyn_run_budget_s": EXUDYN_RUN_BUDGET,
                 "exudyn_repeats": EXUDYN_REPEATS, "linearity_repeats": LINEAR_REPEATS,
                 "sections_run": sorted(only), "mechanisms_run": mechs, "load_average_at_start": os.getloadavg()[0],
                 "saved_runs": str(bench_store().root), "remeasure": args.remeasure})
    log(f"machine: {info['platform']}, {info['cpu_count']} CPUs, load {os.getloadavg()}; output {out}")
    return info


def _warm_up() -> None:
    """One short compiled run of each benchmark mechanism (loads or builds the code cache before any timing)."""
    log("warming up the compiled path (loads or builds the cache)")
    for mech, (variant, _, extra) in CASES.items():
        simulate(mech, variant=variant, t_end=0.05, backend="compiled", **extra)
    simulate("quick_return", variant="seed", t_end=0.05, backend="compiled")


def _accuracy_sections(args: argparse.Namespace, only: set[str], mechs: list[str], out: Path, saved, kept):
    """Sections accel, qr20 and sweep (run and written, or read back), and ``references.csv``.

    Returns (accel, qr20, wp, ratio): the tables the later sections and the targets read.
    """
    if "accel" in only:
        accel = _merge(accel_costs(repeats(args.quick), 2000 if args.quick else 20000, mechs),
                       kept("acceleration_evaluation.csv"), mechs)
        write_csv(accel, out / "acceleration_evaluation.csv")
    else:
        accel = saved("acceleration_evaluation.csv")
    if "qr20" in only:
        log("(f) quick-return 20 s to 1e-8")
        qr20, qr_refs = quick_return_20s(args.quick)
        write_csv(qr20, out / "quick_return_20s.csv")
    else:
        qr20 = saved("quick_return_20s.csv")
    if "sweep" in only:
        tables = summarize([c for m in mechs for c in sweep(m, args.quick)], bench_store().load)
        wp = _merge(tables["work_precision"], kept("work_precision.csv"), mechs)
        sweep_refs = tables["references"]
        write_csv(wp, out / "work_precision.csv")
        per_level = cheapest(wp)
        write_csv(per_level, out / "cpu_to_accuracy.csv")
        ratio = ratios(per_level)
        write_csv(ratio, out / "ratio_inhouse_exudyn.csv")
        save_work_precision_figure(wp, out)
    else:
        wp, ratio = saved("work_precision.csv"), saved("ratio_inhouse_exudyn.csv")
    if "sweep" in only or "qr20" in only:   # references.csv: rows of the sections rerun replaced, the others kept
        old = (saved("references.csv") if (out / "references.csv").exists()
               else pd.DataFrame(columns=["mechanism", "t_end"]))
        of_qr20 = old.t_end == (2.0 if args.quick else T2_T_END)
        rerun = (of_qr20 & ("qr20" in only)) | (~of_qr20 & old.mechanism.isin(mechs) & ("sweep" in only))
        new = ([sweep_refs] if "sweep" in only else []) + ([qr_refs] if "qr20" in only else [])
        write_csv(pd.concat([old[~rerun], *new], ignore_index=True), out / "references.csv")
    return accel, qr20, wp, ratio


def _scaling_sections(args: argparse.Namespace, only: set[str], out: Path, saved):
    """Sections scaling and studies (run and written, or read back).

    Returns (time_df, mem_df, study_cpu); study_cpu is None when the studies' table was neither made nor saved.
    """
    if "scaling" in only:
        time_df, density_df, mem_df = scaling(args.quick)
        write_csv(time_df, out / "scaling_simulated_time.csv")
        write_csv(density_df, out / "scaling_output_density.csv")
        write_csv(mem_df, out / "peak_memory.csv")
    else:
        time_df, mem_df = saved("scaling_simulated_time.csv"), saved("peak_memory.csv")
    study_cpu = None
    if "studies" in only:   # reads the pipeline's saved runs (no run here); absent cache -> no row
        from study.model.compile import cache_dir
        from study.pipeline import Store, backend_cpu, load_case_lists

        study_cpu = backend_cpu(load_case_lists(), Store(cache_dir() / "runs"))
        write_csv(study_cpu, out / "study_backend_cpu.csv")
        log(f"(h) studies: {len(study_cpu)} saved compiled/reference pairs")
    elif (out / "study_backend_cpu.csv").exists():
        study_cpu = saved("study_backend_cpu.csv")
    return time_df, mem_df, study_cpu


def _write_targets(targets: pd.DataFrame, out: Path) -> None:
    """``targets.csv``, and each target's verdict logged."""
    write_csv(targets, out / "targets.csv")
    for _, t in targets.iterrows():
        verdict = {True: "met", False: "MISSED"}.get(t.met, t.met)
        log(f"target {t.target}: measured {t.measured:.4g} {t.unit} vs {t.threshold:g}: {verdict}")


def _write_machine(info: dict, only: set[str], out: Path, t0: float) -> None:
    """``machine.json`` with this run's wall time; a partial run adds its record to the full run's."""
    wall = info["benchmark_wall_s"] = time.perf_counter() - t0
    info["load_average_at_end"] = os.getloadavg()[0]
    path = out / "machine.json"
    if only != set(SECTIONS) and path.exists():   # a partial run keeps the full run's record, adds its own
        full = json.loads(path.read_text())
        full.setdefault("partial_runs", []).append(info)
        info = full
    atomic_write(path, json.dumps(info, indent=1, sort_keys=True))
    log(f"done in {wall:.0f} s; results in {out}")   # this run's time (info may now be the full run's record)


def run(args: argparse.Namespace) -> int:
    """Run the benchmark with parsed options (see :func:`add_arguments`); returns the exit code.

    ``--only`` runs some sections and reads the others' tables from the output folder (written by an
    earlier full run in the same folder), so ``targets.csv`` is always evaluated from every table.
    """
    only, mechs = _selection(args)
    out = claim_output_folder(args.out)
    if args.remeasure:
        shutil.rmtree(bench_store().root, ignore_errors=True)

    def saved(name):
        path = out / name
        if not path.exists():
            raise FileNotFoundError(f"{path} is missing: run the section that writes it (without --only) first")
        return read_table(path)

    def kept(name):   # the saved table whose other mechanisms' rows a --mechanisms run keeps
        return saved(name) if args.mechanisms else None
    t0 = time.perf_counter()
    info = _machine_info(args, only, mechs, out)
    _warm_up()
    accel, qr20, wp, ratio = _accuracy_sections(args, only, mechs, out, saved, kept)
    time_df, mem_df, study_cpu = _scaling_sections(args, only, out, saved)
    if "profile" in only:
        profile = overhead_profile(qr20, wp, accel, repeats(args.quick), mechs)
        write_csv(_merge(profile, kept("overhead_profile.csv"), mechs), out / "overhead_profile.csv")
    _write_targets(evaluate_targets(accel, ratio, qr20, time_df, mem_df, wp=wp, study_cpu=study_cpu), out)
    if "compile" in only and not (args.quick or args.skip_compile):
        write_csv(compile_time(), out / "compile_time.csv")
    _write_machine(info, only, out, t0)
    return 0
