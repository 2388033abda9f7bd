"""What every run specification shares: the refusal of an option it does not take, by name, with the valid ones."""

from __future__ import annotations

from typing import Any, Iterable, Mapping


def refuse_unknown(what: str, given: Mapping[str, Any], valid: Iterable[str]) -> None:
    """A ValueError naming every key of ``given`` not in ``valid``, and the valid ones."""
    valid = list(valid)
    unknown = [k for k in given if k not in valid]
    if unknown:
        raise ValueError(f"{', '.join(unknown)}: not an option of {what}; valid options: {', '.join(valid)}")

