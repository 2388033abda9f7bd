"""numba's on-disk cache for the fast path, keyed by the fast path's own sources.

numba invalidates a cached function only when *its own* file changes, not when a kernel it calls
(in another module) changes. So every compiled artefact of the fast path goes to
``cache_dir()/numba/<hash of study/fast/*.py>`` and a generated module to
``cache_dir()/fast/<hash>/``: editing any fast-path source starts a fresh cache, and compilation
is otherwise paid once per machine. An explicit ``NUMBA_CACHE_DIR`` in the environment wins.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from study.model.compile import cache_dir

_HERE = Path(__file__).resolve().parent
# Every module of the fast path, and the reference modules whose constants its kernels compile in.
_SOURCES = sorted(_HERE.glob("*.py")) + [_HERE.parent / "solver" / "friction.py", _HERE.parent / "solver" / "integrate.py"]


def source_hash() -> str:
    """Hash of the sources the compiled kernels depend on (see ``_SOURCES``)."""
    h = hashlib.sha256()
    for path in _SOURCES:
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:12]


SOURCE_HASH = source_hash()


def generated_dir() -> Path:
    """Folder of the generated numba modules."""
    return cache_dir() / "fast" / SOURCE_HASH


def numba_dir() -> Path:
    """Folder of numba's compiled-function cache."""
    return Path(os.environ.get("NUMBA_CACHE_DIR") or cache_dir() / "numba" / SOURCE_HASH)


if not os.environ.get("NUMBA_CACHE_DIR"):
    import numba

    numba.config.CACHE_DIR = str(numba_dir())
