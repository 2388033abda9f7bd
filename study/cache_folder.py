"""Where the study keeps its caches (generated code, numba's compiled functions, saved runs), checked before use.

The root is ``$STUDY_CACHE_DIR`` when it is set and not empty (a relative path is taken from the working folder;
a folder that does not exist yet is made), else :func:`default_cache_dir`: ``.cache`` in a repository checkout,
the user's cache folder (``$XDG_CACHE_HOME/study`` or ``~/.cache/study``) for an installed package. A root that
is a file, that cannot be written, or that lies inside the package's own source tree is refused with a
:class:`CacheFolderError` naming the variable it came from and the path, before anything is written there.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from study.sources import PACKAGE_ROOT

ENV = "STUDY_CACHE_DIR"
_USABLE: set[Path] = set()   # folders found usable in this process


class CacheFolderError(ValueError):
    """A cache folder that cannot be used (not a folder, not writable, inside the package); the message names the
    variable that chose it and the path."""


def checkout_root() -> Path | None:
    """The repository checkout the package runs from (``<root>/pyproject.toml`` beside ``<root>/study``), or None
    for an installed package."""
    root = PACKAGE_ROOT.parent
    return root if (root / "pyproject.toml").is_file() else None


def default_cache_dir() -> Path:
    """``.cache`` in a repository checkout; else ``$XDG_CACHE_HOME/study`` (when absolute) or ``~/.cache/study``,
    never a folder beside an installed package."""
    root = checkout_root()
    if root is not None:
        return root / ".cache"
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    return (Path(xdg) if os.path.isabs(xdg) else Path.home() / ".cache") / "study"


def configured_cache_dir() -> tuple[Path, str | None]:
    """(the cache root, the variable that chose it or None for the default), unchecked."""
    env = os.environ.get(ENV, "")
    if env:
        return Path(env).expanduser().absolute(), ENV
    return default_cache_dir(), None


def usable_folder(path: Path, variable: str | None) -> Path:
    """``path``, made if missing, once it is known to be a writable folder outside the package's source tree.

    ``variable`` names the environment variable that chose the folder (None: the default, ``STUDY_CACHE_DIR``
    unset).

    Raises
    ------
    CacheFolderError
        Naming the variable and the path: a file (or other non-folder), a folder that cannot be made or written,
        or one inside the package.
    """
    path = Path(path)
    if path in _USABLE:
        return path
    if variable is None:
        name, remedy = f"the default cache folder {path} ({ENV} unset)", f"set {ENV} to a writable folder"
    else:
        name, remedy = f"{variable}={path}", f"set {variable} to a writable folder, or unset it"
    real = path.resolve()
    if real == PACKAGE_ROOT or PACKAGE_ROOT in real.parents:
        raise CacheFolderError(f"{name}: inside the package's source tree {PACKAGE_ROOT}, where nothing is written; "
                               f"{remedy}")
    if path.exists() and not path.is_dir():
        raise CacheFolderError(f"{name}: not a folder (it is a file); {remedy}")
    try:
        path.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=path).close()
    except OSError as exc:
        raise CacheFolderError(f"{name}: the cache folder cannot be written ({exc.strerror or exc}); "
                               f"{remedy}") from None
    _USABLE.add(path)
    return path


def cache_dir() -> Path:
    """The study's cache root, checked by :func:`usable_folder`: ``$STUDY_CACHE_DIR`` or the default."""
    return usable_folder(*configured_cache_dir())
