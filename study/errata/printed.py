"""The printed formulas (``reference/printed_formulas.toml``) and how each paper's symbols map onto a mechanism."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from study.locations import REFERENCE_DIR

FORMULAS_PATH = REFERENCE_DIR / "printed_formulas.toml"
KINDS = ("expression", "generalized_force", "potential", "equation", "sparse", "initial_conditions")


@dataclass(frozen=True)
class PaperSpec:
    """How a paper's printed symbols map onto a mechanism description.

    ``extras``: printed symbols that are not parameters (load magnitudes), with their meaning.
    ``loads``: load or contact name -> printed symbol of its magnitude.
    ``inputs``: the paper's input vector u, as (load name, force direction or None for a torque).
    """

    paper: str
    mechanism: str
    extras: Mapping[str, str]
    loads: Mapping[str, str]
    inputs: tuple[tuple[str, tuple[int, int] | None], ...] = ()


PAPERS: dict[str, PaperSpec] = {
    "000": PaperSpec(
        "000", "slider_crank",
        extras={"M": "drive torque on the crank", "F_ms": "signed friction force on the slider along +x"},
        loads={"drive": "M", "guide": "F_ms"},
    ),
    "001": PaperSpec(
        "001", "quick_return",
        extras={"M": "drive torque on the crank", "F": "cutting force on the ram along +x"},
        loads={"drive": "M", "cutting": "F"},
        inputs=(("drive", None), ("cutting", (1, 0))),
    ),
}


def load_printed(path: Path | None = None) -> list[dict[str, Any]]:
    """The ``[[formula]]`` entries of ``reference/printed_formulas.toml``, in file order.

    Raises
    ------
    ValueError
        Listing every entry with a missing key, an unknown kind or paper, or a duplicate id.
    """
    path = path or FORMULAS_PATH
    with open(path, "rb") as fh:
        entries = tomllib.load(fh).get("formula", [])
    problems, seen = [], set()
    required = ("id", "paper", "equation", "quantity", "printed", "expr", "kind", "target", "note")
    for n, e in enumerate(entries):
        name = e.get("id", f"entry {n}")
        missing = [k for k in required if k not in e]
        if missing:
            problems.append(f"{name}: missing {missing}")
        if e.get("kind") not in KINDS:
            problems.append(f"{name}: kind {e.get('kind')!r} not one of {KINDS}")
        if e.get("paper") not in PAPERS:
            problems.append(f"{name}: paper {e.get('paper')!r} not one of {tuple(PAPERS)}")
        if name in seen:
            problems.append(f"{name}: duplicate id")
        seen.add(name)
    if problems:
        raise ValueError(f"{path}: " + "; ".join(problems))
    return entries

