"""The study's cases as data, run through an on-disk cache keyed by everything that affects them.

A *case list* is a TOML file ``reference/cases/<study>.toml``::

    [study]
    description = "what the study asks"
    summary = "study.studies.sliding_mode"      # module with summarize(cases, load) -> {table: DataFrame}

    [[group]]
    name = "reference"                          # readable, unique within the study
    engine = "inhouse"                          # or "exudyn"
    mechanism = "quick_return"
    variant = "seed"
    t_end = 20.0
    options = { integrator = "DOP853", rtol = 1e-12, method = "projection" }
    # a value "@key" (or "@table:key") is the entry of reference/tolerances.toml (or <table>.toml)
    # optional: the cartesian product of these lists; a list entry that is a table is merged into
    # the options (its 'label' names it), a scalar sets the option of that name. The keys 'variant',
    # 'mechanism' and 't_end' set those fields instead of an option.
    sweep = { omega = [1.0, 10.0], d = [0.5, 1.0] }
    # optional: drop the combinations whose options contain all entries of one of these tables
    exclude = [ { integrator = "LSODA", method = "projection" } ]
    # optional (engine 'inhouse'): the backend of every case of the group ('reference' or 'compiled',
    # study.simulate's backend; a sweep entry may state its own), and for a compiled group every n-th
    # compiled case (the first, the (n+1)-th, ...) also run on the reference path: the pairs are checked
    # to agree (CaseList.samples, tables/
    # backend_agreement.csv; tests/test_backend_samples.py) and are not part of the study's cases
    backend = "compiled"
    reference_sample = 10

Options are the keyword arguments of :func:`study.simulate.simulate` (engine 'inhouse'; plus
``initial = "printed"`` to start from the paper's printed state instead of the consistent one) or of
:func:`study.exudyn_models.run` (engine 'exudyn', e.g. ``h``, ``solver``).

A case's key hashes its specification, the SHA-256 of its parameter set, the source of the code
that computes it (model, solver, mechanisms, and the Exudyn models for that engine) and the versions
of the numerical packages. :class:`Store` keeps one saved result per key; :func:`run_cases` runs
whatever is not stored yet on an executor (a local process pool, or a Dask cluster), saves each
result as it arrives (atomically: an interrupted run leaves no half-written result and resumes
where it stopped) and records failed cases with their error without stopping the others.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import itertools
import json
import os
import sys
import time
import tomllib
import traceback
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Iterable, Iterator, Mapping

import numpy as np
import pandas as pd

from study.errors import ResultIntegrityError
from study.integrity import atomic_write, data_rows, read_json, sha256_text, verify_text
from study.params import REFERENCE_DIR, load_parameters
from study.reference_data import tolerance
from study.results import SimulationResult, package_versions
from study.sources import source_files, source_hash

CASES_DIR = REFERENCE_DIR / "cases"
ENGINES = ("inhouse", "exudyn")
# Source that determines a case's result, per engine (folders or files under study/). The report,
# the studies' summaries and the command line do not change a result and are left out.
_COMMON_CODE = ("model", "solver", "mechanisms", "params.py", "results.py", "reference_data.py")
CODE_PATHS = {
    "inhouse": _COMMON_CODE + ("simulate.py", "fast"),
    "exudyn": _COMMON_CODE + ("exudyn_models",),
}
NUMERIC_PACKAGES = {"inhouse": ("numpy", "scipy", "sympy", "numba"), "exudyn": ("numpy", "scipy", "sympy", "exudyn")}
PIPELINE_RECORD = "pipeline_record.json"  # what the last pipeline run did, in the cache root
_GROUP_KEYS = {"name", "engine", "mechanism", "variant", "t_end", "options", "sweep", "exclude", "backend",
               "reference_sample"}
BACKENDS = ("reference", "compiled")
SAMPLE_SUFFIX = ":reference_sample"   # group name of the reference-path twins of a compiled group
_FIELD_SWEEPS = ("mechanism", "variant", "t_end")


class CaseListError(ValueError):
    """A case list is malformed; the message names the file, the group and the value."""


class MissingResult(LookupError):
    """A case has no saved result (not run yet, or it failed)."""


class CorruptResult(MissingResult):
    """A case's saved result failed its check (row count, checksum, JSON): it is not used."""


# --- cases ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Case:
    """One run: mechanism x variant x engine x options, within a named study and group.

    ``options`` and ``labels`` are sorted tuples of (name, value) so a case is hashable; use
    :attr:`kwargs` and :meth:`label` to read them.
    """

    study: str
    group: str
    engine: str
    mechanism: str
    variant: str
    t_end: float
    options: tuple[tuple[str, Any], ...] = ()
    labels: tuple[tuple[str, str], ...] = ()

    @property
    def kwargs(self) -> dict[str, Any]:
        return dict(self.options)

    def label(self, key: str, default: str | None = None) -> str | None:
        return dict(self.labels).get(key, default)

    @property
    def name(self) -> str:
        """Readable name: study/group[label, ...]."""
        inner = ", ".join(f"{k}={v}" for k, v in self.labels)
        return f"{self.study}/{self.group}" + (f" [{inner}]" if inner else "")

    def spec(self) -> dict[str, Any]:
        return {"study": self.study, "group": self.group, "engine": self.engine, "mechanism": self.mechanism,
                "variant": self.variant, "t_end": self.t_end, "options": self.kwargs}

    def key(self) -> str:
        """Hash of everything that affects the result (the study and group names do not)."""
        payload = {
            "engine": self.engine, "mechanism": self.mechanism, "variant": self.variant, "t_end": self.t_end,
            "options": self.kwargs, "parameters": _parameter_hash(self.mechanism, self.variant),
            "code": code_version(self.engine),
        }
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]

    def matches(self, **criteria) -> bool:
        """True if every criterion equals the field, the option or the label of that name."""
        fields, options, labels = vars(self), self.kwargs, dict(self.labels)
        for k, v in criteria.items():
            if k in ("study", "group", "engine", "mechanism", "variant", "t_end"):
                if fields[k] != v:
                    return False
            elif k in options:
                if options[k] != v:
                    return False
            elif labels.get(k) != v:
                return False
        return True


def find(cases: Iterable[Case], **criteria) -> list[Case]:
    """The cases matching every criterion (fields, options or labels), in list order."""
    return [c for c in cases if c.matches(**criteria)]


def find_one(cases: Iterable[Case], **criteria) -> Case:
    """The single case matching the criteria; a LookupError names the criteria otherwise."""
    found = find(cases, **criteria)
    if len(found) != 1:
        raise LookupError(f"{len(found)} cases match {criteria} (expected exactly one)")
    return found[0]


@lru_cache(maxsize=None)
def _parameter_hash(mechanism: str, variant: str) -> str:
    return load_parameters(mechanism, variant).sha256


@lru_cache(maxsize=None)
def code_version(engine: str) -> str:
    """SHA-256 (16 hex) of the source files that compute a result of ``engine`` + numeric package versions."""
    versions = package_versions()
    numeric = json.dumps({p: versions.get(p) for p in NUMERIC_PACKAGES[engine]}, sort_keys=True)
    return source_hash(source_files(*CODE_PATHS[engine]), extra=numeric)[:16]


# --- case lists ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class CaseList:
    """A study's case list: its cases and the module that summarizes them."""

    study: str
    description: str
    summary: str
    cases: tuple[Case, ...]
    path: Path
    report: Mapping[str, Any] = field(default_factory=dict)   # the list's [report] table: its section's choices
    samples: tuple[tuple[Case, Case], ...] = ()   # (compiled case, its reference-path twin), see reference_sample

    @property
    def all_cases(self) -> tuple[Case, ...]:
        """The study's cases and the reference-path twins of its samples (everything the pipeline runs)."""
        return self.cases + tuple(twin for _, twin in self.samples)


def _label(value: Any) -> str:
    if isinstance(value, Mapping):
        return str(value.get("label") or ",".join(f"{k}={v}" for k, v in value.items()))
    return f"{value:g}" if isinstance(value, float) else str(value)


def _resolve(value: Any, where: str) -> Any:
    """A case-list value; the string '@key' (or '@table:key') stands for that entry of
    reference/tolerances.toml (or reference/<table>.toml), so a number kept there is not typed again."""
    if not (isinstance(value, str) and value.startswith("@")):
        return value
    table, _, key = value[1:].rpartition(":")
    try:
        return tolerance(key, table=table or "tolerances")
    except (KeyError, FileNotFoundError) as exc:
        raise CaseListError(f"{where}: {value!r} names no reference entry ({exc})") from None


def _excluded(rule: Mapping, fields: Mapping, options: Mapping, where: str) -> bool:
    """True if every entry of an exclude rule equals the case's field or option of that name."""
    values = {**options, **fields}
    for k, v in rule.items():
        if k not in values and k not in _FIELD_SWEEPS:
            return False  # an option this case does not set: the rule does not apply to it
        if values.get(k) != v:
            return False
    return True


def _check_exclude(g: Mapping, where: str) -> None:
    """Every key of an exclude rule must be a field or an option some case of the group sets."""
    known = set(_FIELD_SWEEPS) | set(g.get("options", {})) | set(g.get("sweep", {}))
    for v in g.get("sweep", {}).values():
        known |= {kk for item in v if isinstance(item, Mapping) for kk in item}
    for rule in g.get("exclude", []):
        unknown = set(rule) - known
        if unknown:
            raise CaseListError(f"{where}: exclude rule {dict(rule)} names {sorted(unknown)}, which no case "
                                f"of the group sets (a misspelling would exclude nothing)")


def _expand_group(study: str, g: Mapping, where: str) -> list[Case]:
    unknown = set(g) - _GROUP_KEYS
    if unknown:
        raise CaseListError(f"{where}: unknown keys {sorted(unknown)}; valid: {sorted(_GROUP_KEYS)}")
    fields = {"mechanism": g.get("mechanism"), "variant": g.get("variant", "seed"),
              "t_end": _resolve(g.get("t_end"), where)}
    engine = g.get("engine", "inhouse")
    if engine not in ENGINES:
        raise CaseListError(f"{where}: engine = {engine!r} is not one of {ENGINES}")
    sweep = g.get("sweep", {})
    for k, values in sweep.items():
        if not isinstance(values, list) or not values:
            raise CaseListError(f"{where}: sweep.{k} = {values!r} must be a non-empty list")
    _check_exclude(g, where)
    backend = g.get("backend")
    if backend is not None and (engine != "inhouse" or backend not in BACKENDS):
        raise CaseListError(f"{where}: backend = {backend!r} must be one of {BACKENDS}, for engine 'inhouse' only")
    cases = []
    for combo in itertools.product(*sweep.values()) if sweep else [()]:
        case_fields, options, labels = dict(fields), {k: _resolve(v, where) for k, v in g.get("options", {}).items()}, []
        for k, v in zip(sweep, combo):
            if isinstance(v, Mapping):
                options.update({kk: _resolve(vv, where) for kk, vv in v.items() if kk != "label"})
            elif k in _FIELD_SWEEPS:
                case_fields[k] = _resolve(v, where)
            else:
                options[k] = _resolve(v, where)
            labels.append((k, _label(v)))
        if any(_excluded(rule, case_fields, options, where) for rule in g.get("exclude", [])):
            continue
        if case_fields["mechanism"] is None or case_fields["t_end"] is None:
            raise CaseListError(f"{where}: 'mechanism' and 't_end' are required")
        if backend is not None:   # a sweep entry's own backend option (e.g. an integrator only the
            options.setdefault("backend", backend)   # reference path has) is stated there and wins
        t_end = case_fields["t_end"]
        if not isinstance(t_end, (int, float)) or not t_end > 0:
            raise CaseListError(f"{where}: t_end = {t_end!r} must be a number > 0 [s]")
        if engine == "exudyn" and "h" not in options:
            raise CaseListError(f"{where}: an Exudyn case needs the step 'h' [s] in its options or sweep")
        cases.append(Case(study, g["name"], engine, case_fields["mechanism"], case_fields["variant"],
                          float(t_end), tuple(sorted(options.items())), tuple(labels)))
    return cases


def _samples(g: Mapping, cases: list[Case], where: str) -> list[tuple[Case, Case]]:
    """Every n-th case of a compiled group (``reference_sample = n``) and its reference-path twin."""
    n = g.get("reference_sample")
    if n is None:
        return []
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise CaseListError(f"{where}: reference_sample = {n!r} must be a whole number >= 1 (every n-th case)")
    if g.get("backend") != "compiled":
        raise CaseListError(f"{where}: reference_sample needs backend = 'compiled' (it samples a compiled group)")
    compiled = [c for c in cases if c.kwargs.get("backend") == "compiled"]
    return [(c, Case(c.study, c.group + SAMPLE_SUFFIX, c.engine, c.mechanism, c.variant, c.t_end,
                     tuple(sorted({**c.kwargs, "backend": "reference"}.items())), c.labels)) for c in compiled[::n]]


def load_case_list(path: Path) -> CaseList:
    """Parse and expand one case list (CaseListError names the file and group of any problem)."""
    path = Path(path)
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    study = path.stem
    head = data.get("study", {})
    if "summary" not in head:
        raise CaseListError(f"{path}: [study] needs 'summary' (the module with summarize())")
    groups = data.get("group", [])
    if not groups:
        raise CaseListError(f"{path}: no [[group]] entries")
    names = [g.get("name") for g in groups]
    if None in names or len(set(names)) != len(names):
        raise CaseListError(f"{path}: every group needs a unique 'name'; got {names}")
    cases, samples = [], []
    for g in groups:
        where = f"{path.name} group {g['name']!r}"
        group_cases = _expand_group(study, g, where)
        cases += group_cases
        samples += _samples(g, group_cases, where)
    report = data.get("report", {})
    if not isinstance(report, dict):
        raise CaseListError(f"{path}: [report] must be a table (the report section's choices), got {report!r}")
    return CaseList(study, head.get("description", ""), head["summary"], tuple(cases), path, report, tuple(samples))


def load_case_lists(folder: Path = CASES_DIR, studies: Iterable[str] | None = None) -> list[CaseList]:
    """Every case list in ``folder`` (sorted by name), or only the named studies.

    A missing folder, or one without case lists, is a CaseListError (never an empty run).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise CaseListError(f"case folder {folder} does not exist (or is not a folder)")
    available = {p.stem: p for p in sorted(folder.glob("*.toml"))}
    if not available:
        raise CaseListError(f"case folder {folder} holds no case lists (*.toml)")
    chosen = list(available) if studies is None else list(studies)
    missing = [s for s in chosen if s not in available]
    if missing:
        raise CaseListError(f"no case list for {missing} in {folder}; available: {', '.join(available)}")
    return [load_case_list(available[s]) for s in chosen]


# --- running one case ----------------------------------------------------------------------------
def run_case(case: Case) -> SimulationResult:
    """Compute one case (in whatever process the executor chose)."""
    if case.engine == "inhouse":
        from study.simulate import simulate

        options = case.kwargs
        initial = options.pop("initial", "consistent")
        ulps = options.pop("perturb_ulps", 0)  # conditioning check (study.verify): q0, qd0 moved by ulps
        if initial == "printed":  # the paper's printed state, used as is (see the parameter file)
            ps = load_parameters(case.mechanism, case.variant)
            # off the constraints on purpose (the study shows what that does): the check would refuse it
            options.update(q0=list(ps.initial.printed_q), qd0=list(ps.initial.printed_qd), check=False)
        elif initial != "consistent":
            raise ValueError(f"case {case.name}: initial = {initial!r} must be 'consistent' or 'printed'")
        if ulps:
            from study.mechanisms import initial_state, load

            if "q0" not in options:
                state = initial_state(*load(case.mechanism, case.variant))
                options.update(q0=state.q, qd0=state.qd)
            options.update({k: np.add(options[k], ulps * np.spacing(np.asarray(options[k], float))) for k in ("q0", "qd0")})
        return simulate(case.mechanism, variant=case.variant, t_end=case.t_end, **options)
    from study import exudyn_models

    options = case.kwargs
    h = options.pop("h")
    return exudyn_models.run(load_parameters(case.mechanism, case.variant), case.t_end, h, **options)


def _run_case_timed(case: Case) -> tuple[SimulationResult, float, str]:
    """Run a case; also returns the wall time and the code version of the process that ran it."""
    t0 = time.perf_counter()
    result = run_case(case)
    return result, time.perf_counter() - t0, code_version(case.engine)


# --- the cache -----------------------------------------------------------------------------------
class Store:
    """Saved results under ``root/<key>.{csv,json}``; failures as ``<key>.failed.json``.

    The file name is the case's key alone: cases with equal inputs (a reference shared by two studies,
    a grid point in two sweeps) share one saved result, whatever their study, group or labels. The
    readable case (study, group, labels) is kept in the JSON's ``meta.case``.
    """

    def __init__(self, root: Path):
        self.root = Path(root)
        self._verified: dict[str, tuple] = {}  # key -> ((mtimes), problem): each file is hashed once

    def base(self, case: Case) -> Path:
        return self.root / case.key()

    def file(self, case: Case, suffix: str) -> Path:
        base = self.base(case)
        return base.with_name(base.name + suffix)

    def problem(self, case: Case) -> str | None:
        """None if the case has a saved result that passes its check, else why not ('not saved' or the check)."""
        json_path = self.file(case, ".json")
        if not json_path.exists():  # the JSON is written last
            return "not saved"
        stamp = (json_path.stat().st_mtime_ns, self.file(case, ".csv").stat().st_mtime_ns
                 if self.file(case, ".csv").exists() else None)
        cached = self._verified.get(case.key())
        if cached is not None and cached[0] == stamp:
            return cached[1]
        try:
            SimulationResult.verify(self.base(case))
            why = None
        except ResultIntegrityError as exc:
            why = str(exc)
        self._verified[case.key()] = (stamp, why)
        return why

    def has(self, case: Case) -> bool:
        """True if the case has a saved result that passes its check (row count, checksum)."""
        return self.problem(case) is None

    def load(self, case: Case) -> SimulationResult:
        why = self.problem(case)
        if why == "not saved":
            failure = self.failure(case)
            why = f"it failed: {failure['error']}" if failure else "it has not been run"
            raise MissingResult(f"no saved result for case {case.name} ({why})")
        if why is not None:
            raise CorruptResult(f"the saved result of case {case.name} is not used: {why}")
        return SimulationResult.load(self.base(case), verify=False)  # just verified

    def discard(self, case: Case) -> None:
        """Remove a saved result that failed its check (so it can never be read)."""
        for suffix in (".json", ".csv"):
            self.file(case, suffix).unlink(missing_ok=True)
        self._verified.pop(case.key(), None)

    def save(self, case: Case, result: SimulationResult) -> Path:
        result.meta["case"] = {**case.spec(), "key": case.key(), "labels": dict(case.labels)}
        path = result.save(self.base(case))
        self._failure_path(case).unlink(missing_ok=True)
        return path

    def _failure_path(self, case: Case) -> Path:
        return self.file(case, ".failed.json")

    def record_failure(self, case: Case, error: str, details: str) -> None:
        path = self._failure_path(case)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(path, json.dumps({"case": case.name, "key": case.key(), "error": error,
                                        "traceback": details}, indent=1))

    def failure(self, case: Case) -> dict | None:
        path = self._failure_path(case)
        if not path.exists():
            return None
        try:
            return read_json(path)
        except ResultIntegrityError as exc:
            return {"case": case.name, "key": case.key(), "error": f"unreadable failure record ({exc})"}


# --- executors and progress ----------------------------------------------------------------------
class InlineExecutor(Executor):
    """Runs each submitted call at once in this process (workers=1: simple tracebacks, no pickling)."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller through the future
            if isinstance(exc, KeyboardInterrupt):
                raise
            future.set_exception(exc)
        return future


@contextlib.contextmanager
def make_executor(workers: int = 2, scheduler: str | None = None) -> Iterator[Executor]:
    """A local process pool with ``workers`` processes, or the Dask cluster at ``scheduler``.

    ``scheduler`` is a Dask scheduler address ('tcp://host:8786') or a ``distributed.Client``.
    """
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError as exc:  # the extra is optional; say how to get it
            raise RuntimeError("--scheduler needs Dask: pip install 'dask[distributed]'") from exc
        try:
            client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
        except OSError as exc:  # unreachable or refusing: name the address, no traceback
            raise OSError(f"scheduler {scheduler!r} cannot be reached: {exc}") from None
        try:
            yield client.get_executor(pure=False)
        finally:
            if client is not scheduler:
                client.close()
        return
    if not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers = {workers!r} must be an integer >= 1")
    if workers == 1:
        yield InlineExecutor()
        return
    with ProcessPoolExecutor(max_workers=workers) as pool:
        yield pool


class Progress:
    """One status line on stderr: done / remaining / failed (redrawn on a terminal, else every ~5 %)."""

    def __init__(self, total: int, title: str, stream=None):
        self.total, self.title = total, title
        self.done = self.failed = 0
        self.stream = stream or sys.stderr
        self.start = time.perf_counter()
        self._tty = getattr(self.stream, "isatty", lambda: False)()
        self._last_printed = -1

    def update(self, failed: bool = False) -> None:
        self.done += 1
        self.failed += int(failed)
        step = max(self.total // 20, 1)
        if self._tty or self.done == self.total or self.done // step != self._last_printed // step:
            self._last_printed = self.done
            self._draw()

    def _draw(self) -> None:
        width = 24
        filled = int(width * self.done / max(self.total, 1))
        line = (f"{self.title}: [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} done, "
                f"{self.total - self.done} remaining, {self.failed} failed, "
                f"{time.perf_counter() - self.start:.0f} s")
        end = "" if self._tty and self.done < self.total else "\n"
        print(("\r" if self._tty else "") + line, end=end, file=self.stream, flush=True)


@dataclass
class RunSummary:
    """What :func:`run_cases` did: counts, failed cases with their errors, wall time per case."""

    cached: int = 0
    computed: int = 0
    failed: dict[str, str] = field(default_factory=dict)
    rejected: dict[str, str] = field(default_factory=dict)  # saved results that failed their check
    wall_seconds: dict[str, float] = field(default_factory=dict)


def _outcomes(executor: Executor, todo: list[Case]) -> Iterator[tuple[Case, Future]]:
    """(case, finished future) pairs as they complete; pending ones are cancelled if the caller stops."""
    if isinstance(executor, InlineExecutor):  # one at a time, so each is saved before the next starts
        for case in todo:
            yield case, executor.submit(_run_case_timed, case)
        return
    futures = {executor.submit(_run_case_timed, case): case for case in todo}
    try:
        for future in as_completed(futures):
            yield futures[future], future
    finally:  # KeyboardInterrupt or an error while saving: do not leave work queued
        for future in futures:
            future.cancel()


def run_cases(cases: Iterable[Case], store: Store, executor: Executor, title: str = "cases",
              stream=None) -> RunSummary:
    """Run every case without a saved result on ``executor``; save each as it completes.

    Identical cases (same key) run once. A case that raises is recorded (``Store.record_failure``)
    and the others go on. On KeyboardInterrupt the pending cases are cancelled; finished results
    stay saved, so a rerun resumes.
    """
    unique: dict[str, Case] = {}
    for case in cases:
        unique.setdefault(case.key(), case)
    summary = RunSummary()
    stream = stream or sys.stderr
    todo = []
    for c in unique.values():
        why = store.problem(c)
        if why is None:
            continue
        if why != "not saved":  # a damaged result is reported and recomputed, never reused
            print(f"{c.name}: saved result rejected, recomputing: {why}", file=stream)
            summary.rejected[c.name] = why
            store.discard(c)
        todo.append(c)
    summary.cached = len(unique) - len(todo)
    if not todo:
        return summary
    progress = Progress(len(todo), f"{title} ({summary.cached} cached)", stream)
    for case, future in _outcomes(executor, todo):
        try:
            result, wall, worker_code = future.result()
            if worker_code != code_version(case.engine):  # e.g. a Dask worker with another installed copy
                raise RuntimeError(f"the worker runs code version {worker_code}, this process "
                                   f"{code_version(case.engine)}: its result would be saved under a wrong key")
            result.check_finite()  # a NaN anywhere is a failed run, never cached as a success
        except Exception as exc:  # noqa: BLE001 - recorded, the other cases go on
            error = f"{type(exc).__name__}: {exc}"
            store.record_failure(case, error, "".join(traceback.format_exception(exc)))
            summary.failed[case.name] = error
            progress.update(failed=True)
            continue
        store.save(case, result)
        summary.computed += 1
        summary.wall_seconds[case.name] = wall
        progress.update()
    return summary


# --- summaries -----------------------------------------------------------------------------------
TABLE_FLOAT_FORMAT = "%.6g"  # 6 significant digits: the tables compare across runs byte for byte


def summary_function(case_list: CaseList):
    """The study's ``summarize`` function; CaseListError (naming the file and module) if it cannot be had.

    Called for every case list before any case runs, so a misspelt module costs no computation.
    """
    where = f"{case_list.path.name}: [study] summary = {case_list.summary!r}"
    try:
        module = importlib.import_module(case_list.summary)
    except ImportError as exc:
        raise CaseListError(f"{where} cannot be imported ({exc})") from None
    except Exception as exc:  # noqa: BLE001 - a module that fails on import is named, not a traceback
        raise CaseListError(f"{where} fails on import: {type(exc).__name__}: {exc}") from None
    func = getattr(module, "summarize", None)
    if not callable(func):
        raise CaseListError(f"{where} has no function summarize(cases, load)")
    return func


def summarize(case_list: CaseList, store: Store) -> dict[str, pd.DataFrame]:
    """Call the study's ``summarize(cases, load)`` on its saved results."""
    return summary_function(case_list)(list(case_list.cases), store.load)


def write_tables(tables: Mapping[str, pd.DataFrame], reports_dir: Path) -> list[Path]:
    """Write each table to ``tables/<name>.csv``; names ending in ``_timing`` go to ``timing/``.

    Timing (CPU or wall seconds) depends on the machine, so it is kept out of ``tables/``, whose
    files must be byte-identical between two runs.
    """
    written = []
    for name, frame in tables.items():
        folder = Path(reports_dir) / ("timing" if name.endswith("_timing") else "tables")
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{name}.csv"
        atomic_write(path, frame.to_csv(index=False, float_format=TABLE_FLOAT_FORMAT, lineterminator="\n"))
        written.append(path)
    return written


def failures_table(case_lists: Iterable[CaseList], store: Store) -> pd.DataFrame:
    """Every case whose last attempt failed, with its error message."""
    rows = []
    for cl in case_lists:
        for case in cl.all_cases:
            failure = None if store.has(case) else store.failure(case)
            if failure is not None:
                rows.append({"study": cl.study, "case": case.name, "key": case.key(), "error": failure["error"]})
    return pd.DataFrame(rows, columns=["study", "case", "key", "error"])


def sample_agreement(compiled: SimulationResult, reference: SimulationResult, options: Mapping[str, Any]) -> dict:
    """How far a compiled run is from its reference-path twin, and the bound it must stay within.

    Adaptive methods: both paths take the same method at the same tolerances, so each is within the
    global error of the tolerance, adaptive_global_error_factor * rtol * max|q| (reference/tolerances.toml,
    with its reason), of the exact solution. Fixed-step RK4: the same steps, only round-off differs,
    fast_fixed_step_agreement * max|q| (its reason assumes ~300 steps: the check runs that long).
    """
    scale = float(np.max(np.abs(reference.q)))
    if "rtol" in options:
        bound = tolerance("adaptive_global_error_factor") * float(options["rtol"]) * scale
        rule = "adaptive_global_error_factor * rtol * max|q|"
    else:
        bound = tolerance("fast_fixed_step_agreement") * scale
        rule = "fast_fixed_step_agreement * max|q|"
    if len(compiled.t) != len(reference.t):
        return {"max_abs_dq": np.nan, "bound": bound, "rule": rule, "agree": False}
    dq = float(np.max(np.abs(compiled.q - reference.q)))
    return {"max_abs_dq": dq, "bound": bound, "rule": rule, "agree": bool(dq <= bound)}


def backend_agreement(case_lists: Iterable[CaseList], store: Store) -> pd.DataFrame:
    """Every sampled compiled case against its reference-path twin, full horizon (see sample_agreement)."""
    rows = []
    for cl in case_lists:
        for case, twin in cl.samples:
            row = {"study": cl.study, "case": case.name, "t_end": case.t_end}
            if store.has(case) and store.has(twin):
                row.update(sample_agreement(store.load(case), store.load(twin), case.kwargs))
            else:
                row.update(max_abs_dq=np.nan, bound=np.nan, rule="a run failed", agree=False)
            rows.append(row)
    return pd.DataFrame(rows, columns=["study", "case", "t_end", "max_abs_dq", "bound", "rule", "agree"])


def backend_cpu(case_lists: Iterable[CaseList], store: Store) -> pd.DataFrame:
    """CPU of every sampled compiled case and of its reference-path twin (machine-dependent: timing/)."""
    rows = []
    for cl in case_lists:
        for case, twin in cl.samples:
            if store.has(case) and store.has(twin):
                fast, ref = (float(store.load(c).stats["cpu_seconds"]) for c in (case, twin))
                rows.append({"study": cl.study, "case": case.name, "compiled_cpu_s": fast, "reference_cpu_s": ref,
                             "compiled_over_reference": fast / ref if ref > 0 else np.nan})
    return pd.DataFrame(rows, columns=["study", "case", "compiled_cpu_s", "reference_cpu_s", "compiled_over_reference"])


def run_pipeline(reports_dir: Path, cache_root: Path, studies: Iterable[str] | None = None, workers: int = 2,
                 scheduler: str | None = None, folder: Path = CASES_DIR, stream=None,
                 record_root: Path | None = None) -> dict[str, Any]:
    """Run every study's cases (cached ones are reused), then write their tables.

    Before any case runs, every case list is loaded and its summary module imported and checked.
    The record of the run (``pipeline_record.json``) and of the tables each study wrote (with their
    checksums, ``tables/<study>.json``) go to ``record_root`` (default: ``cache_root``); a run of another
    case folder must give its own, so the default record is never overwritten by it.

    Returns a record with the wall time per stage, the counts and the failures (for the manifest).
    """
    stream = stream or sys.stderr
    record_root = Path(cache_root if record_root is None else record_root)
    case_lists = load_case_lists(folder, studies)
    for cl in case_lists:
        summary_function(cl)
    store = Store(Path(cache_root) / "runs")
    record: dict[str, Any] = {"stages": {}, "studies": {}, "case_keys": {}}
    t0 = time.perf_counter()
    with make_executor(workers, scheduler) as executor:
        for cl in case_lists:
            ts = time.perf_counter()
            run = run_cases(cl.all_cases, store, executor, title=cl.study, stream=stream)
            record["studies"][cl.study] = {"cases": len(cl.cases), "reference_samples": len(cl.samples),
                                           "cached": run.cached, "computed": run.computed,
                                           "failed": run.failed, "rejected": run.rejected}
            record["stages"][f"run:{cl.study}"] = time.perf_counter() - ts
            record["case_keys"][cl.study] = {c.name: c.key() for c in cl.all_cases}
    record["stages"]["run"] = time.perf_counter() - t0
    for cl in case_lists:
        ts = time.perf_counter()
        written = record_root / "tables" / f"{cl.study}.json"  # the tables this study wrote last time
        try:
            tables = summarize(cl, store)
        except Exception as exc:  # noqa: BLE001 - a case it needs failed or is missing, or the summary broke
            print(f"{cl.study}: summary skipped: {type(exc).__name__}: {exc}", file=stream)
            record["studies"][cl.study]["summary_error"] = f"{type(exc).__name__}: {exc}"
            for path in _table_record(written):
                Path(path).unlink(missing_ok=True)  # no stale table may pass for a current one
            written.unlink(missing_ok=True)
            continue
        paths = write_tables(tables, reports_dir)
        for path in paths:
            print(f"wrote {path}", file=stream)
        written.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(written, json.dumps({str(p.resolve()): _table_entry(p) for p in paths}, indent=1))
        record["stages"][f"summarize:{cl.study}"] = time.perf_counter() - ts
    write_tables({"failed_cases": failures_table(case_lists, store)}, reports_dir)
    if any(cl.samples for cl in case_lists):
        write_tables({"backend_agreement": backend_agreement(case_lists, store),
                      "backend_cpu_timing": backend_cpu(case_lists, store)}, reports_dir)
    save_record(record, record_root)
    return record


def _table_entry(path: Path) -> dict[str, Any]:
    text = Path(path).read_text()
    return {"rows": data_rows(text), "sha256": sha256_text(text)}


def _table_record(written: Path) -> dict[str, Any]:
    """The tables a study wrote last time, {path: {rows, sha256}} (older records: a list of paths)."""
    if not written.exists():
        return {}
    try:
        data = json.loads(written.read_text())
    except json.JSONDecodeError:
        return {}
    return {p: {} for p in data} if isinstance(data, list) else data


def read_table(path: Path, record_root: Path) -> pd.DataFrame:
    """A table written by :func:`run_pipeline`, after checking it against the rows and checksum recorded
    when it was written (ResultIntegrityError otherwise: a table edited, cut or left over from another run)."""
    path = Path(path).resolve()
    for written in sorted((Path(record_root) / "tables").glob("*.json")):
        entry = _table_record(written).get(str(path))
        if entry is not None:
            verify_text(path, path.read_text(), entry.get("rows"), entry.get("sha256"))
            return pd.read_csv(path)
    raise ResultIntegrityError(f"{path}: no pipeline record lists this table (not written by the last run)")


def save_record(record: Mapping[str, Any], cache_root: Path) -> Path:
    """Write the pipeline record (stage wall times, counts, failures) to ``<cache_root>/pipeline_record.json``."""
    path = Path(cache_root) / PIPELINE_RECORD
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, json.dumps(record, indent=1, sort_keys=True))
    return path


def environment_workers() -> int:
    """Default worker count: $STUDY_WORKERS, else the number of CPUs this process may use."""
    env = os.environ.get("STUDY_WORKERS")
    if env:
        if not env.isdigit() or int(env) < 1:
            raise ValueError(f"STUDY_WORKERS = {env!r} must be a positive integer")
        return int(env)
    return max(len(os.sched_getaffinity(0)), 1)
