"""The result store: one saved result per case key, with failures recorded beside it.

:class:`Store` keeps the saved results (atomically written, checked on every read: a damaged one
is reported and never used) and the failed cases with their errors.
"""

from __future__ import annotations

import json
from pathlib import Path

from study.errors import ResultIntegrityError
from study.integrity import atomic_write, read_json
from study.pipeline.cases import Case
from study.results import SimulationResult


def _stat(path: Path):
    try:
        return path.stat()
    except FileNotFoundError:
        return None


class MissingResult(LookupError):
    """A case has no saved result (not run yet, or it failed)."""


class CorruptResult(MissingResult):
    """A case's saved result failed its check (row count, checksum, JSON): it is not used."""


class Store:
    """Saved results under ``root/<key>.{csv,json}``; failures as ``<key>.failed.json``.

    The file name is the case's key alone: cases with equal inputs (a reference shared by two studies,
    a grid point in two sweeps) share one saved result, whatever their study, group or labels. The
    readable case (study, group, labels) is kept in the JSON's ``meta.case``.
    """

    def __init__(self, root: Path):
        self.root = Path(root)
        self._verified: dict[str, tuple] = {}  # key -> ((mtimes), problem): each file is hashed once

    def base(self, case: Case) -> Path:
        return self.root / case.key()

    def file(self, case: Case, suffix: str) -> Path:
        base = self.base(case)
        return base.with_name(base.name + suffix)

    def problem(self, case: Case) -> str | None:
        """None if the case has a saved result that passes its check, else why not ('not saved' or the check)."""
        json_path = self.file(case, ".json")
        if not json_path.exists():  # the JSON is written last
            return "not saved"
        stamp = tuple((s.st_mtime_ns, s.st_size, s.st_ino) if (s := _stat(p)) else None
                      for p in (json_path, self.file(case, ".csv")))
        cached = self._verified.get(case.key())
        if cached is not None and cached[0] == stamp:
            return cached[1]
        try:
            SimulationResult.verify(self.base(case))
            why = None
        except ResultIntegrityError as exc:
            why = str(exc)
        self._verified[case.key()] = (stamp, why)
        return why

    def has(self, case: Case) -> bool:
        """True if the case has a saved result that passes its check (row count, checksum)."""
        return self.problem(case) is None

    def load(self, case: Case) -> SimulationResult:
        why = self.problem(case)
        if why == "not saved":
            failure = self.failure(case)
            why = f"it failed: {failure['error']}" if failure else "it has not been run"
            raise MissingResult(f"no saved result for case {case.name} ({why})")
        if why is not None:
            raise CorruptResult(f"the saved result of case {case.name} is not used: {why}")
        try:
            return SimulationResult.load(self.base(case), verify=False)  # just verified
        except ResultIntegrityError as exc:  # replaced or removed since it was verified
            self._verified.pop(case.key(), None)
            raise CorruptResult(f"the saved result of case {case.name} is not used: {exc}") from None

    def discard(self, case: Case) -> None:
        """Remove a saved result that failed its check (so it can never be read)."""
        for suffix in (".json", ".csv"):
            self.file(case, suffix).unlink(missing_ok=True)
        self._verified.pop(case.key(), None)

    def save(self, case: Case, result: SimulationResult) -> Path:
        result.meta["case"] = {**case.spec(), "key": case.key(), "labels": dict(case.labels)}
        path = result.save(self.base(case))
        self._failure_path(case).unlink(missing_ok=True)
        return path

    def _failure_path(self, case: Case) -> Path:
        return self.file(case, ".failed.json")

    def record_failure(self, case: Case, error: str, details: str) -> None:
        path = self._failure_path(case)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(path, json.dumps({"case": case.name, "key": case.key(), "error": error,
                                        "traceback": details}, indent=1))

    def failure(self, case: Case) -> dict | None:
        path = self._failure_path(case)
        if not path.exists():
            return None
        try:
            return read_json(path)
        except ResultIntegrityError as exc:
            return {"case": case.name, "key": case.key(), "error": f"unreadable failure record ({exc})"}
