"""The tables a pipeline run writes, each recorded (rows, checksum) so that a later read is checked."""

from __future__ import annotations

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


def table_record(written: Path) -> dict[str, Any]:
    """The tables a study wrote last time, {path: {rows, sha256}} (older records: a list of paths)."""
    if not written.exists():
        return {}
    try:
        data = json.loads(written.read_text())
    except json.JSONDecodeError:
        return {}
    return {p: {} for p in data} if isinstance(data, list) else data


def read_table(path: Path, record_root: Path) -> pd.DataFrame:
    """A table written by :func:`run_pipeline`, after checking it against the rows and checksum recorded
    when it was written (ResultIntegrityError otherwise: a table edited, cut or left over from another run)."""
    path = Path(path).resolve()
    for written in sorted((Path(record_root) / "tables").glob("*.json")):
        entry = table_record(written).get(str(path))
        if entry is not None:
            verify_text(path, path.read_text(), entry.get("rows"), entry.get("sha256"))
            return pd.read_csv(path)
    raise ResultIntegrityError(f"{path}: no pipeline record lists this table (not written by the last run)")
