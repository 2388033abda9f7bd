"""The command line's pipeline commands: ``initial``, ``errata``, ``run``, ``report``, ``reproduce`` (all of them, the
errata check alongside) and ``verify`` (:mod:`study.cli` parses the arguments and reports errors)."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

from study.arguments import writable
from study.output_folder import claim_output_folder
from study.pipeline import CASES_DIR

REPORTS = Path("reports")


def initial(args: argparse.Namespace) -> int:
    from study.initial_report import initial_conditions_table, write_initial_conditions

    path = write_initial_conditions(claim_output_folder(args.out) / "tables")
    with_pd = initial_conditions_table()
    print(with_pd.to_string(index=False))
    print(f"wrote {path}")
    return 0


def errata(args: argparse.Namespace) -> int:
    from study.errata.table import update_errata
    from study.model.compile import cache_dir

    path, reused = update_errata(claim_output_folder(args.out) / "tables", cache_dir())
    if reused:
        print(f"errata: the inputs (package source, reference/*.toml, sympy) are unchanged since {path} and "
              f"{path.with_suffix('.csv').name} were written: reused them")
    else:
        print(path.read_text())
    return 0


def run(args: argparse.Namespace) -> int:
    from study.model.compile import cache_dir
    from study.pipeline import CaseListError, environment_workers, run_pipeline

    writable(args.out, "--out", folder=True)
    try:
        record = run_pipeline(args.out, cache_dir(), studies=args.studies or None,
                              workers=environment_workers() if args.workers is None else args.workers,
                              scheduler=args.scheduler, folder=args.cases, record_root=_record_root(args))
    except CaseListError as exc:
        print(f"error: --cases {args.cases}: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for study, r in record["studies"].items():
        if r.get("expected_failures"):
            print(f"{study}: {len(r['expected_failures'])} cases stopped with the error their case list expects "
                  f"(expect_error; listed in tables/failed_cases.csv)", file=sys.stderr)
    failed = {s: r["failed"] for s, r in record["studies"].items() if r["failed"]}
    for study, cases in failed.items():
        for name, error in cases.items():
            print(f"FAILED {name}: {error}", file=sys.stderr)
    broken = {s: r["summary_error"] for s, r in record["studies"].items() if r.get("summary_error")}
    energy = record.get("energy_balance_flags", {})
    for name, why in energy.items():
        print(f"FAILED energy balance of {name}: {why}", file=sys.stderr)
    return 1 if failed or broken or energy else 0


def _record_root(args: argparse.Namespace) -> Path:
    """Where a pipeline run keeps its record: the cache root for reference/cases; for another case folder
    its own --out (required: the default reports/ holds the tables of reference/cases, tracked in git)."""
    from study.model.compile import cache_dir

    if Path(args.cases).resolve() == CASES_DIR.resolve():
        return cache_dir()
    if Path(args.out).resolve() == REPORTS.resolve():
        raise ValueError(f"--cases {args.cases} is not the default case folder: give it its own --out "
                         f"(the default {REPORTS}/ holds the tracked tables of {CASES_DIR.name}/)")
    return Path(args.out) / ".pipeline"


def report(args: argparse.Namespace) -> int:
    from study.model.compile import cache_dir
    from study.report import build_report

    print(f"report: {build_report(args.out, cache_dir(), getattr(args, 'cases', CASES_DIR)).resolve()}")
    return 0


def reproduce(args: argparse.Namespace) -> int:
    from study.pipeline import PIPELINE_RECORD, save_record

    record_root = _record_root(args)
    claim_output_folder(args.out)   # before the errata process starts writing there
    stages = {}
    code = 0
    # The errata check (sympy, one process) runs alongside the initial conditions and the cases; its output follows.
    t_errata = time.perf_counter()
    errata = subprocess.Popen([sys.executable, "-m", "study", "errata", "--out", str(args.out)],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    for name, step in (("initial", initial), ("run", run), ("errata", None), ("report", report)):
        if name == "errata":
            output = errata.communicate()[0]
            stages["errata"] = time.perf_counter() - t_errata
            print(output, end="")
            if errata.returncode:
                print(f"error: the errata check failed (exit {errata.returncode})", file=sys.stderr)
                return errata.returncode if errata.returncode > 0 else 2
            continue
        if name == "report":  # the manifest shows the wall time of every stage before the report
            record_path = record_root / PIPELINE_RECORD
            record = json.loads(record_path.read_text())
            record["stages"].update({k: stages[k] for k in ("initial", "errata")})
            save_record(record, record_root)
        t0 = time.perf_counter()
        try:
            code = step(args) or code
        except BaseException:
            _stop(errata)
            raise
        stages[name] = time.perf_counter() - t0
        if code and not (name == "run" and code == 1):  # failed cases (1) are reported; errors stop
            _stop(errata)
            return code
    print("wall time per stage (errata alongside initial and run): "
          + ", ".join(f"{k} {v:.1f} s" for k, v in stages.items())
          + f"; this host's pace now: {_evaluation_us():.2f} us per compiled quick-return evaluation",
          file=sys.stderr)
    print(f"(details per study: {record_root / PIPELINE_RECORD})", file=sys.stderr)
    print(f"report: {(args.out / 'index.md').resolve()} and {(args.out / 'report.html').resolve()}")
    return code


def _stop(process: subprocess.Popen) -> None:
    """End a helper process and reap it."""
    process.kill()
    process.wait()


def _evaluation_us() -> float:
    """This host's pace (:func:`study.bench.evaluations.pace_us`), for reading the stages' wall times."""
    from study.bench.evaluations import pace_us

    return pace_us()


def verify(args: argparse.Namespace) -> int:
    from study.model.compile import cache_dir
    from study.pipeline import environment_workers
    from study.verify import main_verify

    for ulps in args.ulps or []:
        if ulps == 0:
            raise ValueError("--ulps 0 moves nothing: the perturbed run would be the run itself (give e.g. 4 or -4)")
    if args.ulps and not args.perturb:
        raise ValueError(f"--ulps {args.ulps[0]} applies to --perturb only")
    return main_verify(args.out, cache_dir(), args.studies or None, args.workers or environment_workers(),
                       args.perturb, args.ulps, args.cases)
