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


def _reproduce(args: argparse.Namespace) -> int:
    for step in (_initial, _errata):
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
        ("reproduce", _reproduce, "run everything that exists and write reports/"),
    ):
        p = sub.add_parser(name, help=text)
        p.add_argument("--out", type=Path, default=REPORTS, help="report folder (default: reports)")
        p.set_defaults(func=func)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
