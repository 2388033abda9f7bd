"""Parameter sets: load ``reference/<mechanism>.toml`` into frozen dataclasses.

Every physics parameter is required. A parameter file entry is a table with exactly
``value``, ``unit`` and ``source`` (provenance: paper file, section, equation or table).
Variants override named values of the ``seed`` set; nothing is ever filled in by default.

Errors are collected and raised together as one :class:`ParameterError` whose message names
the file, the key, the offending value and the rule it breaks.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

REFERENCE_DIR = Path(__file__).resolve().parent.parent / "reference"

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
        return "must be > 0"
    if rule == NONNEGATIVE and not value >= 0:
        return "must be >= 0"
    return None


def physical(rule: str, doc: str) -> Any:
    """Declare a required numeric field with its validation rule and unit/meaning."""
    return field(metadata={"rule": rule, "doc": doc})


def choice(options: tuple[str, ...], doc: str) -> Any:
    """Declare a required string field restricted to ``options``."""
    return field(metadata={"choices": options, "doc": doc})


class ParameterError(ValueError):
    """A parameter file is malformed; the message lists every problem found."""


@dataclass(frozen=True)
class SliderCrankParameters:
    """Mechanism A, paper 000 sec. 3. Units SI; see ``reference/slider_crank.toml`` for provenance."""

    J1: float = physical(POSITIVE, "crank inertia about the pivot O [kg m^2]")
    m1: float = physical(POSITIVE, "crank mass [kg] (COM at O)")
    J2: float = physical(POSITIVE, "rod centroidal inertia [kg m^2]")
    m2: float = physical(POSITIVE, "rod mass [kg]")
    m3: float = physical(POSITIVE, "slider mass [kg]")
    J3: float = physical(POSITIVE, "slider inertia [kg m^2] (rotation locked)")
    l1: float = physical(POSITIVE, "crank length OA [m]")
    l2: float = physical(POSITIVE, "rod length AB [m]")
    c2: float = physical(POSITIVE, "distance A to rod COM C2 [m]")
    g: float = physical(POSITIVE, "gravity [m/s^2], acting along -y")
    mu: float = physical(NONNEGATIVE, "Coulomb coefficient in the slider guide [-]")
    F: float = physical(NONNEGATIVE, "resistance on the slider opposing its motion [N]")
    M: float = physical(FINITE, "drive torque on the crank [N m]")
    alpha: float = physical(NONNEGATIVE, "coefficient of the -alpha*q1 (or -alpha*q1dot) crank term")
    alpha_law: str = choice(("spring", "damping"), "reading of '-alpha q1': torsion spring or viscous damper")
    resistance_reading: str = choice(("holds", "sliding_only"),
                                     "reading of F at rest: part of the static limit F + mu|N| ('holds') or "
                                     "acting only while sliding, limit mu|N| ('sliding_only'); "
                                     "study.solver.friction.RESISTANCE_READINGS")


@dataclass(frozen=True)
class QuickReturnParameters:
    """Mechanism B, paper 001 sec. 4, Table 1. Units SI; see ``reference/quick_return.toml``."""

    l1: float = physical(POSITIVE, "crank length OA [m]")
    l2: float = physical(POSITIVE, "rocker length to its tip E [m]")
    l3: float = physical(POSITIVE, "connecting rod length ED [m]")
    m1: float = physical(POSITIVE, "crank mass [kg]")
    m2: float = physical(POSITIVE, "rocker mass [kg]")
    m3: float = physical(POSITIVE, "rod mass [kg]")
    m4: float = physical(POSITIVE, "sliding block mass [kg]")
    m5: float = physical(POSITIVE, "ram mass [kg]")
    a1: float = physical(NONNEGATIVE, "crank COM distance from O [m]")
    a2: float = physical(POSITIVE, "rocker COM distance from its pivot [m]")
    a3: float = physical(POSITIVE, "rod COM distance from E [m]")
    J1: float = physical(POSITIVE, "crank centroidal inertia [kg m^2]")
    J2: float = physical(POSITIVE, "rocker centroidal inertia [kg m^2]")
    J3: float = physical(POSITIVE, "rod centroidal inertia [kg m^2]")
    J4: float = physical(POSITIVE, "block centroidal inertia [kg m^2]")
    J5: float = physical(POSITIVE, "ram inertia [kg m^2] (rotation locked)")
    h1: float = physical(POSITIVE, "height of the crank pivot above the rocker pivot [m]")
    h2: float = physical(POSITIVE, "height of the ram guide [m]")
    g: float = physical(POSITIVE, "gravity [m/s^2], acting along -y")
    M: float = physical(FINITE, "drive torque on the crank [N m]")
    F_cut: float = physical(NONNEGATIVE, "cutting force magnitude [N]")
    x_cut_min: float = physical(FINITE, "left end of the cutting window for x_D [m]")
    x_cut_max: float = physical(FINITE, "right end of the cutting window for x_D [m]")
    cutting_law: str = choice(("on_off", "smooth"), "cutting-force law")
    v_ramp: float = physical(POSITIVE, "tanh ramp width in v_D, smooth law [m/s]")
    x_ramp: float = physical(POSITIVE, "tanh ramp width at the window edges, smooth law [m]")
    mu_guide: float = physical(NONNEGATIVE, "Coulomb coefficient at the ram guide [-]")


PARAMETER_CLASSES = {
    "slider_crank": SliderCrankParameters,
    "quick_return": QuickReturnParameters,
}


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
    values: SliderCrankParameters | QuickReturnParameters
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
            raise AttributeError(f"parameter set {self.mechanism}/{self.variant} has no field {name!r}") from None


def available_mechanisms() -> tuple[str, ...]:
    return tuple(PARAMETER_CLASSES)


def available_variants(mechanism: str, reference_dir: Path | None = None) -> tuple[str, ...]:
    raw = _read(_path_for(mechanism, reference_dir))
    return tuple(raw.get("variants", {}))


def _path_for(mechanism: str, reference_dir: Path | None) -> Path:
    if mechanism not in PARAMETER_CLASSES:
        raise ParameterError(
            f"unknown mechanism {mechanism!r}; valid choices: {', '.join(PARAMETER_CLASSES)}"
        )
    return (reference_dir or REFERENCE_DIR) / f"{mechanism}.toml"


def _read(path: Path) -> dict[str, Any]:
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ParameterError(f"{path}: parameter file not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML: {exc}") from None


def load_parameters(mechanism: str, variant: str = "seed", reference_dir: Path | None = None) -> ParameterSet:
    """Load and validate one variant of a mechanism's parameter file.

    Parameters
    ----------
    mechanism : {'slider_crank', 'quick_return'}
    variant : str
        A key of the file's ``[variants]`` table; ``'seed'`` is the paper's set.
    reference_dir : Path, optional
        Folder holding ``<mechanism>.toml``; defaults to the repository's ``reference/``.

    Raises
    ------
    ParameterError
        Listing every missing or unknown key, wrong type, non-finite or out-of-range value.
    """
    path = _path_for(mechanism, reference_dir)
    return parse_parameters(_read(path), mechanism, variant, path)


def parse_parameters(raw: Mapping[str, Any], mechanism: str, variant: str, path: Path) -> ParameterSet:
    """Validate an already-parsed parameter document (see :func:`load_parameters`)."""
    cls = PARAMETER_CLASSES[mechanism]
    fields = {f.name: f for f in dataclasses.fields(cls)}
    problems: list[str] = []

    def problem(key: str, value: Any, rule: str) -> None:
        problems.append(f"  {key} = {value!r}: {rule}")

    unknown_sections = set(raw) - {"meta", "parameters", "initial_conditions", "variants"}
    for key in sorted(unknown_sections):
        problem(key, "...", "unknown top-level table (allowed: meta, parameters, initial_conditions, variants)")

    params = raw.get("parameters", {})
    values: dict[str, Any] = {}
    units: dict[str, str] = {}
    sources: dict[str, str] = {}
    for name in fields:
        if name not in params:
            problem(f"parameters.{name}", None, "missing (physics parameters have no defaults)")
    for name, entry in params.items():
        key = f"parameters.{name}"
        if name not in fields:
            problem(key, entry, f"unknown parameter for {mechanism} (known: {', '.join(fields)})")
            continue
        if not isinstance(entry, dict):
            problem(key, entry, "must be a table with keys value, unit, source")
            continue
        extra = set(entry) - {"value", "unit", "source"}
        missing = {"value", "unit", "source"} - set(entry)
        if extra:
            problem(key, sorted(extra), "unknown keys (allowed: value, unit, source)")
        if missing:
            problem(key, sorted(missing), "missing keys (every parameter needs value, unit and source)")
            continue
        values[name] = entry["value"]
        units[name] = entry["unit"]
        sources[name] = entry["source"]

    variants = raw.get("variants", {})
    overridden: set[str] = set()
    if variant not in variants:
        problem("variants", variant, f"unknown variant (valid choices: {', '.join(variants) or 'none'})")
        variant_note = ""
    else:
        overrides = dict(variants[variant])
        variant_note = overrides.pop("note", "")
        for name, value in overrides.items():
            if name not in fields:
                problem(f"variants.{variant}.{name}", value, f"unknown parameter for {mechanism}")
            else:
                values[name] = value
                overridden.add(name)
                sources[name] = f"variant '{variant}': {variant_note}"

    for name, value in values.items():
        meta = fields[name].metadata
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

    initial = _parse_initial(raw.get("initial_conditions", {}), cls, problem)
    if problems:
        raise ParameterError(f"{path} (mechanism {mechanism}, variant {variant}):\n" + "\n".join(problems))

    canonical = json.dumps({"mechanism": mechanism, "values": values, "initial": dataclasses.asdict(initial)},
                           sort_keys=True)
    return ParameterSet(
        mechanism=mechanism,
        variant=variant,
        values=cls(**values),
        units=MappingProxyType(units),
        sources=MappingProxyType(sources),
        initial=initial,
        variant_note=variant_note,
        path=path,
        sha256=hashlib.sha256(canonical.encode()).hexdigest(),
    )


def _parse_initial(raw: Mapping[str, Any], cls: type, problem) -> InitialConditions:
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
