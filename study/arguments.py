"""Checks of arguments at the door: each names the value, where it came from and why it is wrong.

``where`` is the source as the user wrote it: an argument name (``"t_end"``), a flag
(``"--t-end"``), or a file and key (``"run.toml group 'g': options.rtol"``). Every check raises a
ValueError (so the command line reports it in one line) and returns the value converted.
"""

from __future__ import annotations

import argparse
import datetime
import math
import numbers
import os
import re
import tempfile
from pathlib import Path
from typing import Any, Iterable

import numpy as np


def shown(value: Any) -> str:
    """A value as the user wrote it: repr, but dates and times (TOML has them) in their ISO form."""
    if isinstance(value, (datetime.date, datetime.time)):
        return value.isoformat()
    return repr(value)


def number(where: str, value: Any, *, positive: bool = True, whole: bool = False, optional: bool = False):
    """A real, finite number (> 0 unless ``positive=False``; an integer if ``whole``); None if ``optional``.

    Booleans, text, dates and complex numbers are refused: TOML and Python let them pass as numbers.
    """
    if value is None and optional:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        kind = type(value).__name__
        raise ValueError(f"{where} = {shown(value)} must be a number, not {'text' if kind == 'str' else kind}")
    value = float(value) if not isinstance(value, numbers.Integral) else int(value)
    if positive and not (math.isfinite(value) and value > 0):
        raise ValueError(f"{where} = {value!r} must be finite and > 0")
    if not math.isfinite(value):
        raise ValueError(f"{where} = {value!r} must be finite")
    if whole:
        if value != int(value):
            raise ValueError(f"{where} = {value!r} must be a whole number")
        return int(value)
    return value


def choice(where: str, value: Any, choices: Iterable[str], *, optional: bool = False):
    """One of ``choices`` (text); None if ``optional``."""
    choices = tuple(choices)
    if value is None and optional:
        return None
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{where} = {value!r} is not known; valid choices: {', '.join(choices)}")
    return value


def flag(where: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{where} = {value!r} must be True or False")
    return bool(value)


def function(where: str, value: Any, *, optional: bool = True):
    if value is None and optional:
        return None
    if not callable(value):
        raise ValueError(f"{where} = {value!r} must be callable (or None)")
    return value


def text(where: str, value: Any, *, optional: bool = False, empty: bool = False):
    if value is None and optional:
        return None
    if not isinstance(value, str) or (not empty and not value.strip()):
        raise ValueError(f"{where} = {value!r} must be {'text' if empty else 'non-empty text'}")
    return value


def state(where: str, value: Any, size: int, names: Iterable[str] = ()) -> np.ndarray:
    """A state vector of ``size`` real, finite numbers."""
    array = np.asarray(value)
    if array.dtype.kind not in "biuf" or array.dtype.kind == "b":
        what = "complex numbers" if array.dtype.kind == "c" else f"{array.dtype} values"
        raise ValueError(f"{where} = {value!r} must hold real numbers, got {what}")
    array = array.astype(float)
    if array.shape != (size,):
        named = f" ({', '.join(names)})" if names else ""
        raise ValueError(f"{where} has shape {array.shape}: the equations have {size} coordinates{named}")
    if not np.isfinite(array).all():
        raise ValueError(f"{where} = {array} must be finite")
    return array


def per_constraint(method: str, options: dict, eom) -> None:
    """A method option given as one value per constraint (sliding mode's Lambda, K, k) has one per constraint of
    ``eom``."""
    r = eom.n_constraints
    for key, value in options.items():
        if isinstance(value, (list, tuple, np.ndarray)) and len(value) != r:
            raise ValueError(f"{method}: {key} has {len(value)} values (one per constraint), but {eom.name} has {r} "
                             f"constraint{'s' if r != 1 else ''} ({', '.join(eom.constraint_names)})")


def output_path(where: str, value: str) -> Path:
    """An output path as given on the command line, refused before any work if it is empty (Path('') is '.')."""
    if not value.strip():
        raise ValueError(f"{where} {value!r} is empty: give the path of the output (e.g. {where} runs/x)")
    return Path(value)


class Parser(argparse.ArgumentParser):
    """argparse's parser, but a negative number in any form (-1e-3, -.5, -inf) is a value, not a flag, so that it
    reaches the option's own check, which names it and says why it is refused (the subcommands' parsers are of the
    same class). argparse's own test, ``_negative_number_matcher``, knows only -1 and -1.5."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER


_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


def writable(path: Path, argument: str, folder: bool = False) -> None:
    """A ValueError naming the argument unless the output folder (``path`` itself if ``folder``, else its
    parent) exists and is writable, or can be created."""
    folder = Path(path) if folder else Path(path).parent
    existing = next((p for p in [folder, *folder.parents] if p.exists()), None)
    if existing is not None and not existing.is_dir():
        raise ValueError(f"{argument} {path}: {existing} is a file, not a folder")
    if existing is not None and not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(f"{argument} {path}: no permission to write in {existing}")
    try:  # what access() cannot tell (a read-only or virtual file system, root's permissions)
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as exc:
        raise ValueError(f"{argument} {path}: cannot write in {existing} ({exc.strerror or exc})") from None
