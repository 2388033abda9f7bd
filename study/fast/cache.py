"""numba's on-disk cache for the fast path, keyed by the fast path's own sources.

numba invalidates a cached function only when *its own* file changes, not when a kernel it calls
(in another module) changes. So every compiled artefact of the fast path goes to
``cache_dir()/numba/<hash of study/fast/*.py>`` and a generated module to
``cache_dir()/fast/<hash>/``: editing any fast-path source starts a fresh cache, and compilation
is otherwise paid once per machine. An explicit ``NUMBA_CACHE_DIR`` in the environment wins.
"""

from __future__ import annotations

import os
import threading
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
    """Hold an exclusive lock on numba's cache folder while the compiled path's large kernels with declared
    signatures compile or load: the frontend's entry kernels (on its import) and a generated module's (on its load).
    Two processes that start together (the test workers, the pipeline's) would otherwise both compile the same
    kernels; the second waits and loads what the first saved. The small kernels with declared signatures that
    ``study.solver`` imports (the sgn functions, the stabilization biases, the friction phases) compile outside it.
    Where ``fcntl`` is missing (not POSIX) or the cache folder is not writable there is no lock: each process
    compiles, with the same result."""
    try:
        import fcntl
    except ImportError:
        fcntl = None
    if fcntl is None or getattr(_state, "held", False):   # held by this thread already: flock would wait for itself
        yield
        return
    folder = numba_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fh = open(folder / "compile.lock", "w")
    except OSError:
        yield
        return
    with fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        _state.held = True
        try:
            yield
        finally:
            _state.held = False
            fcntl.flock(fh, fcntl.LOCK_UN)


_state = threading.local()


if not os.environ.get("NUMBA_CACHE_DIR"):
    import numba

    numba.config.CACHE_DIR = str(numba_dir())
