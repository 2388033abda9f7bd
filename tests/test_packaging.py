"""The package works once installed: its data ships inside it, and its outputs go where the user works.

``reference/`` (the repository's data folder) is the package ``study._data`` (setup.py, study/locations.py). A
wheel must carry every file of it; an installed package, run from a folder outside the repository, must find its
mechanisms and case lists and write into the working directory, not into the installation.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from study import locations

ROOT = Path(__file__).resolve().parents[1]
# What a wheel is built from: the files pyproject.toml and setup.py name (the package, its data, the readme).
SOURCE = ("study", "reference", "setup.py", "pyproject.toml", "README.md")


def files_under(folder: Path) -> list[Path]:
    """Every file under ``folder``, relative to it (the byte-code Python writes there left out)."""
    return sorted(p.relative_to(folder) for p in folder.rglob("*") if p.is_file() and "__pycache__" not in p.parts)


def data_files() -> list[Path]:
    """Every file under reference/, relative to it."""
    return files_under(ROOT / "reference")


def test_the_checkout_reads_its_own_reference_folder_and_writes_its_own_reports():
    assert locations.REFERENCE_DIR == ROOT / "reference"
    assert locations.CASES_DIR == ROOT / "reference" / "cases"
    assert locations.CHECKOUT == ROOT
    assert locations.REPORTS_DIR == ROOT / "reports"


def copy_sources(folder: Path) -> Path:
    """The files a wheel is built from, copied into ``folder`` (a stale build/ or egg-info of the checkout, whose
    file list setuptools would read back, cannot leak in)."""
    for name in SOURCE:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, folder / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy2(ROOT / name, folder / name)
    return folder


def test_the_build_copies_every_file_of_reference_into_the_package(tmp_path, monkeypatch):
    """setup.py's package list and package data, as the wheel's build step (build_py) reads them."""
    from distutils.core import run_setup   # setuptools' distutils

    monkeypatch.chdir(copy_sources(tmp_path))
    build_py = run_setup("setup.py", stop_after="config").get_command_obj("build_py")
    build_py.ensure_finalized()
    copied = {Path(build) / name for _, _, build, names in build_py.data_files for name in names}
    copied |= {Path(build_py.build_lib, *package.split("."), f"{module}.py")
               for package, module, _ in build_py.find_all_modules()}
    target = Path(build_py.build_lib, "study", "_data")
    missing = [str(rel) for rel in data_files() if target / rel not in copied]
    assert len(data_files()) > 20 and not missing, f"files of reference/ a wheel would not carry: {missing}"


def test_no_module_finds_data_or_reports_by_its_own_file_path():
    """The one home of 'where': study/locations.py. A path built from a module's __file__ towards reference/ or
    reports/ is the repository layout a wheel does not have."""
    offenders = [f"{path.relative_to(ROOT)}:{n}" for path in sorted((ROOT / "study").rglob("*.py"))
                 for n, line in enumerate(path.read_text().splitlines(), 1)
                 if "__file__" in line and ('"reference"' in line or '"reports"' in line)]
    assert not offenders, offenders


def _run(argv: list[str], cwd: Path, env: dict) -> str:
    done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)
    assert done.returncode == 0, f"{argv[1:]} exit {done.returncode}:\n{done.stderr[-2000:]}"
    return done.stdout


@pytest.mark.slow
def test_an_installed_wheel_runs_from_a_folder_outside_the_repository(tmp_path):
    """Build a wheel from a copy of the sources, install it into a folder, and run the command line and the library
    there with nothing of the repository on the path."""
    wheels, target, work = (tmp_path / name for name in ("wheels", "target", "work"))
    source = copy_sources(tmp_path / "source")
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    _run(pip + ["wheel", "--no-deps", "-w", str(wheels), str(source)], tmp_path, dict(os.environ))
    (wheel,) = wheels.glob("study-*.whl")
    _run(pip + ["install", "--no-deps", "--target", str(target), str(wheel)], tmp_path, dict(os.environ))
    work.mkdir()
    env = {**os.environ, "PYTHONPATH": str(target), "STUDY_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONSAFEPATH": "1"}
    where = _run([sys.executable, "-c", "import study, study.locations as L, study.bench.settings as b, "
                  "study.errata.table as e; print(study.__file__, L.REFERENCE_DIR, L.CHECKOUT, "
                  "b.OUT.resolve(), e.DEFAULT_OUT_DIR.resolve(), sep='\\n')"], work, env).split("\n")
    assert Path(where[0]).is_relative_to(target) and Path(where[1]) == target / "study" / "_data", where
    assert where[2] == "None" and where[3:5] == [str(work / "reports" / "benchmarks"), str(work / "reports" / "tables")]
    assert files_under(target / "study" / "_data") == data_files()

    _run([sys.executable, "-m", "study", "simulate", "slider_crank", "--t-end", "0.1", "--out", "x"], work, env)
    assert (work / "x.csv").stat().st_size > 0 and (work / "x.json").stat().st_size > 0
    out = _run([sys.executable, "-c", "import study; r = study.simulate('slider_crank', t_end=0.1); "
                "print(r.meta['mechanism'], r.t[-1])"], work, env)
    assert out.split() == ["slider_crank", "0.1"]
    assert not (target / "reports").exists() and not (target / "study" / "reports").exists()


def test_a_checkout_that_is_not_installed_is_told_how_to_install_it(monkeypatch):
    monkeypatch.setattr(locations, "DATA_PACKAGE", "study._no_such_data")
    with pytest.raises(ModuleNotFoundError, match=r"study\._no_such_data.*make \.venv/\.installed.*reference/"):
        locations._data_dir()
