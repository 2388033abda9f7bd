"""The hash of the package's own source files: what a cache key records about the code behind an entry.

Every cache of the study (generated code, numba's compiled functions, the pipeline's saved results)
is keyed by the source that produced its entries, so that editing that source starts afresh.
:func:`source_hash` is the one hasher they all use, over the files :func:`source_files` lists.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Iterable

PACKAGE_ROOT = Path(__file__).resolve().parent


def source_files(*parts: str) -> list[Path]:
    """The ``.py`` files of folders (recursively, sorted) or single files under ``study/``, in argument order.

    Raises
    ------
    FileNotFoundError
        A part names nothing under ``study/`` (a stale entry would silently drop code from a key).
    """
    files = []
    for rel in parts:
        path = PACKAGE_ROOT / rel
        if path.is_dir():
            files += sorted(path.rglob("*.py"))
        elif path.is_file():
            files.append(path)
        else:
            raise FileNotFoundError(f"source part {rel!r}: no file or folder {path}")
    return files


def source_hash(files: Iterable[Path], extra: str = "") -> str:
    """SHA-256 (64 hex) of ``extra`` and, in order, each file's path relative to ``study/`` and its bytes."""
    h = hashlib.sha256(extra.encode())
    for path in files:
        h.update(str(Path(path).resolve().relative_to(PACKAGE_ROOT)).encode())
        h.update(Path(path).read_bytes())
    return h.hexdigest()
