"""The cache folder (study.cache_folder) and numba's healing cache (study.kernels.cache)."""

from __future__ import annotations

import importlib.util
import pickle
import sys
import warnings

import pytest

import study.cache_folder as cf
from study.kernels.cache import CacheDiscardedWarning
from study.sources import PACKAGE_ROOT


def test_default_is_the_checkouts_cache_folder(monkeypatch):
    monkeypatch.delenv("STUDY_CACHE_DIR", raising=False)
    assert cf.checkout_root() == PACKAGE_ROOT.parent
    assert cf.configured_cache_dir() == (PACKAGE_ROOT.parent / ".cache", None)


def test_installed_package_uses_the_users_cache_folder(monkeypatch, tmp_path):
    monkeypatch.setattr(cf, "checkout_root", lambda: None)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cf.default_cache_dir() == tmp_path / "xdg" / "study"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/xdg")   # not absolute: ignored, as the XDG specification says
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cf.default_cache_dir() == tmp_path / "home" / ".cache" / "study"


def test_empty_variable_means_the_default_and_relative_is_from_the_working_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("STUDY_CACHE_DIR", "")
    assert cf.configured_cache_dir() == (cf.default_cache_dir(), None)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("STUDY_CACHE_DIR", "rel/cache")
    assert cf.cache_dir() == tmp_path / "rel" / "cache" and (tmp_path / "rel" / "cache").is_dir()


@pytest.mark.parametrize("where", ["file", "package"])
def test_unusable_folders_are_refused_by_variable_and_path(monkeypatch, tmp_path, where):
    path = tmp_path / "a_file" if where == "file" else PACKAGE_ROOT / "fast" / "cache_here"
    if where == "file":
        path.write_text("x")
    monkeypatch.setenv("STUDY_CACHE_DIR", str(path))
    with pytest.raises(cf.CacheFolderError, match=rf"STUDY_CACHE_DIR={path}: .*(not a folder|inside the package)"):
        cf.cache_dir()
    assert not (PACKAGE_ROOT / "fast" / "cache_here").exists()


SOURCE = "from study.kernels.cache import kernel\n\n@kernel()\ndef twice(x):\n    return 2.0 * x\n"


def _load(path, name):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _overwrite(path):
    path.write_bytes(b"garbage")


def _cut_in_half(path):
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def _valid_pickle_wrong_content(path):
    path.write_bytes(pickle.dumps(("not", "a", "compiled", "function")))


# the damages of tests/round3/caches.py, which makes the same three in a real process (two in the slow suite)
@pytest.mark.parametrize("suffix, damage", [("nbi", _overwrite), ("nbc", _cut_in_half),
                                            ("nbc", _valid_pickle_wrong_content)])
def test_a_damaged_entry_is_discarded_and_recompiled(monkeypatch, tmp_path, suffix, damage):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    source = tmp_path / "kernels_under_test.py"
    source.write_text(SOURCE)
    assert _load(source, "kernels_under_test").twice(2.0) == 4.0          # compiled and saved
    index = next((tmp_path / "numba").rglob("*.twice-*.nbi"))
    damage(next((tmp_path / "numba").rglob(f"*.twice-*.{suffix}")))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert _load(source, "kernels_under_test").twice(3.0) == 6.0      # a new dispatcher: loads, fails, heals
    messages = [str(w.message) for w in caught if w.category is CacheDiscardedWarning]
    assert len(messages) == 1 and index.name in messages[0] and "recompiling" in messages[0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert _load(source, "kernels_under_test").twice(4.0) == 8.0      # saved afresh: loads quietly
    assert not [w for w in caught if w.category is CacheDiscardedWarning]
    sys.modules.pop("kernels_under_test", None)
