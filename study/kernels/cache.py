"""numba's on-disk cache for the study's compiled functions: where it lives, and entries that heal.

Every function the study compiles is defined with :func:`kernel` (``numba.njit`` with this cache), never with
``njit(cache=True)``; a helper that only compiled code calls is defined with :func:`internal` and has no entry of
its own (its code is in the entry of each kernel that calls it, :mod:`study.kernels.linking`):

- **where**: numba invalidates a cached function only when *its own* file changes, not when a kernel it calls
  (in another module) changes. So every compiled artefact goes to ``cache_dir()/numba/<hash of the fast path's
  sources>`` and a generated module to ``cache_dir()/fast/<hash>/``: editing any fast-path source starts a fresh
  cache. An explicit ``NUMBA_CACHE_DIR`` in the environment wins. There is no other place: numba's own fallback
  (a ``__pycache__`` beside the source, inside the package) is never used.
- **checked**: a cache folder that cannot be used is refused by :func:`check` (``CacheFolderError`` naming
  ``STUDY_CACHE_DIR`` or ``NUMBA_CACHE_DIR`` and the path) before a compiled run; while it is unusable nothing is
  loaded from or saved to it (the small kernels the reference path calls compile in memory).
- **lazy**: a kernel with a declared signature compiles (or loads) for it on first use, not at import: ``import
  study`` compiles nothing, and a run pays only for the kernels it calls (:func:`kernel`).
- **healing**: an entry that fails to load (an index or data file cut, overwritten or emptied) is deleted with one
  :class:`CacheDiscardedWarning` naming its files, and the function is compiled again and saved afresh.
"""

from __future__ import annotations

import hashlib
import os
import threading
import warnings
from contextlib import contextmanager
from pathlib import Path

from numba import njit
from numba.core.compiler_lock import global_compiler_lock
from numba.core.caching import CompileResultCacheImpl, FunctionCache, UserProvidedCacheLocator

from study.cache_folder import CacheFolderError, cache_dir, configured_cache_dir, usable_folder
from study.kernels.linking import link_only
from study.sources import source_files, source_hash

# Every module whose code the compiled kernels hold: the machinery, the laws and the compiled path (no kernel reads
# a constant of study.solver any more).
_SOURCES = ("kernels", "laws", "fast")
SOURCE_HASH = source_hash(source_files(*_SOURCES))[:12]


class CacheDiscardedWarning(UserWarning):
    """A compiled-cache entry could not be loaded: it was deleted and its function compiled again."""


def _numba_root() -> tuple[Path, str | None]:
    """(numba's cache folder, the variable that chose it), unchecked."""
    env = os.environ.get("NUMBA_CACHE_DIR", "")
    if env:
        return Path(env).expanduser().absolute(), "NUMBA_CACHE_DIR"
    root, variable = configured_cache_dir()
    return root / "numba" / SOURCE_HASH, variable


def generated_dir() -> Path:
    """Folder of the generated numba modules (the cache root checked)."""
    return cache_dir() / "fast" / SOURCE_HASH


def numba_dir() -> Path:
    """Folder of numba's compiled-function cache, checked (``CacheFolderError`` if unusable)."""
    return usable_folder(*_numba_root())


def check() -> None:
    """Refuse (``CacheFolderError``) a compiled run whose cache folders cannot be used, before anything is written."""
    generated_dir()
    numba_dir()


def _usable() -> bool:
    try:
        numba_dir()
    except CacheFolderError:
        return False
    return True


class _Locator(UserProvidedCacheLocator):
    """numba's locator for a user-provided folder, with the study's folder and no fallback: numba's next choice
    would be a ``__pycache__`` beside the source, inside the package."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = str(_numba_root()[0] / self.get_suitable_cache_subpath(py_file))

    @classmethod
    def from_function(cls, py_func, py_file):
        return cls(py_func, py_file)


class _Impl(CompileResultCacheImpl):
    _locator_classes = [_Locator]


class HealingCache(FunctionCache):
    """numba's per-function cache in the study's folder; an entry that fails to load is discarded (see the module
    docstring)."""

    _impl_class = _Impl

    def load_overload(self, sig, target_context):
        if not _usable():
            return None
        try:
            return super().load_overload(sig, target_context)
        except Exception as exc:   # noqa: BLE001 - any failure to read or rebuild an entry: discard it, recompile
            self._discard(exc)
            return None

    def save_overload(self, sig, data):
        if _usable():
            super().save_overload(sig, data)

    def _discard(self, exc: Exception) -> None:
        index = Path(self._cache_file._index_path)
        files = [index, *sorted(index.parent.glob(index.name[:-len(".nbi")] + ".*.nbc"))]
        for path in files:
            path.unlink(missing_ok=True)
        why = " ".join(f"{type(exc).__name__}: {exc}".split())[:160]
        warnings.warn(f"compiled cache entry {', '.join(p.name for p in files)} in {index.parent} could not be "
                      f"loaded ({why}): discarded, recompiling", CacheDiscardedWarning, stacklevel=2)


def kernel(signature=None, **options):
    """``numba.njit(**options)`` with the study's :class:`HealingCache` in place of ``cache=True``.

    Used as ``@kernel()`` (compiled for the types of each call, as ``njit``) or ``@kernel(SIGNATURE, ...)``: then the
    function compiles (or loads) for its signature only, as with ``njit(SIGNATURE)``, but on first use
    (:func:`_declare`), not at import."""

    def wrap(func):
        dispatcher = njit(**options)(func)
        dispatcher._cache = HealingCache(func)   # what njit(cache=True) does (Dispatcher.enable_caching)
        if signature is not None:
            _declare(dispatcher, signature)
        return dispatcher
    return wrap


def _declare(dispatcher, signature) -> None:
    """Make ``dispatcher`` compile (or load) for ``signature`` alone, on first use: every way numba asks a dispatcher
    for code (a call from Python, a call from compiled code being typed, its use as a first-class function) compiles
    the declared signature first and then disables compilation, so each use finds that one overload (or converts
    its arguments to it, or is refused) exactly as after ``njit(SIGNATURE)``. The compile lock is the caller's to
    take (:func:`compile_lock`)."""

    def ensure():
        if dispatcher._can_compile:
            with global_compiler_lock:
                if dispatcher._can_compile:
                    dispatcher.compile(signature)
                    dispatcher.disable_compile()

    get_call_template, get_compile_result = dispatcher.get_call_template, dispatcher.get_compile_result

    def call_template(args, kws):
        ensure()
        return get_call_template(args, kws)

    def compile_result(sig):
        ensure()
        return get_compile_result(sig)

    def compile_for_args(*args, **kws):   # numba's C dispatcher found no overload for a call from Python
        ensure()
        return lambda *a, **k: dispatcher(*a, **k)   # called again with the args: the declared overload, or refused

    dispatcher.get_call_template, dispatcher.get_compile_result = call_template, compile_result
    dispatcher._compile_for_args = compile_for_args


def internal():
    """The decorator of a function that only compiled code calls: compiled for linking into its callers only, with
    no wrappers, no disk cache and no machine code of its own (:func:`study.kernels.linking.link_only`)."""
    return link_only


@contextmanager
def compile_lock(name: str):
    """Hold an exclusive lock named ``name`` in numba's cache folder while what it names compiles or loads: an
    entry kernel for its signature (:func:`study.fast.frontend.entry`), or the kernels with declared signatures that
    a compiled run passes to its loop (its generated ``evaluate``..., ``study.fast.frontend.compile_kernels``).
    Two processes that start together (the test workers, the pipeline's) would otherwise both compile the same
    kernel; the second waits and loads what the first saved. Different names compile side by side: one lock for
    every compilation made one process wait, idle, for the other's. A thread holds one lock at a time (one taken
    inside another is not taken), so two processes never wait for each other. The small kernels that the
    reference path calls from Python (the sgn functions, the stabilization biases, the friction phases) compile on
    first use outside it.
    Where ``fcntl`` is missing (not POSIX) there is no lock: each process compiles, with the same result. The
    folder is checked first (:func:`numba_dir`)."""
    try:
        import fcntl
    except ImportError:
        fcntl = None
    if fcntl is None or getattr(_state, "held", False):   # a lock held by this thread already: no second one
        yield
        return
    digest = hashlib.sha256(name.encode()).hexdigest()[:16]
    with open(numba_dir() / f"compile-{digest}.lock", "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        _state.held = True
        try:
            yield
        finally:
            _state.held = False
            fcntl.flock(fh, fcntl.LOCK_UN)


_state = threading.local()
