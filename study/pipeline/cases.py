"""The case-list schema: a study's cases as data, read from ``reference/cases/<study>.toml``.

A *case list* is a TOML file ``reference/cases/<study>.toml``::

    [study]
    description = "what the study asks"
    summary = "study.studies.sliding_mode"      # module with summarize(cases, load) -> {table: DataFrame}
    section = "sliding_mode"                    # optional: its report section (study.report.sections.<name>, or
                                                # the dotted name of any importable module with section(ctx))
    section_order = 40                          # ... and that section's place in the report (a number;
                                                # study.report.FIXED_SECTIONS places the others)
    standalone = "why"                          # optional: a list only its own command runs (the benchmark);
                                                # load_case_lists leaves it out unless named, and run,
                                                # reproduce and verify refuse it

    [[group]]
    name = "reference"                          # readable, unique within the study
    engine = "inhouse"                          # or "exudyn"
    mechanism = "quick_return"                  # or a user's mechanism file, "my_mechanism.py" (relative to this list)
    variant = "seed"
    t_end = 20.0
    options = { integrator = "DOP853", rtol = 1e-12, method = "projection" }
    # a value "@key" (or "@table:key") is the entry of reference/tolerances.toml (or <table>.toml)
    # optional: the cartesian product of these lists; a list entry that is a table is merged into
    # the options (its 'label' names it), a scalar sets the option of that name. The keys 'variant',
    # 'mechanism' and 't_end' set those fields instead of an option.
    sweep = { omega = [1.0, 10.0], d = [0.5, 1.0] }
    exclude = [ { integrator = "LSODA", method = "projection" } ]   # optional: drop the combinations these match
    # optional (engine 'inhouse'): the backend of every case of the group ('reference' or 'compiled',
    # study.simulate's backend; a sweep entry may state its own), and for a compiled group every n-th compiled
    # case (the first, the (n+1)-th, ...) also run on the reference path: the pairs are checked to agree
    # (CaseList.samples, tables/backend_agreement.csv) and are not part of the study's cases
    backend = "compiled"
    reference_sample = 10

Options are the keyword arguments of :func:`study.simulate.simulate` (engine 'inhouse'; plus
``initial = "printed"`` to start from the paper's printed state instead of the consistent one) or of
:func:`study.exudyn_models.run` (engine 'exudyn', e.g. ``h``, ``solver``); either engine also takes
``repeat = k``: the same run once more (a benchmark's k-th timing), a key of its own, the same result. A case's key
(:meth:`Case.key`) is built in :mod:`study.pipeline.keys`.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping

from study import arguments
from study.locations import CASES_DIR
from study.mechanisms import is_user_file, named_mechanism
from study.model import Mechanism
from study.pipeline.engine_options import check_exudyn_options, check_inhouse_options
from study.pipeline.keys import code_version, mechanism_hash
from study.reference_data import tolerance

ENGINES = ("inhouse", "exudyn")
_GROUP_KEYS = {"name", "engine", "mechanism", "variant", "t_end", "options", "sweep", "exclude", "backend",
               "reference_sample", "expect_error"}
BACKENDS = ("reference", "compiled")
SAMPLE_SUFFIX = ":reference_sample"   # group name of the reference-path twins of a compiled group
_FIELD_SWEEPS = ("mechanism", "variant", "t_end")


class CaseListError(ValueError):
    """A case list is malformed; the message names the file, the group and the value."""


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
    mechanism: str | Mechanism   # a study mechanism's name, a user's file (path.py), or a Mechanism passed in from
    variant: str                 # Python (``study validate``: run in this process, keyed by its content)
    t_end: float
    options: tuple[tuple[str, Any], ...] = ()
    labels: tuple[tuple[str, str], ...] = ()
    # The error class this run is expected to stop with (its failure record is the result, e.g. a method
    # that cannot pass a singular position); "" = expected to finish (and then left out of the key).
    expect_error: str = ""

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
        mechanism = self.mechanism if isinstance(self.mechanism, str) else self.mechanism.name
        return {"study": self.study, "group": self.group, "engine": self.engine, "mechanism": mechanism,
                "variant": self.variant, "t_end": self.t_end, "options": self.kwargs}

    def key(self) -> str:
        """Hash of everything that affects the result (the study and group names do not)."""
        name = Path(self.mechanism).name if isinstance(self.mechanism, str) else self.mechanism.name
        payload = {   # a user's file by its name, not its folder: the key is the same in every clone
            "engine": self.engine, "mechanism": name, "variant": self.variant,
            "t_end": self.t_end, "options": self.kwargs, "content": mechanism_hash(self.mechanism, self.variant),
            "code": code_version(self.engine),
        }
        if self.expect_error:  # two lists expecting different outcomes of one run keep separate records
            payload["expect_error"] = self.expect_error
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
    section: str | None = None           # its report section (a module of study.report.sections), if it has one
    section_order: float | None = None   # that section's place in the report (smaller first)
    standalone: str = ""   # why only its own command runs this list ("" = a study of the pipeline)

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


def _check_group(g: Mapping, where: str) -> None:
    """The group's fields have their types (a table where a table is expected, text where text is), its sweep
    lists are non-empty without repeats, and the number of cases it expands to is within ``max_cases``."""
    unknown = set(g) - _GROUP_KEYS
    if unknown:
        raise CaseListError(f"{where}: unknown keys {sorted(unknown)}; valid: {sorted(_GROUP_KEYS)}")
    for key in ("options", "sweep"):
        if not isinstance(g.get(key, {}), Mapping):
            raise CaseListError(f"{where}: {key} = {g[key]!r} must be a table")
    exclude = g.get("exclude", [])
    if not isinstance(exclude, list) or not all(isinstance(rule, Mapping) for rule in exclude):
        raise CaseListError(f"{where}: exclude = {exclude!r} must be a list of tables (option = value)")
    for key in ("mechanism", "variant", "engine"):
        if key in g and not (isinstance(g[key], str) and g[key]):
            raise CaseListError(f"{where}: {key} = {g[key]!r} must be non-empty text")
    size = 1
    for k, values in g.get("sweep", {}).items():
        if not isinstance(values, list) or not values:
            raise CaseListError(f"{where}: sweep.{k} = {values!r} must be a non-empty list")
        repeated = [v for i, v in enumerate(values) if v in values[:i]]
        if repeated:
            raise CaseListError(f"{where}: sweep.{k} lists {repeated[0]!r} twice (the same case twice)")
        size *= len(values)
    limit = tolerance("max_cases")
    if size > limit:
        raise CaseListError(f"{where}: the sweep expands to {size:g} cases, above max_cases = {limit:g} "
                            f"(reference/tolerances.toml): split the list or raise the bound")


def _check_case(case: Case, where: str, checked: set) -> None:
    """A case's mechanism and variant exist (once per pair: ``checked``), its options are its engine's, typed."""
    from study.mechanisms import names, variants

    if (case.mechanism, case.variant) in checked:
        pass
    elif is_user_file(case.mechanism):
        try:
            named_mechanism(case.mechanism, case.variant)
        except Exception as exc:   # anything a user's file raises is a problem of the case list's input
            raise CaseListError(f"{where}: mechanism = {case.mechanism!r}: {type(exc).__name__}: {exc}") from exc
    else:
        known = names()
        if case.mechanism not in known:
            raise CaseListError(f"{where}: mechanism = {case.mechanism!r} is not known; valid choices: "
                                f"{', '.join(known)}, or a user's mechanism file (a path ending in .py)")
        known = variants(case.mechanism)
        if case.variant not in known:
            raise CaseListError(f"{where}: variant = {case.variant!r} is not a variant of {case.mechanism}; valid "
                                f"choices: {', '.join(known)}")
    checked.add((case.mechanism, case.variant))
    options = case.kwargs
    try:
        arguments.number("repeat", options.pop("repeat", 1), whole=True)
        if case.engine == "exudyn":
            check_exudyn_options(options, case.t_end)
        else:
            check_inhouse_options(options, case.t_end)
    except ValueError as exc:
        raise CaseListError(f"{where}: {exc}") from None


def _expand_group(study: str, g: Mapping, where: str, folder: Path) -> list[Case]:
    _check_group(g, where)
    fields = {"mechanism": g.get("mechanism"), "variant": g.get("variant", "seed"),
              "t_end": _resolve(g.get("t_end"), where)}
    engine = g.get("engine", "inhouse")
    if engine not in ENGINES:
        raise CaseListError(f"{where}: engine = {engine!r} is not one of {ENGINES}")
    sweep = g.get("sweep", {})
    _check_exclude(g, where)
    expect = g.get("expect_error", "")
    if expect != "" and not _is_error_name(expect):
        raise CaseListError(f"{where}: expect_error = {expect!r} must name an error class a run can stop with: "
                            f"{', '.join(sorted(_error_names()))} or a built-in exception")
    backend = g.get("backend")
    if backend is not None and (engine != "inhouse" or backend not in BACKENDS):
        raise CaseListError(f"{where}: backend = {backend!r} must be one of {BACKENDS}, for engine 'inhouse' only")
    cases, checked = [], set()
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
        if is_user_file(str(case_fields["mechanism"])):   # a user's file, relative to the case list's folder
            case_fields["mechanism"] = str((folder / case_fields["mechanism"]).resolve())
        if backend is not None:   # a sweep entry's own backend option (e.g. an integrator only the
            options.setdefault("backend", backend)   # reference path has) is stated there and wins
        try:
            t_end = arguments.number("t_end", case_fields["t_end"])
        except ValueError as exc:
            raise CaseListError(f"{where}: {exc} [s]") from None
        if engine == "exudyn" and "h" not in options:
            raise CaseListError(f"{where}: an Exudyn case needs the step 'h' [s] in its options or sweep")
        case = Case(study, g["name"], engine, case_fields["mechanism"], case_fields["variant"], float(t_end),
                    tuple(sorted(options.items())), tuple(labels), expect)
        _check_case(case, where, checked)
        cases.append(case)
    if not cases:
        raise CaseListError(f"{where}: exclude removes every case of the group")
    return cases


def _error_names() -> set[str]:
    """The error classes a case may be expected to stop with: the study's own and Exudyn's SolverError."""
    from study import errors
    from study.solver.friction import FrictionLawError, PainleveError
    from study.model.initial_state import InitialConditionError

    own = {n for n, v in vars(errors).items() if isinstance(v, type) and issubclass(v, Exception)}
    return own | {c.__name__ for c in (FrictionLawError, PainleveError, InitialConditionError)} | {"SolverError"}


def _is_error_name(name) -> bool:
    import builtins

    builtin = getattr(builtins, name, None) if isinstance(name, str) else None
    return name in _error_names() or (isinstance(builtin, type) and issubclass(builtin, BaseException))


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
    return [(c, Case(c.study, c.group + SAMPLE_SUFFIX, c.engine, c.mechanism, c.variant, sample_horizon(c),
                     tuple(sorted({**c.kwargs, "backend": "reference"}.items())), c.labels)) for c in compiled[::n]]


def sample_horizon(case: Case) -> float:
    """The horizon of a sampled case's reference-path twin: the case's own, cut to ``backend_sample_horizon``
    (an adaptive run) or to ``backend_sample_steps`` steps (a fixed-step run), the horizons the agreement bounds'
    reasons assume (reference/tolerances.toml), and then down to a whole number of output steps, so that every sample of the
    twin is a sample of the case."""
    from study.reference_data import tolerance
    from study.run_arguments import DEFAULT_OUTPUT_STEP

    step = case.kwargs.get("step")
    limit = tolerance("backend_sample_horizon") if step is None else tolerance("backend_sample_steps") * float(step)
    if limit >= case.t_end:
        return float(case.t_end)
    output_step = float(case.kwargs.get("output_step", DEFAULT_OUTPUT_STEP))
    return round(max(1, math.floor(limit / output_step + 1e-9)) * output_step, 12)


def load_case_list(path: Path) -> CaseList:
    """Parse and expand one case list (CaseListError names the file and group of any problem)."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise CaseListError(f"{path}: not valid TOML: {exc}") from None
    study = path.stem
    head = data.get("study", {})
    if not isinstance(head, Mapping) or "summary" not in head:
        raise CaseListError(f"{path}: [study] needs 'summary' (the module with summarize())")
    for key in ("summary", "description"):
        if key in head and not (isinstance(head[key], str) and (head[key].strip() or key == "description")):
            raise CaseListError(f"{path}: [study] {key} = {head[key]!r} must be text")
    groups = data.get("group", [])
    if not isinstance(groups, list) or not all(isinstance(g, Mapping) for g in groups):
        raise CaseListError(f"{path}: group = {groups!r} must be an array of tables ([[group]] entries)")
    if not groups:
        raise CaseListError(f"{path}: no [[group]] entries")
    names = [g.get("name") for g in groups]
    for name in names:
        if not (isinstance(name, str) and name.strip()):
            raise CaseListError(f"{path}: group name = {name!r} must be non-empty text (every group needs a name)")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise CaseListError(f"{path}: group names must be unique; {', '.join(map(repr, repeated))} is used more than once")
    cases, samples = [], []
    for g in groups:
        where = f"{path.name} group {g['name']!r}"
        group_cases = _expand_group(study, g, where, path.parent)
        cases += group_cases
        samples += _samples(g, group_cases, where)
    section, order = head.get("section"), head.get("section_order")
    if section is not None and not (isinstance(section, str) and all(p.isidentifier() for p in section.split("."))):
        raise CaseListError(f"{path}: [study] section = {section!r} must be the name of a module of "
                            f"study.report.sections, or the dotted name of a module of your own")
    if (section is None) != (order is None):
        raise CaseListError(f"{path}: [study] 'section' and 'section_order' go together (got section = "
                            f"{section!r}, section_order = {order!r})")
    if order is not None and (isinstance(order, bool) or not isinstance(order, (int, float))):
        raise CaseListError(f"{path}: [study] section_order = {order!r} must be a number (the section's place)")
    standalone = head.get("standalone", "")
    if not isinstance(standalone, str):
        raise CaseListError(f"{path}: [study] standalone = {standalone!r} must be the reason (text) why only its own "
                            f"command runs this list")
    report = data.get("report", {})
    if not isinstance(report, dict):
        raise CaseListError(f"{path}: [report] must be a table (the report section's choices), got {report!r}")
    return CaseList(study, head.get("description", ""), head["summary"], tuple(cases), path, report, tuple(samples),
                    section, None if order is None else float(order), standalone)


def load_case_lists(folder: Path = CASES_DIR, studies: Iterable[str] | None = None) -> list[CaseList]:
    """Every study's case list in ``folder`` (sorted by name), or only the named studies.

    A missing folder, or one without case lists, is a CaseListError (never an empty run). A
    ``standalone`` list (the benchmark's) is left out of "every", and naming it is a CaseListError
    giving its reason: only its own command (:func:`load_case_list`) runs it.
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
    lists = [load_case_list(available[s]) for s in chosen]
    if studies is None:
        return [cl for cl in lists if not cl.standalone]
    for cl in lists:
        if cl.standalone:
            raise CaseListError(f"{cl.path}: not a study of the pipeline ([study] standalone): {cl.standalone}")
    return lists
