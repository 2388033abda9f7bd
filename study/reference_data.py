"""Reference numbers and tolerances kept once, in ``reference/<table>.toml``, each with its reason.

Each entry is a TOML table ``[key]`` with ``value`` and ``reason``. The default table is
``tolerances``; the cross-validation against Exudyn keeps its own in ``cross_validation``.
"""

from __future__ import annotations

import tomllib
from functools import lru_cache

from study.locations import REFERENCE_DIR


@lru_cache(maxsize=None)
def _table(table: str) -> dict:
    path = REFERENCE_DIR / f"{table}.toml"
    if not path.exists():
        raise FileNotFoundError(f"no reference table {path}")
    with open(path, "rb") as fh:
        return tomllib.load(fh)


def tolerance(key: str, table: str = "tolerances") -> float:
    """The value of ``[key]`` in reference/<table>.toml (KeyError lists the known keys)."""
    data = _table(table)
    if key not in data:
        raise KeyError(f"no entry {key!r} in reference/{table}.toml; known: {', '.join(data)}")
    return float(data[key]["value"])


def reason(key: str, table: str = "tolerances") -> str:
    return _table(table)[key]["reason"]


def values(key: str, table: str) -> tuple[float, ...]:
    """The list ``value`` of ``[key]`` in reference/<table>.toml (a published vector, e.g. a reference solution)."""
    data = _table(table)
    if key not in data:
        raise KeyError(f"no entry {key!r} in reference/{table}.toml; known: {', '.join(data)}")
    value = data[key]["value"]
    if not isinstance(value, list):
        raise TypeError(f"reference/{table}.toml [{key}] value = {value!r} is not a list (use tolerance() for a number)")
    return tuple(float(v) for v in value)
