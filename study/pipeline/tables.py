"""The tables a pipeline run writes, each recorded (rows, checksum) so that a later read is checked."""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any, Mapping

import pandas as pd

from study.errors import ResultIntegrityError
from study.integrity import atomic_write, data_rows, sha256_text, verify_text

TABLE_FLOAT_FORMAT = "%.6g"  # 6 significant digits: the tables compare across runs byte for byte


def write_tables(tables: Mapping[str, pd.DataFrame], reports_dir: Path) -> list[Path]:
    """Write each table to ``tables/<name>.csv``; names ending in ``_timing`` go to ``timing/``.

    Timing (CPU or wall seconds) depends on the machine, so it is kept out of ``tables/``, whose
    files must be byte-identical between two runs.
    """
    written = []
    for name, frame in tables.items():
        folder = Path(reports_dir) / ("timing" if name.endswith("_timing") else "tables")
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{name}.csv"
        atomic_write(path, frame.to_csv(index=False, float_format=TABLE_FLOAT_FORMAT, lineterminator="\n"))
        written.append(path)
    return written


def table_entry(path: Path) -> dict[str, Any]:
    text = Path(path).read_text()
    return {"rows": data_rows(text), "sha256": sha256_text(text)}


def record_tables(written: Path, paths: list[Path]) -> None:
    """Record the tables just written (rows and SHA-256 of each) in the record file ``written``, which
    :func:`read_table` checks them against."""
    written.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(written, json.dumps({str(Path(p).resolve()): table_entry(p) for p in paths}, indent=1))


def table_record(written: Path, strict: bool = False) -> dict[str, Any]:
    """The tables a study wrote last time, {path: {rows, sha256}} (older records: a list of paths).

    A missing record is empty. An unreadable one (not valid JSON, not a list or object) is empty too,
    or, with ``strict``, a ResultIntegrityError naming the record file: the tables it lists cannot be
    checked against it.
    """
    written = Path(written)
    if not written.exists():
        return {}
    try:
        data = json.loads(written.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        if strict:
            raise ResultIntegrityError(f"{written}: pipeline record of tables is not valid JSON ({exc}); "
                                       f"the tables it lists cannot be checked") from None
        return {}
    if isinstance(data, list) and all(isinstance(p, str) for p in data):
        return {p: {} for p in data}
    if isinstance(data, dict):
        return data
    if strict:
        raise ResultIntegrityError(f"{written}: not a pipeline record of tables (a JSON {type(data).__name__}, "
                                   f"not an object); the tables it lists cannot be checked")
    return {}


def read_table(path: Path, record_root: Path) -> pd.DataFrame:
    """A table written by :func:`run_pipeline`, after checking it against the rows and checksum recorded
    when it was written (ResultIntegrityError otherwise: a table edited, cut or left over from another run,
    or a record that cannot be read)."""
    path = Path(path).resolve()
    for written in sorted((Path(record_root) / "tables").glob("*.json")):
        entry = table_record(written, strict=True).get(str(path))
        if entry is not None:
            if not isinstance(entry, dict):
                entry = {}
            if not path.exists():
                raise ResultIntegrityError(f"{path}: missing (listed in the pipeline record {written})")
            text = path.read_text()
            verify_text(path, text, entry.get("rows"), entry.get("sha256"))
            try:
                return pd.read_csv(io.StringIO(text))
            except pd.errors.EmptyDataError:  # a table without columns (an empty summary), as written
                return pd.DataFrame()
    raise ResultIntegrityError(f"{path}: no pipeline record lists this table (not written by the last run)")
