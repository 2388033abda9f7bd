"""Command-line entry points: ``python -m study <command>``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPORTS = Path("reports")


def _initial(args: argparse.Namespace) -> int:
    from study.initial_report import initial_conditions_table, write_initial_conditions

    path = write_initial_conditions(args.out / "tables")
    with_pd = initial_conditions_table()
    print(with_pd.to_string(index=False))
    print(f"wrote {path}")
    return 0


def _errata(args: argparse.Namespace) -> int:
    from study.errata import write_errata

    path = write_errata(args.out / "tables")
    print(path.read_text() if path.suffix == ".md" else f"wrote {path}")
    return 0


def _simulate(args: argparse.Namespace) -> int:
    from study.simulate import simulate

    options = {}
    for item in args.option or []:
        key, _, value = item.partition("=")
        if not value:
            raise SystemExit(f"--option {item!r}: expected KEY=VALUE (e.g. omega=10 or sgn=tanh)")
        try:
            options[key] = float(value)
        except ValueError:
            options[key] = value
    try:
        result = simulate(args.mechanism, variant=args.case, t_end=args.t_end, method=args.method,
                          integrator=args.integrator, rtol=args.rtol, atol=args.atol, step=args.step,
                          acceleration_solver=args.acceleration_solver, **options)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    path = result.save(args.out)
    s = result.summary()
    print(f"{args.mechanism}/{args.case} {args.method} {args.integrator}: max|Phi| = {s['max_abs_phi']:.3e}, "
          f"energy error = {s['energy_error']:.3e} J ({s['energy_error_relative']:.2e} of max T), "
          f"CPU {s['cpu_seconds']:.3f} s, {result.stats['nfev']} evaluations -> {path}")
    return 0


def _sliding_mode(args: argparse.Namespace) -> int:
    from study.model.compile import cache_dir
    from study.studies.sliding_mode import run_study

    for path in run_study(args.out / "tables", cache_dir() / "results"):
        print(f"wrote {path}")
    return 0


def _slider_crank(args: argparse.Namespace) -> int:
    from study.model.compile import cache_dir
    from study.studies.slider_crank import run_study

    summary = run_study(cache_dir() / "results" / "slider_crank")
    path = args.out / "tables" / "slider_crank_summary.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    # CPU time is machine-dependent; it stays in each saved result's JSON, not in the compared table
    summary.drop(columns=["cpu_seconds"]).to_csv(path, index=False, float_format="%.6g")
    print(f"wrote {path}")
    return 0


def _report(args: argparse.Namespace) -> int:
    from study.model.compile import cache_dir
    from study.report import build_report

    print(f"report: {build_report(args.out, cache_dir()).resolve()}")
    return 0


def _reproduce(args: argparse.Namespace) -> int:
    for step in (_initial, _errata, _sliding_mode, _slider_crank, _report):
        code = step(args)
        if code:
            return code
    print(f"reports written under {args.out.resolve()}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m study", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    for name, func, text in (
        ("initial", _initial, "consistent initial conditions and the printed ones' residuals"),
        ("errata", _errata, "check the papers' printed formulas against the derived equations"),
        ("report", _report, "figures, tables, index.md and report.html from saved results only"),
        ("reproduce", _reproduce, "run everything that exists and write reports/"),
    ):
        p = sub.add_parser(name, help=text)
        p.add_argument("--out", type=Path, default=REPORTS, help="report folder (default: reports)")
        p.set_defaults(func=func)
    p = sub.add_parser("slider-crank", help="000's slider-crank with Coulomb friction: variants x treatments")
    p.add_argument("--out", type=Path, default=REPORTS, help="report folder (default: reports)")
    p.set_defaults(func=_slider_crank)
    p = sub.add_parser("sliding-mode", help="001's drift claims over methods, sgn approximations and integrators")
    p.add_argument("--out", type=Path, default=REPORTS, help="report folder (default: reports)")
    p.set_defaults(func=_sliding_mode)

    from study.mechanisms import MECHANISMS
    from study.solver.accelerations import ACCELERATION_SOLVERS
    from study.solver.integrate import INTEGRATORS
    from study.solver.stabilization import STABILIZATIONS

    p = sub.add_parser("simulate", help="run one case and save its result (CSV + JSON)")
    p.add_argument("mechanism", choices=list(MECHANISMS))
    p.add_argument("--case", default="seed", help="parameter-set variant (default: seed)")
    p.add_argument("--method", default="none", choices=list(STABILIZATIONS))
    p.add_argument("--integrator", default="RK45", choices=list(INTEGRATORS))
    p.add_argument("--acceleration-solver", default="multiplier", choices=list(ACCELERATION_SOLVERS))
    p.add_argument("--rtol", type=float, default=1e-8)
    p.add_argument("--atol", type=float, default=1e-10)
    p.add_argument("--step", type=float, default=None, help="fixed step h (RK4)")
    p.add_argument("--t-end", type=float, default=20.0)
    p.add_argument("--option", action="append", metavar="KEY=VALUE",
                   help="stabilization option, e.g. omega=10, d=1, Lambda=10, sgn=tanh, width=1e-8")
    p.add_argument("--out", type=Path, required=True, help="output path (writes .csv and .json)")
    p.set_defaults(func=_simulate)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
