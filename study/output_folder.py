"""Output folders: a command writes only into a folder it made, or one that carries its marker.

A folder a command makes (or finds empty) gets the marker file ``.study-output``; the repository's own ``reports/``
carries it too (committed). Any other non-empty folder, or a file where a folder is wanted, is refused before any
work with one :class:`OutputFolderError` naming it: nothing a user made is overwritten or deleted.

- :func:`check_output_folder`: may the command write there? (writes nothing: call it before any work);
- :func:`claim_output_folder`: the same check, then the folder made (with its parents) and marked; call it just
  before the first write;
- :func:`require_output_folder`: a folder that must already be a marked output folder (one that is read).
"""

from __future__ import annotations

from pathlib import Path

from study.integrity import atomic_write

MARKER = ".study-output"
MARKER_TEXT = ("This folder is written by `python -m study` (its commands write only into folders that carry this "
               "file).\nDelete this file to keep study from writing here.\n")


class OutputFolderError(ValueError):
    """An output folder that study may not write into (a user's non-empty folder, a file, no marker)."""


def is_marked(folder: Path) -> bool:
    return (Path(folder) / MARKER).is_file()


def check_output_folder(folder: Path, argument: str = "--out") -> Path:
    """``folder`` if a command may write into it: new, empty, or marked; OutputFolderError otherwise. Writes nothing."""
    folder = Path(folder)
    existing = next((p for p in [folder, *folder.parents] if p.exists() or p.is_symlink()), None)
    if existing is not None and not existing.is_dir():
        where = "" if existing == folder else f" ({existing} is a file)"
        raise OutputFolderError(f"{argument} {folder}: not a folder{where}; give a new folder or one study made")
    if existing == folder and not is_marked(folder):
        entries = sorted(p.name for p in folder.iterdir())
        if entries:
            shown = ", ".join(entries[:3]) + (f" and {len(entries) - 3} more" if len(entries) > 3 else "")
            raise OutputFolderError(
                f"{argument} {folder}: a folder with files of its own ({shown}) and no {MARKER} marker, so not one "
                f"study made; refused, nothing written: give a new or empty folder")
    return folder


def claim_output_folder(folder: Path, argument: str = "--out") -> Path:
    """:func:`check_output_folder`, then make ``folder`` (and its parents) and mark it; returns it."""
    folder = check_output_folder(folder, argument)
    folder.mkdir(parents=True, exist_ok=True)
    if not is_marked(folder):
        atomic_write(folder / MARKER, MARKER_TEXT)
    return folder


def require_output_folder(folder: Path, argument: str = "--out") -> Path:
    """``folder`` if it exists and carries the marker (a folder study wrote, to be read); else OutputFolderError."""
    folder = Path(folder)
    if not folder.is_dir():
        raise OutputFolderError(f"{argument} {folder}: " + ("not a folder" if folder.exists() else "no such folder")
                                + "; give a report folder study wrote (default reports)")
    if not is_marked(folder):
        raise OutputFolderError(f"{argument} {folder}: no {MARKER} marker, so not a report folder study wrote; refused")
    return folder
