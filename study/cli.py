"""Command-line entry points: ``python -m study <command>``."""

from __future__ import annotations

import argparse
import inspect
import os
import sys
from pathlib import Path

from study import arguments
from study import cli_pipeline
from study.arguments import writable
from study.pipeline import CASES_DIR

REPORTS = cli_pipeline.REPORTS
# One example per command, shown at the end of its --help.
EXAMPLES = {
    "initial": "python -m study initial --out reports",
    "errata": "python -m study errata --out reports",
    "report": "python -m study report --out reports",
    "run": "python -m study run sliding_mode --workers 2",
    "reproduce": "python -m study reproduce --workers 2",
    "simulate": "python -m study simulate slider_crank --variant slip_then_stick --t-end 5 --out /tmp/sc",
    "bench": "python -m study bench --quick --out /tmp/bench",
    "verify": "python -m study verify work_precision --perturb",
    "describe": "python -m study describe quick_return --variant guide_friction",
    "validate": "python -m study validate examples/scotch_yoke/scotch_yoke.py --t-end 1 --out /tmp/yoke",
}


def _friction_text(result, chosen_by_default: bool) -> str:
    """How friction ran, for the one-line summary: treatment, settings, whether it was the default, and the friction
    entries a run without friction left out."""
    name = result.meta.get("friction")
    left_out = result.meta.get("friction_left_out") or []
    if name is None:
        text = "friction none" + (f" (asked: the friction of {', '.join(left_out)} left out)" if left_out else "")
    elif name == "regularized":
        text = f"friction regularized ({result.meta.get('friction_sgn', '?')}, eps = {result.meta['friction_eps']:g} m/s)"
    elif name == "sign":
        text = f"friction sign (plain sgn, stick band {result.meta['friction_eps']:g} m/s)"
    else:
        text = f"friction {name}"
    return text + (" [parameter set's default]" if chosen_by_default else "")


# simulate()'s arguments set by a flag of the simulate command (an --option must not set them again)
SIMULATE_FLAGS = {"variant": "--variant", "method": "--method", "integrator": "--integrator",
                  "acceleration_solver": "--acceleration-solver", "backend": "--backend", "friction": "--friction",
                  "friction_eps": "--friction-eps", "friction_sgn": "--friction-sgn", "rtol": "--rtol", "atol": "--atol",
                  "max_evaluations": "--max-evaluations", "step": "--step", "t_end": "--t-end",
                  "output_step": "--output-step"}


def method_options(items: list[str] | None, method: str) -> dict:
    """The --option KEY=VALUE items of ``method``, each parsed to its declared type; a ValueError names the item."""
    from study.solver.stabilization import check_options, method_options as declared_options

    declared = declared_options(method)
    options = {}
    for item in items or []:
        key, _, value = item.partition("=")
        if not key or not value:
            raise ValueError(f"--option {item!r}: expected KEY=VALUE (e.g. omega=10 or sgn=tanh)")
        if key in SIMULATE_FLAGS:
            raise ValueError(f"--option {key}: set it with {SIMULATE_FLAGS[key]}, not as a method option")
        if key in options:
            raise ValueError(f"--option {key} given twice ({options[key]!r} and {value!r})")
        kind = declared.get(key)
        if kind is None:
            valid = ", ".join(declared) or "none (it takes no options)"
            raise ValueError(f"--option {key}: not an option of --method {method}; valid options: {valid}")
        try:
            options[key] = int(value) if kind == "int" else value if kind == "str" else float(value)
        except ValueError:
            wanted = "a whole number" if kind == "int" else "a number"
            raise ValueError(f"--option {key} = {value!r} must be {wanted}") from None
    return check_options(method, options, source="--option ")


def _simulate(args: argparse.Namespace) -> int:
    from study.progress import ProgressPrinter
    from study.results import check_save_target
    from study.engines.runner import resolve
    from study.friction_default import default_friction
    from study.run_arguments import DEFAULT_FRICTION, DEFAULT_OUTPUT_STEP, check_arguments
    from study.simulate import simulate

    out = arguments.output_path("--out", args.out)
    options = method_options(args.option, args.method)
    target = args.mechanism
    if target.endswith(".py"):   # a user's mechanism file: its own parameter set, the variant chosen here
        from study.user_mechanism import load_mechanism

        target = load_mechanism(target, args.variant)
    run = {k: getattr(args, k) for k in ("variant", "method", "integrator", "acceleration_solver", "backend", "friction",
                                         "friction_eps", "friction_sgn", "rtol", "atol", "step", "t_end",
                                         "max_evaluations")}
    run["output_step"] = DEFAULT_OUTPUT_STEP if args.output_step is None else args.output_step
    if not isinstance(target, str):   # the file's parameter set is already the chosen variant
        run["variant"] = None
    if run["friction"] is None:  # the parameter set's treatment of every friction entry (contacts and pins)
        eom, mech = resolve(target, run["variant"])
        run["friction"] = default_friction(eom, None if mech is None else mech.parameters) or "none"
    check_arguments(**run, progress=None, resistance_reading=None, check=True, min_step=None, max_output_bytes=None,
                    names=SIMULATE_FLAGS)
    writable(out, "--out")
    check_save_target(out)   # a user's folder or file there is refused before the run
    if args.friction is None:   # checked with the treatment it stands for; the run records that it was the default
        run["friction"] = DEFAULT_FRICTION
    result = simulate(target, **run, **options,
                      progress=ProgressPrinter(args.t_end) if args.backend == "reference" else None)
    path = result.save(out)
    s = result.summary()
    print(f"{args.mechanism}/{args.variant} {args.method} {args.integrator} ({args.backend}), "
          f"{_friction_text(result, args.friction is None)}: max|Phi| = {s['max_abs_phi']:.3e}, "
          f"energy error = {s['energy_error']:.3e} J ({s['energy_error_relative']:.2e} of max T), "
          f"CPU {s['cpu_seconds']:.3f} s, {result.stats['nfev']} evaluations -> {path}")
    return 0


def _describe(args: argparse.Namespace) -> int:
    from study.describe import describe_text

    if args.mechanism.endswith(".py"):
        from study.user_mechanism import load_mechanism

        print(describe_text(load_mechanism(args.mechanism, args.variant)))
    else:
        print(describe_text(args.mechanism, args.variant))
    return 0


def _validate(args: argparse.Namespace) -> int:
    from study.user_mechanism import load_mechanism
    from study.validation import Settings, validate

    settings = Settings(**{k: getattr(args, k) for k in ("t_end", "output_step", "h", "levels", "friction_eps")
                           if getattr(args, k) is not None})
    out = args.out or Path("validation") / Path(args.file).stem
    writable(out, "--out", folder=True)
    tables = validate(load_mechanism(args.file, args.variant), settings, out,
                      say=lambda text: print(text, file=sys.stderr))
    failed = [*tables["in_house"].loc[tables["in_house"]["error"] != "", "run"],
              *(f"Exudyn {r.solver} h = {r.h:g} s" for r in tables["exudyn_convergence"].itertuples() if r.error)]
    if failed:
        print(f"validate: {len(failed)} runs failed (their errors are in the report): {', '.join(failed)}",
              file=sys.stderr)
    return 1 if failed else 0


def _bench(args: argparse.Namespace) -> int:
    from study.bench.command import run

    return run(args)


def build_parser() -> argparse.ArgumentParser:
    parser = arguments.Parser(prog="python -m study", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    for add in (_report_commands, _pipeline_commands, _verify_command, _simulate_command, _describe_command,
                _validate_command, _bench_command):
        add(sub)
    for name, example in EXAMPLES.items():  # every command's --help ends with one example
        command = sub.choices[name]
        command.formatter_class = argparse.RawDescriptionHelpFormatter
        command.epilog = f"example:\n  {example}"
    return parser


def _report_commands(sub) -> None:
    """initial, errata, report: from the equations or the saved results into the report folder."""
    for name, func, text in (
        ("initial", cli_pipeline.initial, "consistent initial conditions and the printed ones' residuals"),
        ("errata", cli_pipeline.errata, "check the papers' printed formulas against the derived equations"),
        ("report", cli_pipeline.report, "figures, tables, index.md and report.html from saved results only"),
    ):
        p = sub.add_parser(name, help=text)
        p.add_argument("--out", type=Path, default=REPORTS, help="report folder (default: reports)")
        p.set_defaults(func=func)


def _pipeline_commands(sub) -> None:
    """run, reproduce: the case lists through the pipeline."""
    for name, func, text in (
        ("run", cli_pipeline.run, "run the studies' cases (reference/cases/*.toml) that are not cached, write their tables"),
        ("reproduce", cli_pipeline.reproduce, "initial conditions, errata, every study, and the report"),
    ):
        p = sub.add_parser(name, help=text)
        p.add_argument("--out", type=Path, default=REPORTS, help="report folder (default: reports)")
        p.add_argument("--workers", type=int, default=None,
                       help="local worker processes (default: $STUDY_WORKERS or the CPUs available)")
        p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="run the cases on the Dask cluster at ADDRESS (e.g. tcp://host:8786)")
        p.add_argument("--cases", type=Path, default=CASES_DIR, metavar="DIR",
                       help="folder of case lists (default: reference/cases)")
        if name == "run":
            p.add_argument("studies", nargs="*", help="studies to run (default: every case list)")
        else:
            p.set_defaults(studies=None)
        p.set_defaults(func=func)



def _verify_command(sub) -> None:
    p = sub.add_parser("verify", help="regenerate every table and compare it with reports/tables (reference/verify.toml); "
                                      "--perturb: rerun every in-house case from a state moved by a few ulps instead")
    p.add_argument("studies", nargs="*", help="studies to check (default: every case list, plus initial and errata)")
    p.add_argument("--out", type=Path, default=REPORTS, help="report folder whose tables/ is the snapshot (default: reports)")
    p.add_argument("--workers", type=int, default=None, help="local worker processes (default: $STUDY_WORKERS or the CPUs)")
    p.add_argument("--cases", type=Path, default=CASES_DIR, metavar="DIR", help="folder of case lists")
    p.add_argument("--perturb", action="store_true",
                   help="the conditioning check: writes <out>/tables/perturbation_check.csv")
    p.add_argument("--ulps", type=int, action="append", default=None,
                   help="perturbation of q(0), qd(0) in ulps, repeatable (default: +4 and -4)")
    p.set_defaults(func=cli_pipeline.verify)



def _mechanism_help() -> str:
    from study.mechanisms import names

    return (f"a study mechanism ({', '.join(names())}) or your own mechanism's .py file (describe(ps), "
            f"its parameters in a .toml beside it)")


def _simulate_command(sub) -> None:
    """simulate: one in-house run, its flags the keyword arguments of study.simulate."""
    from study.solver.accelerations import ACCELERATION_SOLVERS
    from study.solver.stabilization import SIGN_FUNCTIONS, STABILIZATIONS

    from study.run_arguments import BACKENDS, DEFAULT_OUTPUT_STEP, FIXED_STEP, INTEGRATOR_NAMES
    from study.simulate import simulate
    from study.solver.friction import DEFAULT_EPS, FRICTION_TREATMENTS

    defaults = {k: v.default for k, v in inspect.signature(simulate).parameters.items()}

    p = sub.add_parser("simulate", help="run one case and save its result (CSV + JSON)")
    p.add_argument("mechanism", help=_mechanism_help())
    p.add_argument("--variant", "--case", dest="variant", default="seed",
                   help="parameter-set variant (default: seed; --case is an alias)")
    p.add_argument("--method", default="none", choices=list(STABILIZATIONS))
    p.add_argument("--integrator", default="RK45", choices=list(INTEGRATOR_NAMES),
                   help="an ODE integrator (scipy's, or RK4 with --step), or ALI3P: the index-3 augmented Lagrangian "
                        "with mass-orthogonal projections (--step; passes singular positions)")
    p.add_argument("--acceleration-solver", default=None, choices=list(ACCELERATION_SOLVERS),
                   help="accelerations of the ODE integrators (default multiplier)")
    p.add_argument("--backend", default=defaults["backend"], choices=list(BACKENDS),
                   help=f"reference: Python + scipy; compiled: numba, described mechanisms (default {defaults['backend']})")
    p.add_argument("--friction", default=None, choices=[*FRICTION_TREATMENTS, "none"],
                   help="Coulomb friction at the sliding contacts and pins (default: the parameter set's "
                        "friction_treatment, else exact stick/slip, for every entry with friction; none without any)")
    p.add_argument("--friction-eps", type=float, default=None, metavar="EPS",
                   help=f"regularization width [m/s] of 'regularized', stick band of 'sign' (default {DEFAULT_EPS:g})")
    p.add_argument("--friction-sgn", default=None, choices=[k for k in SIGN_FUNCTIONS if k != "sign"],
                   help="smooth sgn of 'regularized' (default tanh)")
    p.add_argument("--rtol", type=float, default=None, help="relative tolerance (adaptive integrators; default 1e-8)")
    p.add_argument("--atol", type=float, default=None, help="absolute tolerance (adaptive integrators; default 1e-10)")
    p.add_argument("--max-evaluations", type=float, default=None,
                   help="bound on evaluations (default in reference/tolerances.toml); confirms a large fixed-step run")
    p.add_argument("--step", type=float, default=None, help=f"fixed step h [s] ({', '.join(FIXED_STEP)} only)")
    p.add_argument("--t-end", type=float, default=20.0, help="end time [s] (default 20)")
    p.add_argument("--output-step", type=float, default=None,
                   help=f"spacing of the saved samples [s] (default {DEFAULT_OUTPUT_STEP:g})")
    p.add_argument("--option", action="append", metavar="KEY=VALUE",
                   help="option of the --method, e.g. omega=10, d=1, Lambda=10, sgn=tanh, width=1e-8, max_iter=5")
    p.add_argument("--out", required=True, help="output path (writes .csv and .json)")
    p.set_defaults(func=_simulate)



def _describe_command(sub) -> None:
    p = sub.add_parser("describe", help="print a mechanism's bodies, joints, loads, variants and consistent initial state")
    p.add_argument("mechanism", help=_mechanism_help())
    p.add_argument("--variant", "--case", dest="variant", default="seed", help="parameter-set variant (default: seed)")
    p.set_defaults(func=_describe)



def _validate_command(sub) -> None:
    p = sub.add_parser("validate", help="run your own mechanism (describe(ps) in a .py file, its parameters in a "
                                        ".toml beside it) through every in-house method and Exudyn; write a report")
    p.add_argument("file", type=Path, help="the mechanism's Python file")
    p.add_argument("--variant", default="seed", help="parameter-set variant (default: seed)")
    p.add_argument("--t-end", dest="t_end", type=float, default=None, help="horizon [s] (default 1)")
    p.add_argument("--output-step", dest="output_step", type=float, default=None, help="sample spacing [s] (default 0.01)")
    p.add_argument("--h", type=float, default=None, help="Exudyn's largest step [s], then h/2, h/4 (default 2e-3)")
    p.add_argument("--levels", type=int, default=None, help="number of Exudyn steps halving from --h (default 3)")
    p.add_argument("--friction-eps", dest="friction_eps", type=float, default=None,
                   help="width of the regularized friction law compared with Exudyn [m/s] (default 1e-3)")
    p.add_argument("--out", type=Path, default=None, help="report folder (default validation/<file name>)")
    p.set_defaults(func=_validate)



def _bench_command(sub) -> None:
    from study.bench.command import add_arguments as bench_arguments

    p = sub.add_parser("bench", help="benchmark: accuracy per CPU second, in-house vs Exudyn (same as "
                                     "python -m study.bench)")
    bench_arguments(p).set_defaults(func=_bench)


def main(argv: list[str] | None = None) -> int:
    """Run a command. A user error or a failed run is one line on stderr and exit code 2 (1 for a run
    that failed); ``STUDY_TRACEBACK=1`` shows the traceback instead."""
    from study.errors import SimulationError
    from study.solver.friction import PainleveError
    from study.model.initial_state import InitialConditionError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (SimulationError, PainleveError, InitialConditionError) as exc:
        if os.environ.get("STUDY_TRACEBACK"):
            raise
        print(f"error: the run failed: {_one_line(exc)}", file=sys.stderr)
        return 1
    except (ValueError, LookupError, OSError) as exc:  # bad values, names, paths, permissions, scheduler
        if os.environ.get("STUDY_TRACEBACK"):
            raise
        print(f"error: {_one_line(exc)}", file=sys.stderr)
        return 2


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if isinstance(exc, (ValueError, RuntimeError)) else f"{type(exc).__name__}: {text}"


if __name__ == "__main__":
    sys.exit(main())
