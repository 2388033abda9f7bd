"""Round three, group 'caches': see tests/round3/__init__.py.

Tries that damage numba's compiled cache run the command line in a child process on a private copy of the
shared cache (``_own_cache``), never on the shared folder that ``isolate()`` links: a damaged entry there would
break every other test. Tries on the cache folder itself (a file, read-only, relative, ...) run in this process.

Tally (17 tries): before 7 good, 2 weak, 8 bad; after 17 good.
"""

from __future__ import annotations

import contextlib
import io
import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

from round3 import OK, add

G = "caches"
ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "study"
RUN = ["-m", "study", "simulate", "quick_return", "--t-end", "0.05", "--backend", "compiled"]


# --- helpers ------------------------------------------------------------------------------------------------
def _package_files() -> dict[str, tuple[int, int]]:
    """Every file of the package's source tree with its size and time."""
    return {str(p.relative_to(PACKAGE)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in PACKAGE.rglob("*") if p.is_file()}


def _own_cache(tmp: Path) -> Path:
    """A private copy of the shared numba cache, warmed first by a compiled run in a child process on the shared
    cache root. Not in this process: a kernel that this process has compiled or loaded already (under any cache
    root, by an earlier test) is never saved again, so the shared folder could lack its entry."""
    from study.kernels.cache import SOURCE_HASH

    warm = _child(tmp / "cache", tmp)
    assert warm.returncode == 0, warm.stderr[-300:]
    own = tmp / "own_cache"
    shutil.copytree((tmp / "cache" / "numba" / SOURCE_HASH).resolve(), own / "numba" / SOURCE_HASH)
    return own


def _child(cache: Path, tmp: Path, *args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    """``python -m study simulate ...`` in a child process with its own cache root; nothing of the package may
    change meanwhile (snapshot before and after)."""
    child_env = {**os.environ, "STUDY_CACHE_DIR": str(cache), "PYTHONDONTWRITEBYTECODE": "1", **(env or {})}
    child_env.pop("NUMBA_CACHE_DIR", None)
    child_env.pop("STUDY_TRACEBACK", None)
    before = _package_files()
    out = subprocess.run([sys.executable, *(args or RUN), "--out", str(tmp / "run")], cwd=tmp, env=child_env,
                         capture_output=True, text=True)
    changed = sorted(set(_package_files().items()) ^ set(before.items()))
    assert not changed, f"files written inside the package {PACKAGE}: {changed[:5]}"
    return out


def _healed(out: subprocess.CompletedProcess, damaged: Path) -> None:
    """The run succeeded, said in one line that it discarded the damaged entry, and showed no traceback."""
    err = out.stderr
    assert out.returncode == 0, f"exit {out.returncode}: {err.strip().splitlines()[-1:] if err.strip() else ''}"
    assert "Traceback" not in err, f"a traceback on stderr: {err[-300:]}"
    lines = [line for line in err.splitlines() if damaged.name in line]
    assert len(lines) == 1, f"expected one line naming {damaged.name}, got {lines} in {err[-400:]}"
    assert "recompil" in lines[0], f"the line does not say it recompiles: {lines[0]}"


def _entry(cache: Path, pattern: str) -> Path:
    """The entry of the current code (the folder of the fast path's source hash)."""
    from study.kernels.cache import SOURCE_HASH

    found = sorted((cache / "numba" / SOURCE_HASH).rglob(pattern))
    assert found, f"no cache entry {pattern} under {cache}"
    return found[0]


@contextlib.contextmanager
def _read_only(folder: Path):
    """``folder`` made unwritable for the duration (immutable for root, for whom modes do not count)."""
    folder.mkdir(parents=True, exist_ok=True)
    root = os.geteuid() == 0
    subprocess.run(["chattr", "+i", str(folder)], check=True) if root else folder.chmod(0o555)
    try:
        yield folder
    finally:
        subprocess.run(["chattr", "-i", str(folder)], check=True) if root else folder.chmod(0o755)


# --- 1. a damaged compiled-cache entry is discarded and recompiled, with one line saying so ------------------
def _damaged_kernel(damage):
    def action(tmp):
        own = _own_cache(tmp)
        path = damage(own)
        _healed(_child(own, tmp), path)
        out = _child(own, tmp)                         # healed for good: the next run loads it quietly
        assert out.returncode == 0 and path.name not in out.stderr, out.stderr[-300:]
    return action


# The damage goes to the small kernel that a compiled quick-return run loads beside the loop's entry (a declared
# kernel compiles or loads on first use, study.kernels.cache; a warm run reads only these two entries, as
# NUMBA_DEBUG_CACHE shows): the stabilization's zero bias, the loop's argument. It heals by the same code as a large
# one (study.kernels.cache.HealingCache.load_overload, for every kernel), and recompiles in a fraction of a second
# where the compiled loop's entry takes many seconds of CPU.
def _cut_in_half(own):
    path = _entry(own, "stabilization.zero_bias-*.nbc")
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    return path


def _overwrite_index(own):
    path = _entry(own, "stabilization.zero_bias-*.nbi")
    path.write_bytes(b"this is not numba's index" * 8)
    return path


def _valid_pickle_wrong_content(own):
    path = _entry(own, "stabilization.zero_bias-*.nbc")
    path.write_bytes(pickle.dumps(("not", "a", "compiled", "function")))
    return path


# Every damage fails inside the same ``load_overload`` and heals by the same ``_discard``: in a real process (each
# recompiles the loop) the three run in the slow suite (make verify); make test heals all three damages in its own
# process in tests/test_cache_folder.py (test_a_damaged_entry_is_discarded_and_recompiled).
add(G, "kernel_nbc_cut_in_half_is_recompiled", _damaged_kernel(_cut_in_half), OK, slow=True)
add(G, "kernel_nbi_overwritten_is_recompiled", _damaged_kernel(_overwrite_index), OK, slow=True)
add(G, "kernel_nbc_valid_pickle_wrong_content", _damaged_kernel(_valid_pickle_wrong_content), OK, slow=True)


def _mechanism_entry(damage, pattern):
    """The mechanism's own compiled entries (the generated module's) are made by a first run, then damaged."""
    def action(tmp):
        own = tmp / "own_cache"
        first = _child(own, tmp)
        assert first.returncode == 0, first.stderr[-300:]
        path = _entry(own, pattern)
        damage(path)
        _healed(_child(own, tmp), path)
    return action


# These three compile the whole compiled path in a cache of their own, twice (about 45 s of CPU each): they run in
# the slow suite (make verify); make test keeps the kernel tries above, which heal the same way.
add(G, "mechanism_nbi_empty_is_recompiled",
    _mechanism_entry(lambda p: p.write_bytes(b""), "study_fast_quick_return_*.evaluate-*.nbi"), OK, slow=True)
add(G, "mechanism_nbc_truncated_is_recompiled",
    _mechanism_entry(lambda p: p.write_bytes(p.read_bytes()[:100]), "study_fast_quick_return_*.indicators-*.nbc"), OK,
    slow=True)


def _generated_source_edited(tmp):
    own = tmp / "own_cache"
    first = _child(own, tmp)
    assert first.returncode == 0, first.stderr[-300:]
    source = next((own / "fast").rglob("study_fast_quick_return_*.py"))
    source.write_text(source.read_text().replace("N_WORK = ", "N_WORK = 1 + ", 1))
    out = _child(own, tmp)
    assert out.returncode == 0 and "Traceback" not in out.stderr, out.stderr[-300:]
    assert "regenerated" in out.stderr and source.name in out.stderr, out.stderr[-300:]
    assert "N_WORK = 1 + " not in source.read_text(), "the edit survived"


add(G, "generated_fast_source_edited_is_regenerated", _generated_source_edited, OK, slow=True)


def _clean_run_writes_nothing_in_the_package(tmp):
    out = _child(_own_cache(tmp), tmp)      # _child asserts that the package's files are unchanged
    assert out.returncode == 0, out.stderr[-300:]


# Every child run of this group asserts the same (_child), the three of each damage try among them (slow suite):
# this try runs in the slow suite too.
add(G, "compiled_run_writes_nothing_in_the_package", _clean_run_writes_nothing_in_the_package, OK, slow=True)


# --- 2. a cache folder that cannot be used is refused by its variable, before anything is written -----------
def _read_only_child(tmp):
    with _read_only(tmp / "ro_cache") as ro:
        out = _child(ro, tmp)
    err = out.stderr.strip()
    assert out.returncode == 2, f"exit {out.returncode}: {err[-300:]}"
    assert err.count("\n") == 0 and "Traceback" not in err, f"not one line: {err[-400:]}"
    assert "STUDY_CACHE_DIR" in err and str(ro) in err, err


add(G, "read_only_cache_refused_and_package_untouched", _read_only_child, OK)


def _read_only_library(tmp):
    from study.simulate import simulate

    with _read_only(tmp / "ro_cache") as ro:
        os.environ["STUDY_CACHE_DIR"] = str(ro)
        simulate("quick_return", t_end=0.05)


add(G, "read_only_cache_library", _read_only_library, ValueError, "STUDY_CACHE_DIR", "ro_cache", "writ")


def _cache_is_a_file(backend):
    def action(tmp):
        (tmp / "a_file").write_text("not a folder\n")
        os.environ["STUDY_CACHE_DIR"] = str(tmp / "a_file")
        return ["simulate", "quick_return", "--t-end", "0.05", "--backend", backend, "--out", "run"]
    return action


add(G, "cache_dir_is_a_file_reference", _cache_is_a_file("reference"), 2, "STUDY_CACHE_DIR", "a_file",
    "not a folder")
add(G, "cache_dir_is_a_file_compiled", _cache_is_a_file("compiled"), 2, "STUDY_CACHE_DIR", "a_file",
    "not a folder")


def _numba_cache_is_a_file(tmp):
    from study.simulate import simulate

    (tmp / "numba_file").write_text("not a folder\n")
    old = os.environ.get("NUMBA_CACHE_DIR")
    os.environ["NUMBA_CACHE_DIR"] = str(tmp / "numba_file")
    try:
        simulate("quick_return", t_end=0.05, backend="compiled")
    finally:
        os.environ.pop("NUMBA_CACHE_DIR") if old is None else os.environ.update(NUMBA_CACHE_DIR=old)


add(G, "numba_cache_dir_is_a_file", _numba_cache_is_a_file, ValueError, "NUMBA_CACHE_DIR", "numba_file",
    "not a folder")


def _cache_env(value, then):
    def action(tmp):
        os.environ["STUDY_CACHE_DIR"] = value(tmp)
        return ["simulate", "quick_return", "--t-end", "0.05", "--out", "run"]
    return action, then


def _made(rel):
    def then(tmp):
        folder = tmp / rel
        assert folder.is_dir() and any(folder.rglob("quick_return_*.py")), f"no generated code under {folder}"
    return then


def _nothing_in_cwd(tmp):
    stray = [p.name for p in tmp.iterdir() if p.name != "cache" and not p.name.startswith("run")]
    assert not stray, f"written into the working folder: {stray}"


for name, value, then in (
        ("cache_dir_empty_means_default", lambda tmp: "", _nothing_in_cwd),
        ("cache_dir_relative_is_the_working_folder", lambda tmp: "rel/cache", _made("rel/cache/codegen")),
        ("cache_dir_not_existing_is_made", lambda tmp: str(tmp / "new" / "deeper"), _made("new/deeper/codegen")),
):
    action, check = _cache_env(value, then)
    add(G, name, action, OK, cli=True, then=check)


def _stale_entries_ignored(tmp):
    """Entries of another version of the code (other keys) beside the current ones are never loaded."""
    from study.cli import main

    cache = tmp / "stale"
    (cache / "codegen").mkdir(parents=True)
    (cache / "codegen" / "quick_return_0000000000000000.py").write_text("raise RuntimeError('stale')\n")
    (cache / "numba" / "000000000000").mkdir(parents=True)
    (cache / "numba" / "000000000000" / "loop.integrate_segment-1.py311.nbi").write_bytes(b"stale")
    os.environ["STUDY_CACHE_DIR"] = str(cache)
    code = main(["simulate", "quick_return", "--t-end", "0.05", "--out", str(tmp / "run")])
    assert code == 0, f"exit {code}"


add(G, "stale_entries_of_another_version_ignored", _stale_entries_ignored, OK)


# --- 3. the pipeline's saved runs ---------------------------------------------------------------------------
def _store_json_missing(tmp):
    """A saved run whose JSON is gone (its CSV left alone) is computed again, not half-read."""
    import study.pipeline as pl
    from test_reliability_catalogue import _one_case_store

    case, store = _one_case_store(tmp)
    first = store.load(case)
    store.file(case, ".json").unlink()          # the pair broken: its CSV without its JSON
    log = io.StringIO()
    summary = pl.run_cases([case], store, pl.InlineExecutor(), stream=log)
    assert summary.computed == 1, f"the broken pair was reused: {summary}"
    np.testing.assert_array_equal(store.load(case).q, first.q)


add(G, "store_json_missing_is_recomputed", _store_json_missing, OK)
