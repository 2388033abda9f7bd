"""Checksums of files the study writes and later reuses (results, generated code, tables).

A file is reused only when its content still has the SHA-256 (and, for tables, the row count)
recorded when it was written. Anything else raises :class:`study.errors.ResultIntegrityError`
naming the file and what differs, so the caller recomputes instead of trusting it.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Mapping

from study.errors import ResultIntegrityError


def sha256_text(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def sha256_file(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def data_rows(text: str) -> int:
    """Rows of a CSV text after its header (complete lines only)."""
    return max(text.count("\n") - 1, 0)


def _umask() -> int:
    """The process's file-creation mask (read by setting it, then restoring it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write(path: Path, text: str) -> None:
    """Write UTF-8 ``text`` to a temporary file in the same folder, then rename: readers never see half a file."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        os.fchmod(fd, 0o666 & ~_umask())  # the mode open() would give, not mkstemp's private 0600
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:  # interrupted or failed: leave no temporary file behind
        Path(tmp).unlink(missing_ok=True)
        raise


def stage_files(files: Mapping[Path, str]) -> list[tuple[Path, Path]]:
    """Write each text (with :func:`atomic_write`) to a private staging folder beside its file; replace nothing.

    Returns the (staged, final) pairs for :func:`replace_together`. A failure while writing (disk full, an
    interruption) removes what was staged and propagates: no file was replaced.
    """
    staged: list[tuple[Path, Path]] = []
    folders: dict[Path, Path] = {}
    try:
        for path, text in files.items():
            path = Path(path)
            if path.parent not in folders:
                folders[path.parent] = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.",
                                                             suffix=".staging"))
            staged.append((folders[path.parent] / path.name, path))
            atomic_write(staged[-1][0], text)
    except BaseException:
        _discard_staged([tmp for tmp, _ in staged], folders.values())
        raise
    return staged


class PartlyReplacedError(OSError):
    """Renaming a set of files into place failed, and so did putting back the previous version of one already
    replaced: the set is now part new, part old."""


def replace_together(staged: list[tuple[Path, Path]]) -> None:
    """Rename files written by :func:`stage_files` into place as one set, and remove the staging folders.

    Before the first rename, each file to be replaced is kept (a hard link in the staging folder). If a rename
    fails or is interrupted (any exception, Ctrl-C included), the files already renamed get their previous content
    back (or are removed, where there was none) before the exception propagates: the set is all new or all old.
    Only if putting one back fails too is it left part new, part old: :class:`PartlyReplacedError` says so.
    """
    kept: dict[Path, Path] = {}
    done: list[Path] = []
    try:
        for tmp, path in staged:
            if path.exists():
                kept[path] = tmp.with_name(tmp.name + ".previous")
                _keep(path, kept[path])
        for tmp, path in staged:
            os.replace(tmp, path)
            done.append(path)
    except BaseException as exc:
        _put_back(done, kept, exc)
        raise
    finally:
        _discard_staged([tmp for tmp, _ in staged] + list(kept.values()), {tmp.parent for tmp, _ in staged})


def _keep(path: Path, keep: Path) -> None:
    """``keep`` holding ``path``'s current content: a hard link (no copy), or a copy where links are not supported."""
    try:
        os.link(path, keep)
    except OSError:
        shutil.copy2(path, keep)


def _put_back(done: list[Path], kept: dict[Path, Path], exc: BaseException) -> None:
    """Undo the renames of ``done`` (in reverse); PartlyReplacedError (from ``exc``) if one cannot be undone."""
    for path in reversed(done):
        try:
            if path in kept:
                os.replace(kept[path], path)
            else:
                path.unlink()
        except OSError as undo:
            raise PartlyReplacedError(
                getattr(exc, "errno", None) or undo.errno,
                f"renaming the new files into place failed ({exc!r}), and putting the previous {path.name} back "
                f"failed too ({undo})") from exc


def _discard_staged(files, folders) -> None:
    for tmp in files:
        Path(tmp).unlink(missing_ok=True)
    for folder in folders:
        with contextlib.suppress(OSError):
            Path(folder).rmdir()


def _sidecar(path: Path) -> Path:
    return path.with_name(path.name + ".sha256")


def write_checked(path: Path, text: str) -> None:
    """Write ``text`` and, after it, ``<path>.sha256`` holding its hash (the entry is valid once both exist)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, text)
    atomic_write(_sidecar(path), sha256_text(text) + "\n")


def verify_checked(path: Path) -> None:
    """Raise ResultIntegrityError unless ``path`` matches the hash written with it by :func:`write_checked`."""
    path = Path(path)
    side = _sidecar(path)
    if not side.exists():
        raise ResultIntegrityError(f"{path}: no checksum entry {side.name} (written by an older version, or "
                                   f"interrupted before its checksum)")
    expected = side.read_text().strip()
    actual = sha256_file(path)
    if actual != expected:
        raise ResultIntegrityError(f"{path}: content changed since it was written (SHA-256 {actual[:12]}..., "
                                   f"recorded {expected[:12]}...)")


def verify_text(path: Path, text: str, rows: int | None, sha256: str | None) -> None:
    """Raise ResultIntegrityError unless ``text`` (read from ``path``) has the recorded rows and SHA-256."""
    if rows is None or sha256 is None:
        raise ResultIntegrityError(f"{path}: no row count and checksum recorded (written by an older version)")
    if isinstance(rows, bool) or not isinstance(rows, int) or not isinstance(sha256, str):
        raise ResultIntegrityError(f"{path}: no row count and checksum recorded, but {rows!r:.40} and "
                                   f"{sha256!r:.40} (the record was edited)")
    got_rows = data_rows(text)
    if got_rows != rows:
        raise ResultIntegrityError(f"{path}: {got_rows} data rows, {rows} recorded when it was saved (truncated?)")
    got = sha256_text(text)
    if got != sha256:
        now = ("now empty: 0 data rows and no header" if not text
               else f"{got_rows} data row{'' if got_rows == 1 else 's'}, as recorded")
        raise ResultIntegrityError(f"{path}: SHA-256 {got[:12]}... differs from the recorded {sha256[:12]}... "
                                   f"(the file was changed after it was saved; {now})")


def read_json(path: Path, text: str | None = None) -> dict:
    """A JSON file (or its ``text``, already read) as a dict; ResultIntegrityError if it is not valid JSON
    (garbage, half a file) or not an object."""
    try:
        data = json.loads(Path(path).read_text() if text is None else text)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ResultIntegrityError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(data, dict):
        raise ResultIntegrityError(f"{path}: expected a JSON object, got {type(data).__name__}")
    return data


class RegeneratedWarning(UserWarning):
    """A cached generated file failed its checksum and was generated again."""


def ensure_generated(path: Path, generate) -> str | None:
    """Make ``path`` hold generated code whose checksum entry matches; returns why it was (re)generated.

    A missing file is generated; a file that fails :func:`verify_checked` (edited, cut, or from a
    version without checksums) is reported with a :class:`RegeneratedWarning` and generated again,
    never used. ``generate()`` returns the source text.
    """
    import warnings

    path = Path(path)
    if path.exists():
        try:
            verify_checked(path)
            return None
        except ResultIntegrityError as exc:
            why = str(exc)
            warnings.warn(f"generated code rejected and regenerated: {why}", RegeneratedWarning, stacklevel=2)
    else:
        why = "not generated yet"
    write_checked(path, generate())
    return why
