"""Are the published tables reproducible? Two checks, one comparison rule.

1. :func:`verify_tables` (``make verify``, ``python -m study verify``): regenerate every table
   (initial conditions, errata, every study's cases through the pipeline) into a scratch folder and
   compare it with the snapshot in ``reports/tables`` (on a fresh clone: the committed one); a friction run
   whose energy balance the regenerated ``energy_balance`` table flags fails it too.
2. :func:`perturbation_check` (``python -m study verify --perturb``): rerun every in-house case of the
   studies (references included) with its initial state q(0), qd(0) moved by a few ulps
   (``perturb_ulps``, handled by :func:`study.pipeline.run_case`), rebuild each table from the
   perturbed runs and compare it with the table from the nominal runs. Last-bit differences between
   machines (libm, BLAS, compiler) act like such a perturbation, so a metric that passes here is
   fixed, to its tolerance, by the inputs alone; one that fails is not a result to the digits it
   shows. The check writes ``reports/tables/perturbation_check.csv``.

Both compare two tables cell by cell with :func:`compare_tables` and the per-column rules of
``reference/verify.toml`` (each with its reason):

- a numeric cell passes if |a - b| <= atol + rtol |a|, or, for a rule with ``decades``, if a and b have
  the same sign and |log10(b / a)| <= decades (a quantity reproducible only to its order of magnitude);
- a string cell must be identical (verdicts such as pass/fail, phases, labels), except a list of
  numbers separated by ';' (event times), compared number by number with the column's tolerance;
- a column whose rule says ``compare = false`` is reported, not judged (it must say why).

Exudyn cases are not perturbed: their initial state is built inside ``study.exudyn_models`` from the
parameter set; the perturbed tables use their nominal runs.
"""

from __future__ import annotations

import math
import shutil
import sys
import tempfile
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from study.locations import REFERENCE_DIR
from study.output_folder import check_output_folder, claim_output_folder, require_output_folder
from study.pipeline import (CASES_DIR, Case, MissingResult, Store, check_tables, load_case_lists, make_executor,
                            read_table, run_cases, write_tables)
from study.pipeline.summaries import energy_flags

RULES_PATH = REFERENCE_DIR / "verify.toml"
# Tables whose content is about the check itself or about failed runs, not a published result.
# singular_four_bar_scaling: written by a one-off script (python -m study.studies.n_four_bar_scaling), not by the
# pipeline, and its columns are CPU times of this host.
SKIPPED_TABLES = ("failed_cases", "perturbation_check", "singular_four_bar_scaling")


# --- rules ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Rule:
    """How one column is compared: |a - b| <= atol + rtol |a| (or within ``decades`` of a in log10), or not at
    all (compare = False)."""

    rtol: float
    atol: float
    reason: str
    compare: bool = True
    name: str = "default"
    decades: float = 0.0  # > 0: also passes if |log10(b / a)| <= decades (same sign)


@lru_cache(maxsize=None)
def rules(path: Path = RULES_PATH) -> dict:
    """The checked rule file: [default], [class.*], [column], [table.*] and [[rows]] (see the file's header)."""
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    for key in ("default", "class", "column"):
        if key not in data:
            raise ValueError(f"{path}: missing [{key}]")
    for where, entry in [("default", data["default"]), *((f"class.{k}", v) for k, v in data["class"].items())]:
        missing = {"rtol", "atol", "reason"} - set(entry) if entry.get("compare", True) else {"reason"} - set(entry)
        if missing:
            raise ValueError(f"{path}: [{where}] needs {sorted(missing)}")
    for col, cls in data["column"].items():
        if cls not in data["class"]:
            raise ValueError(f"{path}: column {col!r} names class {cls!r}; known: {', '.join(data['class'])}")
    for i, entry in enumerate(data.get("rows", [])):
        missing = {"table", "where", "columns", "class"} - set(entry)
        if missing:
            raise ValueError(f"{path}: [[rows]] entry {i + 1} needs {sorted(missing)}")
        if entry["class"] not in data["class"]:
            raise ValueError(f"{path}: [[rows]] entry {i + 1} names class {entry['class']!r}")
    return data


def rule_for(table: str, column: str, path: Path = RULES_PATH, row: Mapping | None = None) -> Rule:
    """The rule of ``column`` in ``table`` (and, if given, in this ``row`` of it): a [[rows]] entry whose
    ``where`` cells all equal the row's, else the [table.<table>] entry, else [column], else [default]."""
    data = rules(path)
    name = None
    if row is not None:
        name = next((e["class"] for e in data.get("rows", []) if e["table"] == table and column in e["columns"]
                     and all(row.get(k) == v for k, v in e["where"].items())), None)
    name = name or data.get("table", {}).get(table, {}).get(column) or data["column"].get(column)
    entry = data["class"][name] if name else data["default"]
    return Rule(float(entry.get("rtol", 0.0)), float(entry.get("atol", 0.0)), entry["reason"],
                bool(entry.get("compare", True)), name or "default", float(entry.get("decades", 0.0)))


# --- comparing two tables ------------------------------------------------------------------------
def _numbers(cell: str) -> list[float] | None:
    """The numbers of a ';'-separated list ('0.0036;4.434;...(+3)'), or None if it is not one."""
    parts = [p for p in str(cell).split(";") if p and not p.startswith("...")]
    try:
        return [float(p) for p in parts]
    except ValueError:
        return None


def _is_number(x) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)


def _cell_difference(a, b, rule: Rule) -> tuple[float, float, float]:
    """(|a - b|, |a - b| / |a|, margin) for one cell: margin is how many times the difference fits into what the rule
    allows (inf for equal cells, 0 for a difference no tolerance covers: a NaN against a number, a changed string);
    the cell is within its rule if the margin is >= 1. NaN equals NaN."""
    if _is_number(a) and _is_number(b):
        fa, fb = float(a), float(b)
        if math.isnan(fa) or math.isnan(fb):
            same = math.isnan(fa) and math.isnan(fb)
            return (0.0, 0.0, math.inf) if same else (math.inf, math.inf, 0.0)
        if math.isinf(fa) or math.isinf(fb):
            return (0.0, 0.0, math.inf) if fa == fb else (math.inf, math.inf, 0.0)
        d = abs(fa - fb)
        rel = d / abs(fa) if fa else (0.0 if d == 0 else math.inf)
        if d == 0:
            return 0.0, 0.0, math.inf
        margin = (rule.atol + rule.rtol * abs(fa)) / d
        if rule.decades > 0 and fa * fb > 0:
            margin = max(margin, rule.decades / abs(math.log10(fb / fa)) if fa != fb else math.inf)
        return d, rel, margin
    if isinstance(a, str) and isinstance(b, str):
        if a == b:
            return 0.0, 0.0, math.inf
        na, nb = _numbers(a), _numbers(b)
        if na is None or nb is None or len(na) != len(nb) or a.count("...") != b.count("..."):
            return math.inf, math.inf, 0.0
        worst = (0.0, 0.0, math.inf)
        for x, y in zip(na, nb):
            d = _cell_difference(x, y, rule)
            worst = (max(worst[0], d[0]), max(worst[1], d[1]), min(worst[2], d[2]))
        return worst
    if type(a) is type(b) and a == b:  # booleans (verdicts) and other identical values
        return 0.0, 0.0, math.inf
    same = not isinstance(a, str) and not isinstance(b, str) and bool(pd.isna(a)) and bool(pd.isna(b))
    return (0.0, 0.0, math.inf) if same else (math.inf, math.inf, 0.0)


def compare_tables(table: str, old: pd.DataFrame, new: pd.DataFrame, rules_path: Path = RULES_PATH) -> pd.DataFrame:
    """One row per column of ``old`` and rule class applied in it (a [[rows]] entry gives some of a column's cells
    another class): the cell with the smallest margin (allowed / found, see :func:`_cell_difference`), its absolute
    and relative difference to ``new`` and its row, and whether every cell is within its rule.

    Tables must have the same columns and rows (same order); a missing column or a different row
    count is a failed row with ``column`` '<shape>'.
    """
    rows = []
    if list(old.columns) != list(new.columns) or len(old) != len(new):
        rows.append({"table": table, "column": "<shape>", "rule": "identical", "rtol": 0.0, "atol": 0.0,
                     "decades": 0.0, "worst_abs_diff": math.inf, "worst_rel_diff": math.inf, "margin": 0.0,
                     "worst_row": -1, "compared": True, "passed": False,
                     "note": f"columns {list(old.columns)} rows {len(old)} vs columns {list(new.columns)} rows {len(new)}"})
        return pd.DataFrame(rows)
    records = old.to_dict("records")
    for col in old.columns:
        per_rule: dict[str, dict] = {}
        for i, (a, b) in enumerate(zip(old[col].tolist(), new[col].tolist())):
            rule = rule_for(table, col, rules_path, records[i])
            entry = per_rule.setdefault(rule.name, {"rule": rule, "abs": 0.0, "rel": 0.0, "margin": math.inf, "row": -1})
            if not rule.compare:
                continue
            d_abs, d_rel, margin = _cell_difference(a, b, rule)
            if margin < entry["margin"] or (entry["row"] < 0 and (d_abs, d_rel) > (entry["abs"], entry["rel"])):
                entry.update(abs=d_abs, rel=d_rel, row=i, margin=min(margin, entry["margin"]))
        if not per_rule:   # an empty table: the column's own rule, nothing compared
            rule = rule_for(table, col, rules_path)
            per_rule[rule.name] = {"rule": rule, "abs": 0.0, "rel": 0.0, "margin": math.inf, "row": -1}
        for name, e in per_rule.items():
            rule = e["rule"]
            rows.append({"table": table, "column": col, "rule": name, "rtol": rule.rtol, "atol": rule.atol,
                         "decades": rule.decades, "worst_abs_diff": e["abs"], "worst_rel_diff": e["rel"],
                         "margin": e["margin"], "worst_row": e["row"], "compared": rule.compare,
                         "passed": bool(e["margin"] >= 1 or not rule.compare), "note": ""})
    return pd.DataFrame(rows)


def compare_folders(old_dir: Path, new_dir: Path, names: Iterable[str] | None = None,
                    rules_path: Path = RULES_PATH) -> pd.DataFrame:
    """:func:`compare_tables` for every ``*.csv`` of ``old_dir`` (or the given table names) against
    the same file in ``new_dir``; a table missing from ``new_dir`` is a failure."""
    names = sorted(p.stem for p in Path(old_dir).glob("*.csv")) if names is None else list(names)
    parts = []
    for name in names:
        if name in SKIPPED_TABLES:
            continue
        new_path = Path(new_dir) / f"{name}.csv"
        if not new_path.exists():
            parts.append(pd.DataFrame([{"table": name, "column": "<missing>", "rule": "identical", "passed": False,
                                        "compared": True, "worst_abs_diff": math.inf, "worst_rel_diff": math.inf,
                                        "note": f"not regenerated: {new_path}"}]))
            continue
        parts.append(compare_tables(name, _read(Path(old_dir) / f"{name}.csv"), _read(new_path), rules_path))
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


def _read(path: Path) -> pd.DataFrame:
    """A table checked against its record (:func:`study.pipeline.read_table`); strings kept as written ('1e-4'
    labels stay strings only if pandas cannot parse them: same on both sides)."""
    return read_table(path, keep_default_na=True)


def worst_per_table(comparison: pd.DataFrame) -> pd.DataFrame:
    """Per table: the compared column with the largest relative difference, and whether all passed."""
    rows = []
    for table, part in comparison.groupby("table", sort=True):
        judged = part[part["compared"]]
        finite = judged.replace([np.inf], np.nan)
        i = finite["worst_rel_diff"].idxmax() if finite["worst_rel_diff"].notna().any() else judged.index[0]
        failed = part.loc[~part["passed"], "column"].tolist()
        rows.append({"table": table, "worst_column": part.loc[i, "column"],
                     "worst_abs_diff": part.loc[i, "worst_abs_diff"], "worst_rel_diff": part.loc[i, "worst_rel_diff"],
                     "smallest_margin": judged["margin"].min() if len(judged) else math.inf,
                     "passed": not failed, "failed_columns": ";".join(failed)})
    return pd.DataFrame(rows)


# --- make verify ---------------------------------------------------------------------------------
def regenerate(out_dir: Path, cache_root: Path, studies: Sequence[str] | None = None, workers: int = 1,
               cases_dir: Path = CASES_DIR) -> Path:
    """Write every table again into ``out_dir/tables`` (initial conditions, errata, the studies)."""
    from study.errata import write_errata
    from study.initial_report import write_initial_conditions
    from study.pipeline import run_pipeline

    claim_output_folder(out_dir)
    tables = Path(out_dir) / "tables"
    if studies is None:
        write_initial_conditions(tables)
        write_errata(tables)
    run_pipeline(Path(out_dir), cache_root, studies=studies, workers=workers, folder=cases_dir)
    return tables


def verify_tables(snapshot: Path, cache_root: Path, studies: Sequence[str] | None = None, workers: int = 1,
                  cases_dir: Path = CASES_DIR, stream=None) -> tuple[bool, pd.DataFrame]:
    """Regenerate into a scratch folder, compare with ``snapshot``; print the worst difference per table."""
    stream = stream or sys.stdout
    with tempfile.TemporaryDirectory(prefix="verify-") as tmp:
        regenerated = regenerate(Path(tmp), cache_root, studies, workers, cases_dir)
        if studies is None:
            names = None
        else:
            names = sorted({p.stem for p in regenerated.glob("*.csv")} - set(SKIPPED_TABLES))
        comparison = compare_folders(snapshot, regenerated, names)
        flags = energy_flags(_read(regenerated / "energy_balance.csv"))
    _print(worst_per_table(comparison), comparison, "make verify: regenerated tables against the snapshot", stream)
    for name, why in flags.items():   # a failed check of the regenerated runs, whatever the snapshot holds
        print(f"FAILED energy balance of {name}: {why}", file=stream)
    return bool(comparison["passed"].all()) and not flags, comparison


def _print(worst: pd.DataFrame, comparison: pd.DataFrame, title: str, stream) -> None:
    print(title, file=stream)
    with pd.option_context("display.width", 200, "display.max_colwidth", 60):
        print(worst.to_string(index=False, float_format=lambda x: f"{x:.3g}"), file=stream)
    failed = comparison[~comparison["passed"]]
    if len(failed):
        print("FAILED columns:", file=stream)
        print(failed[["table", "column", "rule", "rtol", "atol", "decades", "worst_abs_diff", "worst_rel_diff",
                      "margin", "worst_row", "note"]].to_string(index=False), file=stream)


# --- the perturbation check ----------------------------------------------------------------------
DEFAULT_ULPS = (4, -4)


def perturbed(case: Case, ulps: int) -> Case:
    """The same case with ``perturb_ulps`` added to its options (its own key, its own saved result)."""
    options = dict(case.options)
    options["perturb_ulps"] = int(ulps)
    return Case(case.study, case.group, case.engine, case.mechanism, case.variant, case.t_end,
                tuple(sorted(options.items())), case.labels, case.expect_error)


def perturbation_check(reports_dir: Path, cache_root: Path, studies: Sequence[str] | None = None,
                       ulps: Sequence[int] = DEFAULT_ULPS, workers: int = 1, cases_dir: Path = CASES_DIR,
                       stream=None) -> tuple[bool, pd.DataFrame]:
    """Rerun every in-house case with q(0), qd(0) moved by each of ``ulps``; compare every table built
    from the perturbed runs with the one from the nominal runs. Writes
    ``reports_dir/tables/perturbation_check.csv`` (one row per table, column and perturbation)."""
    import importlib

    stream = stream or sys.stderr
    store = Store(Path(cache_root) / "runs")
    case_lists = load_case_lists(cases_dir, studies)
    parts = []
    with make_executor(workers) as executor:
        for cl in case_lists:
            module = importlib.import_module(cl.summary)
            inhouse = [c for c in cl.cases if c.engine == "inhouse"]
            run_cases(cl.cases, store, executor, title=f"{cl.study} nominal", stream=stream)
            try:
                nominal = module.summarize(list(cl.cases), store.load)
            except MissingResult as exc:
                raise RuntimeError(f"{cl.study}: a nominal run is missing ({exc})") from None
            for k in ulps:
                twins = {c: perturbed(c, k) for c in inhouse}
                run_cases(twins.values(), store, executor, title=f"{cl.study} perturbed {k:+d} ulps", stream=stream)
                moved = module.summarize(list(cl.cases), lambda c, twins=twins: store.load(twins.get(c, c)))
                for name, table in nominal.items():
                    if name.endswith("_timing"):
                        continue
                    if name not in moved:
                        raise RuntimeError(f"{cl.study}: table {name} not rebuilt from the perturbed runs")
                    # compare the tables as written (6 significant digits), as make verify does
                    a, b = _roundtrip(table), _roundtrip(moved[name])
                    part = compare_tables(name, a, b)
                    part.insert(0, "perturb_ulps", k)
                    part.insert(0, "study", cl.study)
                    parts.append(part)
    full = pd.concat(parts, ignore_index=True)
    result = full.drop(columns=["worst_row", "note"])
    claim_output_folder(reports_dir)
    write_tables({"perturbation_check": result}, reports_dir, f"python -m study verify --perturb --out {reports_dir}")
    _print(worst_per_table(result), full, f"perturbation check ({', '.join(f'{k:+d}' for k in ulps)} ulps)",
           sys.stdout)
    return bool(result["passed"].all()), result


def _roundtrip(frame: pd.DataFrame) -> pd.DataFrame:
    """A table as :func:`study.pipeline.write_tables` writes it and :func:`_read` reads it back."""
    from io import StringIO

    from study.pipeline import TABLE_FLOAT_FORMAT

    return pd.read_csv(StringIO(frame.to_csv(index=False, float_format=TABLE_FLOAT_FORMAT, lineterminator="\n")))


def copy_snapshot(tables_dir: Path, dest: Path) -> Path:
    """Copy the snapshot's tables before anything regenerates them."""
    dest = Path(dest)
    shutil.copytree(tables_dir, dest, dirs_exist_ok=True)
    return dest


def main_verify(reports_dir: Path, cache_root: Path, studies: Sequence[str] | None, workers: int,
                perturb: bool, ulps: Sequence[int] | None, cases_dir: Path = CASES_DIR) -> int:
    """``python -m study verify``: 0 if every compared column is within its rule, 1 otherwise."""
    if perturb:
        check_output_folder(reports_dir)   # before any run: it writes tables/perturbation_check.csv there
        ok, _ = perturbation_check(reports_dir, cache_root, studies, tuple(ulps or DEFAULT_ULPS), workers, cases_dir)
        return 0 if ok else 1
    require_output_folder(reports_dir)   # the snapshot: a report folder study wrote, every table as recorded
    if not (Path(reports_dir) / "tables").is_dir():
        raise ValueError(f"--out {reports_dir}: no tables/ folder, so no snapshot to compare with")
    check_tables(Path(reports_dir) / "tables")
    with tempfile.TemporaryDirectory(prefix="snapshot-") as tmp:
        snapshot = copy_snapshot(Path(reports_dir) / "tables", Path(tmp) / "tables")
        ok, _ = verify_tables(snapshot, cache_root, studies, workers, cases_dir)
    return 0 if ok else 1
