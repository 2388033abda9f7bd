"""numba's on-disk cache for the fast path, keyed by the fast path's own sources.

numba invalidates a cached function only when *its own* file changes, not when a kernel it calls
(in another module) changes. So every compiled artefact of the fast path goes to
``cache_dir()/numba/<hash of study/fast/*.py>`` and a generated module to
``cache_dir()/fast/<hash>/``: editing any fast-path source starts a fresh cache, and compilation
is otherwise paid once per machine. An explicit ``NUMBA_CACHE_DIR`` in the environment wins.
"""

from __future__ import annotations

import os
from pathlib import Path

from study.model.compile import cache_dir
from study.sources import source_files, source_hash

# Every module of the fast path, and the reference modules whose constants its kernels compile in.
_SOURCES = ("fast", "solver/friction", "solver/integrate.py")
SOURCE_HASH = source_hash(source_files(*_SOURCES))[:12]


def generated_dir() -> Path:
    """Folder of the generated numba modules."""
    return cache_dir() / "fast" / SOURCE_HASH


def numba_dir() -> Path:
    """Folder of numba's compiled-function cache."""
    return Path(os.environ.get("NUMBA_CACHE_DIR") or cache_dir() / "numba" / SOURCE_HASH)


if not os.environ.get("NUMBA_CACHE_DIR"):
    import numba

    numba.config.CACHE_DIR = str(numba_dir())
