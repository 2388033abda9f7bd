"""numba's on-disk cache for the fast path, keyed by the fast path's own sources.

numba invalidates a cached function only when *its own* file changes, not when a kernel it calls
(in another module) changes. So every compiled artefact of the fast path goes to
``cache_dir()/numba/<hash of study/fast/*.py>`` and a generated module to
``cache_dir()/fast/<hash>/``: editing any fast-path source starts a fresh cache, and compilation
is otherwise paid once per machine. An explicit ``NUMBA_CACHE_DIR`` in the environment wins.
"""

from __future__ import annotations

import os
from contextlib import contextmanager
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


@contextmanager
def compile_lock():
    """Hold an exclusive lock on numba's cache folder while kernels with declared signatures compile or load (they
    do so when their module is imported). Two processes that start together (the test workers, the pipeline's)
    would otherwise both compile the same kernels; the second now waits and loads what the first saved. Where
    ``fcntl`` is missing (not POSIX) there is no lock: each process compiles, with the same result."""
    global _held
    try:
        import fcntl
    except ImportError:
        fcntl = None
    if fcntl is None or _held:   # held by this process already (a nested compile): flock would wait for itself
        yield
        return
    folder = numba_dir()
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "compile.lock", "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        _held = True
        try:
            yield
        finally:
            _held = False
            fcntl.flock(fh, fcntl.LOCK_UN)


_held = False


if not os.environ.get("NUMBA_CACHE_DIR"):
    import numba

    numba.config.CACHE_DIR = str(numba_dir())
