"""Parameter sets: load ``reference/<mechanism>.toml`` into frozen dataclasses.

A mechanism is known by its parameter file ``reference/<mechanism>.toml`` (``[meta] mechanism``
equal to the file name); the file is its own schema. A parameter entry is a table with ``value``,
``unit``, ``source`` (provenance: paper file, section, equation or table), ``doc`` (meaning) and its
validation: ``rule`` (positive, nonnegative, finite) for numbers or ``choices`` for strings.
Variants override named values of the ``seed`` set; nothing is ever filled in by default. This module knows no
mechanism: which parameters a description reads is the catalogue's knowledge (:mod:`study.mechanisms`), which passes
them as ``required`` (a missing or unknown one is then listed with the file's other problems) and checks a set read
without them with :func:`check_parameter_names` before describing it.

A file may extend another mechanism's file in its folder (``[meta] extends = "<name>"``): it then holds that file's
entries and variants as they are (values, units, sources, rules), adds entries of its own, and needs its own
``[initial_conditions]`` (its coordinates are its own). It cannot replace an inherited entry or variant, so the base
file stays the one place of its values; its own variants override values of the whole set.

Errors are collected and raised together as one :class:`ParameterError` whose message names
the file, the key, the offending value and the rule it breaks.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping, Sequence

from study.arguments import shown
from study.locations import REFERENCE_DIR  # the study's data folder (re-exported: params.REFERENCE_DIR)

# Validation rules, by name. Each returns None when the value is fine, else what is wrong.
POSITIVE = "positive"          # finite and > 0 (masses, lengths, inertias, g)
NONNEGATIVE = "nonnegative"    # finite and >= 0 (offsets that may be zero, friction coefficients)
FINITE = "finite"              # any finite real (loads, positions)


def _check_number(value: Any, rule: str) -> str | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"must be a number, got {type(value).__name__}"
    if not math.isfinite(value):
        return "must be finite"
    if rule == POSITIVE and not value > 0:
        return "must be > 0 (rule 'positive')"
    if rule == NONNEGATIVE and not value >= 0:
        return "must be >= 0 (rule 'nonnegative')"
    return None


RULES = (POSITIVE, NONNEGATIVE, FINITE)
#: Keys of one parameter entry: value, unit, source (provenance), doc (meaning), and exactly one of
#: rule (a numeric parameter, one of RULES) or choices (a string parameter, the allowed values).
ENTRY_KEYS = {"value", "unit", "source", "doc", "rule", "choices"}


class ParameterError(ValueError):
    """A parameter file is malformed; the message lists every problem found."""


def values_class(mechanism: str, names: list[str]) -> type:
    """A frozen dataclass holding one mechanism's parameter values (``ps.values.<name>``)."""
    return dataclasses.make_dataclass(f"{mechanism.title().replace('_', '')}Parameters",
                                      [(n, Any) for n in names], frozen=True)


@dataclass(frozen=True)
class InitialConditions:
    """Printed and consistent-IC specifications of one mechanism."""

    printed_q: tuple[float, ...]
    printed_qd: tuple[float, ...]
    printed_source: str
    independent: tuple[int, ...]
    q_independent: tuple[float, ...]
    qd_independent: tuple[float, ...]
    branch: str
    source: str


@dataclass(frozen=True)
class ParameterSet:
    """One variant of one mechanism's parameters, with provenance and a content hash."""

    mechanism: str
    variant: str
    values: Any  # frozen dataclass, one field per parameter of the file
    units: Mapping[str, str]
    sources: Mapping[str, str]
    initial: InitialConditions
    variant_note: str
    path: Path
    sha256: str

    def __getattr__(self, name: str) -> Any:  # convenience: ps.l1 == ps.values.l1
        values = object.__getattribute__(self, "values")
        try:
            return getattr(values, name)
        except AttributeError:
            raise AttributeError(f"parameter set {self.mechanism}/{self.variant} has no field {name!r}", name=name,
                                 obj=self) from None


def available_mechanisms(reference_dir: Path | None = None) -> tuple[str, ...]:
    """Mechanisms with a parameter file: ``reference/<name>.toml`` whose ``[meta] mechanism`` is ``name``."""
    found = []
    for path in sorted((reference_dir or REFERENCE_DIR).glob("*.toml")):
        try:
            meta = _parsed(path).get("meta", {})
        except ParameterError:
            continue
        if isinstance(meta, dict) and meta.get("mechanism") == path.stem:
            found.append(path.stem)
    return tuple(found)


def available_variants(mechanism: str, reference_dir: Path | None = None) -> tuple[str, ...]:
    """The variants of a mechanism's parameter file (with those of the file it extends, first)."""
    path = _path_for(mechanism, reference_dir)
    problems: list[str] = []
    raw = _extended(_read(path), path, lambda key, value, rule: problems.append(f"  {key} = {shown(value)}: {rule}"))
    if problems:
        raise ParameterError(f"{path} (mechanism {mechanism}):\n" + "\n".join(problems))
    return tuple(raw.get("variants", {}))


def _extended(raw: dict[str, Any], path: Path, problem, seen: tuple[Path, ...] = ()) -> dict[str, Any]:
    """``raw`` with the entries and variants of the file its ``[meta] extends`` names (in the same folder), the
    inherited ones first; an entry or variant defined in both, a missing base file and a cycle are problems."""
    meta = raw.get("meta", {})
    base_name = meta.get("extends") if isinstance(meta, dict) else None
    if base_name is None:
        return raw
    path = Path(path)
    if not isinstance(base_name, str) or not base_name or "/" in base_name or "\\" in base_name:
        problem("meta.extends", base_name, "must name another mechanism's parameter file in the same folder")
        return raw
    base_path = path.parent / f"{base_name}.toml"
    if base_path.resolve() in seen + (path.resolve(),):
        chain = " -> ".join([p.stem for p in seen + (path,)] + [base_name])
        problem("meta.extends", base_name, f"the files extend each other in a cycle: {chain}")
        return raw
    try:
        base = _read(base_path)
    except ParameterError as exc:
        problem("meta.extends", base_name, f"the file it names cannot be read: {exc}")
        return raw
    base = _extended(base, base_path, problem, seen + (path.resolve(),))
    merged = dict(raw)
    for table, what in (("parameters", "an entry"), ("variants", "a variant")):
        inherited = dict(base.get(table, {}))
        for key, value in raw.get(table, {}).items():
            if key in inherited:
                problem(f"{table}.{key}", "...", f"is also {what} of {base_name}.toml, which this file extends: the "
                                                  f"file inherits it as it is and cannot replace it"
                                                  + (" (a variant of its own changes a value)" if table == "parameters"
                                                     else ""))
            else:
                inherited[key] = value
        merged[table] = inherited
    return merged


def _path_for(mechanism: str, reference_dir: Path | None) -> Path:
    if reference_dir is not None and not Path(reference_dir).is_dir():
        what = "is not a folder" if Path(reference_dir).exists() else "does not exist"
        raise ParameterError(f"reference_dir = {reference_dir} {what} (it is the folder of the parameter files "
                             f"<mechanism>.toml)")
    known = available_mechanisms(reference_dir)
    path = Path(reference_dir or REFERENCE_DIR) / f"{mechanism}.toml"
    if mechanism not in known:
        if path.is_file():   # there, but it names another mechanism (or is not valid TOML: _parsed names the file)
            meta = _parsed(path).get("meta", {})
            named = meta.get("mechanism") if isinstance(meta, dict) else None
            raise ParameterError(f"{path}: [meta] mechanism = {named!r} must be {mechanism!r}, the file's name")
        where = "" if reference_dir is None else f" ({path} does not exist)"
        raise ParameterError(f"unknown mechanism {mechanism!r}{where}; valid choices: {', '.join(known) or 'none'}")
    return path


def _read(path: Path) -> dict[str, Any]:
    """The parsed TOML file, a fresh copy the caller may change."""
    return copy.deepcopy(_parsed(path))


def _parsed(path: Path) -> dict[str, Any]:
    """The parsed TOML file, shared (not to be changed): parsed once per content, the stamp being path, size
    and modification time."""
    try:
        stat = Path(path).stat()
    except FileNotFoundError:
        raise ParameterError(f"{path}: parameter file not found") from None
    return _parse(str(path), stat.st_size, stat.st_mtime_ns)


@functools.lru_cache(maxsize=64)
def _parse(path: str, size: int, mtime_ns: int) -> dict[str, Any]:
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ParameterError(f"{path}: parameter file not found") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{path}: not valid TOML: {exc}") from None


def load_parameters(mechanism: str, variant: str = "seed", reference_dir: Path | None = None,
                    required: Sequence[str] = (), start_in_code: str = "") -> ParameterSet:
    """Load and validate one variant of a mechanism's parameter file.

    Parameters
    ----------
    mechanism : str
        One of :func:`available_mechanisms` (a parameter file ``reference/<mechanism>.toml``).
    variant : str
        A key of the file's ``[variants]`` table; ``'seed'`` is the paper's set.
    reference_dir : Path, optional
        Folder holding ``<mechanism>.toml``; defaults to the study's data (:data:`study.locations.REFERENCE_DIR`).
    required : sequence of str, optional
        The parameters the mechanism's description reads (the catalogue's :class:`study.mechanisms.Entry`): a missing
        or an unknown one is then listed with the file's other problems. Without it the file is its own schema, and
        :func:`check_parameter_names` checks the set before it is described.
    start_in_code : str, optional
        Where the start is given instead of ``[initial_conditions]`` (a spatial user's file: its ``start(ps)``): the
        file must then have no such table, and the set's initial conditions are empty, with this as their source.

    Raises
    ------
    ParameterError
        Listing every missing or unknown key, wrong type, non-finite or out-of-range value.
    """
    path = _path_for(mechanism, reference_dir)
    return parse_parameters(_read(path), mechanism, variant, path, required, start_in_code)


def parse_parameters(raw: Mapping[str, Any], mechanism: str, variant: str, path: Path,
                     required: Sequence[str] = (), start_in_code: str = "") -> ParameterSet:
    """Validate an already-parsed parameter document (see :func:`load_parameters`)."""
    problems: list[str] = []

    def problem(key: str, value: Any, rule: str) -> None:
        problems.append(f"  {key} = {shown(value)}: {rule}")

    raw = _extended(raw, path, problem)
    unknown_sections = set(raw) - {"meta", "parameters", "initial_conditions", "variants"}
    for key in sorted(unknown_sections):
        problem(key, "...", "unknown top-level table (allowed: meta, parameters, initial_conditions, variants)")
    params = raw.get("parameters", {})
    if not params:
        problem("parameters", params, "missing or empty (every physics parameter is listed with its value)")
    if required:
        problems += _name_problems(params, required, mechanism)
    fields, values, units, sources = _entries({k: v for k, v in params.items() if not required or k in required},
                                              problem)
    variant_note, overridden = _apply_variant(raw.get("variants", {}), variant, mechanism, fields, values, sources,
                                              problem)
    _check_values(values, fields, overridden, variant, problem)
    if start_in_code:
        if "initial_conditions" in raw:
            problem("initial_conditions", sorted(raw["initial_conditions"]), f"not read: the start is {start_in_code}; "
                    f"remove the table")
        initial = InitialConditions(printed_q=(), printed_qd=(), printed_source=start_in_code, independent=(),
                                    q_independent=(), qd_independent=(), branch="", source=start_in_code)
    else:
        initial = _parse_initial(raw.get("initial_conditions", {}), problem)
    if problems:
        raise ParameterError(f"{path} (mechanism {mechanism}, variant {variant}):\n" + "\n".join(problems))

    canonical = json.dumps({"mechanism": mechanism, "values": values, "initial": dataclasses.asdict(initial)},
                           sort_keys=True)
    return ParameterSet(
        mechanism=mechanism,
        variant=variant,
        values=values_class(mechanism, list(values))(**values),
        units=MappingProxyType(units),
        sources=MappingProxyType(sources),
        initial=initial,
        variant_note=variant_note,
        path=path,
        sha256=hashlib.sha256(canonical.encode()).hexdigest(),
    )


def _entry_problem(key: str, entry: Any, problem) -> bool:
    """Report what is wrong with one parameter entry's keys and text; True when it cannot be read at all."""
    if not isinstance(entry, dict):
        problem(key, entry, "must be a table with keys value, unit, source, doc and rule (or choices)")
        return True
    extra = set(entry) - ENTRY_KEYS
    missing = {"value", "unit", "source", "doc"} - set(entry)
    if extra:
        problem(key, sorted(extra), f"unknown keys (allowed: {', '.join(sorted(ENTRY_KEYS))})")
    if missing:
        problem(key, sorted(missing), "missing keys (every parameter needs value, unit, source and doc)")
        return True
    if ("rule" in entry) == ("choices" in entry):
        problem(key, entry.get("rule", entry.get("choices")), "needs exactly one of rule (numbers) or choices (strings)")
        return True
    if "rule" in entry and entry["rule"] not in RULES:
        problem(f"{key}.rule", entry["rule"], f"must be one of {', '.join(RULES)}")
        return True
    if "choices" in entry and (not isinstance(entry["choices"], list) or not entry["choices"]
                               or not all(isinstance(c, str) for c in entry["choices"])):
        problem(f"{key}.choices", entry["choices"], "must be a non-empty list of strings")
        return True
    for text_key in ("unit", "source", "doc"):
        if not isinstance(entry[text_key], str) or not entry[text_key].strip():
            problem(f"{key}.{text_key}", entry[text_key], "must be non-empty text (write '-' for a dimensionless "
                                                          "unit)" if text_key == "unit" else "must be non-empty text")
    return False


def _entries(params: Mapping[str, Any], problem) -> tuple[dict, dict, dict, dict]:
    """The readable entries' validation (name -> {'rule': ...} or {'choices': (...)}), values, units and sources."""
    fields: dict[str, dict[str, Any]] = {}
    values: dict[str, Any] = {}
    units: dict[str, str] = {}
    sources: dict[str, str] = {}
    for name, entry in params.items():
        if _entry_problem(f"parameters.{name}", entry, problem):
            continue
        fields[name] = {"rule": entry["rule"]} if "rule" in entry else {"choices": tuple(entry["choices"])}
        values[name] = entry["value"]
        units[name] = entry["unit"]
        sources[name] = entry["source"]
    return fields, values, units, sources


def _apply_variant(variants: Mapping[str, Any], variant: str, mechanism: str, fields: Mapping, values: dict,
                   sources: dict, problem) -> tuple[str, set[str]]:
    """Override ``values`` (and their sources) with the variant's; its note and the names it overrides."""
    if variant not in variants:
        problem("variants", variant, f"unknown variant (valid choices: {', '.join(variants) or 'none'})")
        return "", set()
    overrides = dict(variants[variant])
    variant_note = overrides.pop("note", "")
    overridden: set[str] = set()
    for name, value in overrides.items():
        if name not in fields:
            problem(f"variants.{variant}.{name}", value, f"unknown parameter for {mechanism}")
        else:
            values[name] = value
            overridden.add(name)
            sources[name] = f"variant '{variant}': {variant_note}"
    return variant_note, overridden


def _check_values(values: dict, fields: Mapping, overridden: set[str], variant: str, problem) -> None:
    """Check every value against its rule or choices (numbers become floats)."""
    for name, value in values.items():
        meta = fields[name]
        key = f"variants.{variant}.{name}" if name in overridden else f"parameters.{name}"
        if "choices" in meta:
            if not isinstance(value, str) or value not in meta["choices"]:
                problem(key, value, f"must be one of {', '.join(meta['choices'])}")
        else:
            why = _check_number(value, meta["rule"])
            if why:
                problem(key, value, why)
            else:
                values[name] = float(value)


def _name_problems(given: Mapping[str, Any], required: Sequence[str], mechanism: str) -> list[str]:
    """A missing parameter (physics parameters have no defaults) and an unknown one (``given``: name -> what to show),
    against the names ``required`` that the mechanism's description reads."""
    problems = [f"  parameters.{name} = None: missing (the description of {mechanism} needs it; physics "
                f"parameters have no defaults)" for name in required if name not in given]
    return problems + [f"  parameters.{name} = {shown(value)}: unknown parameter for {mechanism} (its description "
                       f"reads: {', '.join(required)})" for name, value in given.items() if name not in required]


def check_parameter_names(ps: ParameterSet, required: Sequence[str]) -> None:
    """Raise ParameterError unless ``ps`` holds exactly the parameters ``required`` (those its mechanism's description
    reads): a missing one and an unknown one are named with the file."""
    problems = _name_problems(vars(ps.values), required, ps.mechanism)
    if problems:
        raise ParameterError(f"{ps.path} (mechanism {ps.mechanism}, variant {ps.variant}):\n" + "\n".join(problems))


def _parse_initial(raw: Mapping[str, Any], problem) -> InitialConditions:
    printed = raw.get("printed", {})
    consistent = raw.get("consistent", {})

    def vector(table: Mapping[str, Any], section: str, key: str) -> tuple[float, ...]:
        value = table.get(key)
        if not isinstance(value, list) or not value:
            problem(f"initial_conditions.{section}.{key}", value, "missing or not a non-empty list of numbers")
            return ()
        for item in value:
            why = _check_number(item, FINITE)
            if why:
                problem(f"initial_conditions.{section}.{key}", value, f"every entry {why}")
                return ()
        return tuple(float(v) for v in value)

    def text(table: Mapping[str, Any], section: str, key: str) -> str:
        value = table.get(key)
        if not isinstance(value, str) or not value:
            problem(f"initial_conditions.{section}.{key}", value, "missing or not a string")
            return ""
        return value

    q = vector(printed, "printed", "q")
    qd = vector(printed, "printed", "qd")
    if q and qd and len(q) != len(qd):
        problem("initial_conditions.printed", (q, qd), "q and qd must have the same length")
    independent = consistent.get("independent")
    if not isinstance(independent, list) or not all(isinstance(i, int) and not isinstance(i, bool)
                                                     for i in independent or [None]):
        problem("initial_conditions.consistent.independent", independent, "must be a list of coordinate indices")
        independent = []
    elif q and any(not 0 <= i < len(q) for i in independent):
        problem("initial_conditions.consistent.independent", independent, f"indices must lie in 0..{len(q) - 1}")
    q_ind = vector(consistent, "consistent", "q_independent")
    qd_ind = vector(consistent, "consistent", "qd_independent")
    if independent and (len(q_ind) != len(independent) or len(qd_ind) != len(independent)):
        problem("initial_conditions.consistent", (q_ind, qd_ind),
                "q_independent and qd_independent need one value per independent coordinate")
    for section, table, allowed in (("printed", printed, {"q", "qd", "source"}),
                                    ("consistent", consistent,
                                     {"independent", "q_independent", "qd_independent", "branch", "source"})):
        for key in sorted(set(table) - allowed):
            problem(f"initial_conditions.{section}.{key}", table[key], f"unknown key (allowed: {', '.join(sorted(allowed))})")
    return InitialConditions(
        printed_q=q,
        printed_qd=qd,
        printed_source=text(printed, "printed", "source"),
        independent=tuple(independent),
        q_independent=q_ind,
        qd_independent=qd_ind,
        branch=text(consistent, "consistent", "branch"),
        source=text(consistent, "consistent", "source"),
    )
