"""Reference numbers and tolerances kept once, in ``reference/tolerances.toml``, each with its reason."""

from __future__ import annotations

import tomllib
from functools import lru_cache

from study.params import REFERENCE_DIR


@lru_cache(maxsize=None)
def _table() -> dict:
    with open(REFERENCE_DIR / "tolerances.toml", "rb") as fh:
        return tomllib.load(fh)


def tolerance(key: str) -> float:
    """The value of ``[key]`` in reference/tolerances.toml (KeyError lists the known keys)."""
    table = _table()
    if key not in table:
        raise KeyError(f"no tolerance {key!r} in reference/tolerances.toml; known: {', '.join(table)}")
    return float(table[key]["value"])


def reason(key: str) -> str:
    return _table()[key]["reason"]
