"""The one writer and the one checked reader of the study's tables.

:func:`write_table` writes a table (a CSV, or the errata's Markdown) and records its rows, SHA-256 and the command
that rebuilds it in ``checksums.json`` beside it (one record per folder: ``tables/``, ``timing/``,
``benchmarks/``, a validation's ``tables/``). :func:`read_table` reads a table only after checking it against that
record, and refuses (ResultIntegrityError naming the file and the command that rebuilds it) a table that differs:
cut, edited, emptied, a column added or removed; a table the record lists that is gone; a table no record lists; a
record that is missing or not readable. :func:`check_tables` checks a whole folder (a report does, before it writes
anything).
"""

from __future__ import annotations

import contextlib
import fcntl
import io
import json
import os
from pathlib import Path
from typing import Any, Mapping

import pandas as pd

from study.errors import ResultIntegrityError
from study.integrity import atomic_write, data_rows, sha256_text, verify_text

TABLE_FLOAT_FORMAT = "%.6g"  # 6 significant digits: the tables compare across runs byte for byte
CHECKSUMS = "checksums.json"   # the record of the tables of a folder, beside them
TABLE_SUFFIXES = (".csv", ".md")


def write_tables(tables: Mapping[str, pd.DataFrame], reports_dir: Path, command: str) -> list[Path]:
    """Write each table to ``tables/<name>.csv`` (names ending in ``_timing``: ``timing/``) with :func:`write_table`.

    Timing (CPU or wall seconds) depends on the machine, so it is kept out of ``tables/``, whose
    files must be byte-identical between two runs.
    """
    written = []
    for name, frame in tables.items():
        folder = Path(reports_dir) / ("timing" if name.endswith("_timing") else "tables")
        text = frame.to_csv(index=False, float_format=TABLE_FLOAT_FORMAT, lineterminator="\n")
        written.append(write_table(folder / f"{name}.csv", text, command))
    return written


def write_table(path: Path, text: str, command: str) -> Path:
    """Write ``text`` to ``path`` (atomically) and record it, with ``command`` (what rebuilds it), in the folder's
    ``checksums.json``. The table is written first: one interrupted before its record is refused when read."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, text)
    record_written(path, command)
    return path


def record_written(path: Path, command: str) -> None:
    """Record the table at ``path`` as written, with ``command``, in the folder's ``checksums.json`` (for
    :func:`write_table`, and once for the committed snapshot's tables)."""
    path = Path(path)
    with _locked(path.parent):
        record = _load(path.parent, missing_ok=True)
        text = path.read_text(encoding="utf-8")
        record[path.name] = {"rows": data_rows(text), "sha256": sha256_text(text), "command": command}
        _save(path.parent, record)


def forget_table(path: Path) -> None:
    """Remove a table and its entry in the record (a table whose study no longer writes it: no stale table may pass
    for a current one)."""
    path = Path(path)
    path.unlink(missing_ok=True)
    if (path.parent / CHECKSUMS).exists():
        with _locked(path.parent):
            record = _load(path.parent)
            if record.pop(path.name, None) is not None:
                _save(path.parent, record)


def verified_text(path: Path) -> str:
    """The text of a table after checking it against its record; ResultIntegrityError naming the file otherwise."""
    path = Path(path)
    entry = _load(path.parent).get(path.name)
    if not isinstance(entry, dict):
        raise ResultIntegrityError(f"{path}: no record lists this table ({path.parent / CHECKSUMS} has no entry "
                                   f"for it): not written by study, or written by hand; remove it, or rebuild it "
                                   f"with the command that writes it")
    rebuild = f"; rebuild it with `{entry.get('command', 'python -m study reproduce')}`"
    if not path.exists():
        raise ResultIntegrityError(f"{path}: missing (listed in {CHECKSUMS}){rebuild}")
    try:
        text = path.read_text(encoding="utf-8")
        verify_text(path, text, entry.get("rows"), entry.get("sha256"))
    except UnicodeDecodeError as exc:
        raise ResultIntegrityError(f"{path}: not a text table ({exc}){rebuild}") from None
    except ResultIntegrityError as exc:
        raise ResultIntegrityError(f"{exc}{rebuild}") from None
    return text


def read_table(path: Path, record_root: Path | None = None, missing_ok: bool = False,
               **read_csv: Any) -> pd.DataFrame | None:
    """A table, after checking it against the record beside it (:func:`verified_text`); ``read_csv`` are passed to
    :func:`pandas.read_csv`.

    ``missing_ok``: None for a table that is neither there nor recorded (its study was not run). ``record_root``: the
    table must also be listed by a study's record there (:func:`record_tables`), i.e. written by that pipeline run.
    """
    path = Path(path)
    if missing_ok and not path.exists() and not recorded(path):
        return None
    if record_root is not None:
        _listed(path, Path(record_root))
    text = verified_text(path)
    try:
        return pd.read_csv(io.StringIO(text), **read_csv)
    except pd.errors.EmptyDataError:  # a table without columns (an empty summary), as written
        return pd.DataFrame()
    except (pd.errors.ParserError, ValueError) as exc:
        raise ResultIntegrityError(f"{path}: not a readable table ({' '.join(str(exc).split())})") from None


def recorded(path: Path) -> bool:
    """Whether the record beside ``path`` lists it (a missing record lists nothing)."""
    path = Path(path)
    return path.name in _load(path.parent, missing_ok=True)


def table_names(folder: Path) -> list[str]:
    """The tables the record of ``folder`` lists (none if it has no record)."""
    return sorted(_load(Path(folder), missing_ok=True))


def check_tables(folder: Path) -> int:
    """Check every table of ``folder`` (``*.csv``, ``*.md``) and every table its record lists; returns how many.

    A folder without tables and without a record passes (nothing was written there yet).
    """
    folder = Path(folder)
    files = {p.name for p in folder.iterdir() if p.suffix in TABLE_SUFFIXES} if folder.is_dir() else set()
    if not files and not (folder / CHECKSUMS).exists():
        return 0
    names = sorted(files | set(_load(folder)))
    for name in names:
        verified_text(folder / name)
    return len(names)


# --- the record beside the tables --------------------------------------------------------------
@contextlib.contextmanager
def _locked(folder: Path):
    """An exclusive lock on ``folder`` (processes writing tables into one folder at once update its record in turn)."""
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _load(folder: Path, missing_ok: bool = False) -> dict[str, Any]:
    path = Path(folder) / CHECKSUMS
    if not path.exists():
        if missing_ok:
            return {}
        raise ResultIntegrityError(f"{path}: missing, so the tables of {folder} cannot be checked (written by hand, "
                                   f"or by an older version); rebuild them with `python -m study reproduce`")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ResultIntegrityError(f"{path}: not valid JSON ({exc}), so the tables of {folder} cannot be checked; "
                                   f"rebuild them with `python -m study reproduce`") from None
    if not isinstance(data, dict):
        raise ResultIntegrityError(f"{path}: a JSON {type(data).__name__}, not the record of the tables of {folder}")
    return data


def _save(folder: Path, record: dict[str, Any]) -> None:
    atomic_write(Path(folder) / CHECKSUMS, json.dumps(dict(sorted(record.items())), indent=1, sort_keys=True) + "\n")


# --- which tables a study wrote last time (the pipeline's own record, in its cache) ---------------
def record_tables(written: Path, paths: list[Path]) -> None:
    """Record which tables a study just wrote (their paths) in ``written``: the pipeline removes them when the
    study's summary fails next time, and :func:`read_table` with ``record_root`` requires a table listed there."""
    written.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(written, json.dumps(sorted(str(Path(p).resolve()) for p in paths), indent=1))


def table_record(written: Path, strict: bool = False) -> list[str]:
    """The tables a study wrote last time (their resolved paths). A missing record is empty. An unreadable one (not
    valid JSON, not a list or object of paths) is empty too, or, with ``strict``, a ResultIntegrityError naming it."""
    written = Path(written)
    if not written.exists():
        return []
    try:
        data = json.loads(written.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        if strict:
            raise ResultIntegrityError(f"{written}: pipeline record of tables is not valid JSON ({exc}); "
                                       f"the tables it lists cannot be checked") from None
        return []
    if isinstance(data, (list, dict)) and all(isinstance(p, str) for p in data):
        return list(data)
    if strict:
        raise ResultIntegrityError(f"{written}: not a pipeline record of tables (a JSON {type(data).__name__}, "
                                   f"not a list of paths); the tables it lists cannot be checked")
    return []


def _listed(path: Path, record_root: Path) -> None:
    resolved = str(path.resolve())
    for written in sorted((record_root / "tables").glob("*.json")):
        if resolved in table_record(written, strict=True):
            return
    raise ResultIntegrityError(f"{path}: no pipeline record lists this table (not written by the last run)")
