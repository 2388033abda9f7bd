"""A user's mechanism file, loaded in the user's terms: ``describe(ps)`` in ``<name>.py``, its parameters in
``<name>.toml`` beside it (optionally ``initial_guess(ps)`` and ``PARAMETERS``, the names ``describe`` reads).

Whatever goes wrong in the user's file is one :class:`study.errors.UserFileError` naming the file, the function, the
line and the cause: a syntax error, an exception while the file runs or while ``describe`` or ``initial_guess``
runs (the innermost line of the user's file it passed through), a parameter the ``.toml`` lacks, a ``describe`` that
cannot take the parameter set or returns something other than a :class:`study.Description`, a description that
fails its checks. The exception the file raised is the ``__cause__`` (shown with ``STUDY_TRACEBACK=1``).

A spatial file defines ``start(ps)`` beside ``describe(ps)``: ``describe`` returns a
:class:`study.spatial.SpatialDescription`, ``start`` the initial state by body as a dict of the keyword arguments of
:class:`study.spatial.SpatialMechanism` (``positions``, and optionally ``orientations``, ``angular_velocities``,
``frame``, ``velocities``); its ``.toml`` then has no ``[initial_conditions]``. Its errors are named as a planar file's.
"""

from __future__ import annotations

import inspect
import traceback
from pathlib import Path
from types import ModuleType
from typing import Any, Callable

import numpy as np

from study.errors import UserFileError
from study.model.joints import Description, DescriptionError
from study.model.mechanism import Mechanism
from study.params import ParameterSet, available_mechanisms, load_parameters
from study.spatial.catalogue import SPATIAL
from study.spatial.description import SpatialDescription
from study.spatial.elements import SpatialDescriptionError
from study.spatial.mechanism import SpatialMechanism

SHAPE = "a user's mechanism: describe(ps) in <name>.py, its parameters in <name>.toml beside it"
START_KEYS = ("positions", "orientations", "angular_velocities", "frame", "velocities")


def load_parts(path: str | Path, variant: str = "seed") -> tuple[Description, ParameterSet, np.ndarray | None]:
    """What a user's mechanism file (``describe(ps)``, optional ``initial_guess(ps)``) and its parameter file beside it
    give: the checked description, the parameter set and Newton's start (None: the printed q(0)), from which
    :func:`load_mechanism` makes the Mechanism; a :class:`~study.errors.UserFileError` (or a
    ParameterError for the ``.toml``) names what is wrong."""
    path = python_file(path)
    return _parts(path, _run(path), variant)


def _parts(path: Path, module: ModuleType, variant: str) -> tuple[Any, ParameterSet, np.ndarray | None]:
    """:func:`load_parts` of the file already run (a spatial file's description is checked by :func:`_spatial`)."""
    describe = getattr(module, "describe", None)
    if describe is None:
        raise UserFileError(f"{path} defines no describe(ps) returning a study.Description ({SHAPE})")
    _takes_the_parameter_set(path, describe, "describe")
    ps = _parameters(path, module, variant)
    d = _call(path, describe, ps, "describe")
    if _is_spatial(module):
        return d, ps, None
    if not isinstance(d, Description):
        raise UserFileError(f"{path}: describe(ps) at line {_first_line(describe)} returned {_kind(d)}, not a "
                            f"study.Description{_hint(d)}")
    guess = None
    if getattr(module, "initial_guess", None) is not None:
        _takes_the_parameter_set(path, module.initial_guess, "initial_guess")
        guess = _guess(path, _call(path, module.initial_guess, ps, "initial_guess"), _first_line(module.initial_guess))
    try:
        d.validate()
    except DescriptionError as exc:
        raise UserFileError(f"{path}: describe(ps) at line {_first_line(describe)} returned a description that fails "
                            f"its checks: {exc}") from exc
    return d, ps, guess


def load_mechanism(path: str | Path, variant: str = "seed") -> Mechanism:
    """A user's mechanism file (``describe(ps)``, optional ``initial_guess(ps)``; a spatial one ``start(ps)``) and its
    parameter file beside it (whatever is wrong in the file is one UserFileError naming the file, the function, the
    line and the cause)."""
    path = python_file(path)
    module = _run(path)
    d, ps, guess = _parts(path, module, variant)
    return _spatial(path, module, d, ps) if _is_spatial(module) else Mechanism(d, ps, guess)


def _is_spatial(module: ModuleType) -> bool:
    """Whether a user's file is spatial: it defines start(ps)."""
    return getattr(module, "start", None) is not None


def _spatial(path: Path, module: ModuleType, d: Any, ps: ParameterSet) -> SpatialMechanism:
    """The SpatialMechanism of a spatial file's description and its ``start(ps)``."""
    if not isinstance(d, SpatialDescription):
        raise UserFileError(f"{path}: describe(ps) at line {_first_line(module.describe)} returned {_kind(d)}, not a "
                            f"study.spatial.SpatialDescription (the file defines start(ps), so it is spatial)")
    _takes_the_parameter_set(path, module.start, "start")
    start = _call(path, module.start, ps, "start")
    line = _first_line(module.start)
    if not isinstance(start, dict):
        raise UserFileError(f"{path}: start(ps) at line {line} returned {_kind(start)}, not a dict of "
                            f"{', '.join(START_KEYS)}")
    unknown = sorted(set(start) - set(START_KEYS))
    if unknown:
        raise UserFileError(f"{path}: start(ps) at line {line} returned the unknown keys {', '.join(map(str, unknown))} "
                            f"(valid: {', '.join(START_KEYS)})")
    if "positions" not in start:
        raise UserFileError(f"{path}: start(ps) at line {line} gives no 'positions' (every body's centre [m])")
    try:   # the start is checked as it is solved: its errors are the file's
        mechanism = SpatialMechanism(d, **start)
        mechanism.initial_state()
        return mechanism
    except SpatialDescriptionError as exc:
        raise UserFileError(f"{path}: start(ps) at line {line}: {exc}") from exc


def python_file(path: str | Path) -> Path:
    """``path`` resolved, if it is an existing ``.py`` file (a UserFileError saying what it is otherwise)."""
    path = Path(path).resolve()
    if not path.exists():
        raise UserFileError(f"{path} does not exist ({SHAPE})")
    if path.is_dir():
        raise UserFileError(f"{path} is a folder, not a Python file ({SHAPE})")
    if path.suffix != ".py":
        raise UserFileError(f"{path} is not a Python file: its name does not end in .py ({SHAPE})")
    return path


def _run(path: Path) -> ModuleType:
    """The user's file run as a module of its own (not in sys.modules; compiled here, so that nothing, not even a
    __pycache__, is written beside it)."""
    module = ModuleType(f"user_mechanism_{path.stem}")
    module.__file__ = str(path)
    try:
        exec(compile(path.read_bytes(), str(path), "exec"), module.__dict__)  # noqa: S102 - the user's own file
    except SyntaxError as exc:   # IndentationError too
        where = "" if exc.filename in (None, str(path)) else f" in {exc.filename}"
        raise UserFileError(f"{path}: syntax error{where} at line {exc.lineno}: {exc.msg}") from exc
    except Exception as exc:  # noqa: BLE001 - whatever the user's file raises is named with its line
        raise UserFileError(f"{path}: running the file raised {_where(exc, path)}") from exc
    return module


def _where(exc: BaseException, path: Path, called: str = "<module>") -> str:
    """'ZeroDivisionError at line 7: division by zero', with 'in helper()' when the innermost line of ``path`` the
    exception passed through is in a function other than ``called``; its other frames (the study's, a library's)
    are left out."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if f.filename == str(path)]
    place = ""
    if frames:
        last = frames[-1]
        function = "" if last.name == called else f" in {last.name}()"
        place = f"{function} at line {last.lineno}"
    return f"{type(exc).__name__}{place}: {exc}"


def _takes_the_parameter_set(path: Path, function: Any, name: str) -> None:
    if not callable(function):
        raise UserFileError(f"{path}: {name} = {function!r} is not a function: define {name}(ps), which takes the "
                            f"parameter set")
    try:
        inspect.signature(function).bind(object())
    except TypeError:
        raise UserFileError(f"{path}: {name}{inspect.signature(function)} at line {_first_line(function)} cannot "
                            f"take the parameter set: define {name}(ps)") from None
    except ValueError:   # no signature to read (a builtin): its call says
        pass


def _first_line(function: Any) -> int | str:
    code = getattr(function, "__code__", None)
    return code.co_firstlineno if code is not None else "?"


def _parameters(path: Path, module: ModuleType, variant: str) -> ParameterSet:
    """The parameter set of ``<name>.toml`` beside the file, with every name of the module's ``PARAMETERS``."""
    toml = path.with_suffix(".toml")
    if path.stem in (*available_mechanisms(), *SPATIAL):
        raise UserFileError(f"{path}: a user's mechanism cannot be named like the study's mechanism {path.stem!r} "
                            f"(its results would carry that name, by which the reports read the study mechanism's label and units): "
                            f"rename "
                            f"{path.name} and {toml.name}")
    if not toml.is_file():
        raise UserFileError(f"{path}: its parameter file {toml} does not exist ({SHAPE})")
    ps = load_parameters(path.stem, variant, reference_dir=path.parent,
                         start_in_code=f"{path.name}'s start(ps)" if _is_spatial(module) else "")
    missing = [k for k in getattr(module, "PARAMETERS", ()) if not hasattr(ps.values, k)]
    if missing:
        raise UserFileError(f"{toml}: {', '.join(f'parameters.{k}' for k in missing)} missing ({path.name}'s "
                            f"PARAMETERS lists {'them' if len(missing) > 1 else 'it'}; physics parameters have no "
                            f"defaults)")
    return ps


def _call(path: Path, function: Callable, ps: ParameterSet, called: str) -> Any:
    """``function(ps)``; what it raises becomes a UserFileError naming the function and the line."""
    name = f"{called}(ps)"
    try:
        return function(ps)
    except AttributeError as exc:
        if getattr(exc, "obj", None) is ps.values or getattr(exc, "obj", None) is ps:
            frames = [f for f in traceback.extract_tb(exc.__traceback__) if f.filename == str(path)]
            line = f" at line {frames[-1].lineno}" if frames else ""
            raise UserFileError(f"{path}: {name}{line} reads the parameter {exc.name!r}, which "
                                f"{path.with_suffix('.toml')} does not define (it defines "
                                f"{', '.join(vars(ps.values)) or 'none'})") from exc
        raise UserFileError(f"{path}: {name} raised {_where(exc, path, called)}") from exc
    except Exception as exc:  # noqa: BLE001 - whatever the user's function raises is named with its line
        raise UserFileError(f"{path}: {name} raised {_where(exc, path, called)}") from exc


def _kind(value: Any) -> str:
    """'None', 'an int', 'a dict', 'a study.Mechanism': what a function returned."""
    if value is None:
        return "None"
    cls = type(value)
    name = f"study.{cls.__name__}" if cls.__module__.startswith("study") else cls.__name__
    return f"{'an' if cls.__name__[0].lower() in 'aeiou' else 'a'} {name}"


def _hint(value: Any) -> str:
    from study.model.builder import MechanismBuilder

    if isinstance(getattr(value, "description", None), Description):   # a study.Mechanism
        return " (return the description: the Mechanism is made from it and the parameter set)"
    if isinstance(value, MechanismBuilder):
        return (" (a MechanismBuilder is the study's internal body-level form a description is lowered to; "
                "describe(ps) returns the joint-level study.Description every engine takes)")
    return ""


def _guess(path: Path, value: Any, line: int | str) -> np.ndarray:
    """The positions of ``initial_guess(ps)``'s (q, qd), as numbers."""
    try:
        return np.asarray(value[0], dtype=float)
    except (TypeError, ValueError, IndexError, KeyError) as exc:
        raise UserFileError(f"{path}: initial_guess(ps) at line {line} returned {_kind(value)}, not (q, qd), two "
                            f"sequences of numbers ({type(exc).__name__}: {exc})") from exc
