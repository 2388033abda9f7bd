"""The one result type for every run (in-house solver and Exudyn), with lossless save/load.

A result holds sampled time series (time, q, qd, qdd, lambda, Phi, Phidot, energies, forces of
interest), solver statistics and metadata. It is saved as a CSV of the series (17 significant
digits, so the round trip is exact) plus a JSON sidecar with statistics and metadata. The sidecar
records the CSV's row count and SHA-256, and its own SHA-256 (``json_sha256``, of its canonical
text without that key): both files are checked before a saved result is reused.
"""

from __future__ import annotations

import json
import platform
import sys
from dataclasses import dataclass, field
from importlib import metadata as importlib_metadata
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from study.errors import NonFiniteError, ResultIntegrityError
from study.integrity import (PartlyReplacedError, data_rows, read_json, replace_together, sha256_text, stage_files,
                             verify_text)

Array = np.ndarray

# The sidecar's own checksum: SHA-256 of its canonical text (sorted keys, indent 1) without this key.
JSON_CHECKSUM_KEY = "json_sha256"

# Packages whose versions go into every result's metadata.
TRACKED_PACKAGES = ("study", "numpy", "scipy", "sympy", "pandas", "exudyn", "numba")


def package_versions() -> dict[str, str]:
    out = {"python": sys.version.split()[0], "platform": platform.platform()}
    for name in TRACKED_PACKAGES:
        try:
            out[name] = importlib_metadata.version(name)
        except importlib_metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


@dataclass
class SimulationResult:
    """Sampled solution of one run.

    Attributes
    ----------
    t : (N,) times [s]
    q, qd, qdd : (N, m) coordinates, rates, accelerations
    lam : (N, r) Lagrange multipliers (M qdd + Phi_q^T lam = Q)
    phi, phidot : (N, r) constraint residuals Phi(q) and Phi_q qd
    energies : name -> (N,); 'kinetic', 'potential' and 'work_<load>' (work done by each
        non-conservative load since t0, including friction as 'work_friction_<contact>')
    forces : name -> (N,); forces of interest (normal and friction forces, joint reactions, ...)
    stats : solver statistics (steps, nfev, projections, cpu_seconds, events, ...)
    meta : method, settings, parameter-set hash, package versions, ...
    """

    t: Array
    q: Array
    qd: Array
    qdd: Array
    lam: Array
    phi: Array
    phidot: Array
    energies: dict[str, Array] = field(default_factory=dict)
    forces: dict[str, Array] = field(default_factory=dict)
    stats: dict[str, Any] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = len(self.t)
        for key in ("q", "qd", "qdd", "lam", "phi", "phidot"):
            value = np.asarray(getattr(self, key), dtype=float)
            if value.ndim == 1:
                value = value.reshape(n, -1)
            if value.shape[0] != n:
                raise ValueError(f"{key} has {value.shape[0]} rows, expected {n} (one per time)")
            setattr(self, key, value)
        for group in ("energies", "forces"):
            for name, value in getattr(self, group).items():
                if np.shape(value) != (n,):
                    raise ValueError(f"{group}[{name!r}] has shape {np.shape(value)}, expected ({n},)")

    def check_finite(self) -> None:
        """Raise NonFiniteError naming the first sample (time) and quantity that is NaN or infinite."""
        arrays = [self.t, self.q, self.qd, self.qdd, self.lam, self.phi, self.phidot,
                  *self.energies.values(), *self.forces.values()]
        if all(np.isfinite(a).all() for a in arrays):  # the cheap test; names only for the message
            return
        for name, values in self.series():
            bad = ~np.isfinite(values)
            if bad.any():
                k = int(np.argmax(bad))
                t = float(self.t[k]) if np.isfinite(self.t[k]) else float("nan")
                raise NonFiniteError(
                    f"non-finite {name} = {values[k]!r} at sample {k} (t = {t:.9g} s) of "
                    f"{self.meta.get('mechanism', self.meta.get('engine', 'a run'))}: a failed run (a step too "
                    f"large, non-finite forces or a singular matrix), not a result", t=t, quantity=name)

    def series(self):
        """(column name, (N,) values) of every sampled series, as in the CSV."""
        for name, values in self.to_dataframe().items():
            yield name, np.asarray(values, dtype=float)

    # --- derived quantities ---------------------------------------------------------------
    def energy_balance(self) -> Array:
        """kinetic + potential - sum of work of non-conservative loads; constant for an exact solution."""
        total = self.energies.get("kinetic", 0.0) + self.energies.get("potential", 0.0)
        for name, value in self.energies.items():
            if name.startswith("work_"):
                total = total - value
        return np.asarray(total, dtype=float)

    def summary(self) -> dict[str, float]:
        balance = self.energy_balance()
        scale = max(np.abs(self.energies.get("kinetic", np.zeros(1))).max(), 1e-300)
        return {
            "max_abs_phi": float(np.abs(self.phi).max()) if self.phi.size else 0.0,
            "max_abs_phidot": float(np.abs(self.phidot).max()) if self.phidot.size else 0.0,
            "energy_error": float(np.abs(balance - balance[0]).max()),
            "energy_error_relative": float(np.abs(balance - balance[0]).max() / scale),
            "cpu_seconds": float(self.stats.get("cpu_seconds", float("nan"))),
        }

    # --- tabular form and persistence ------------------------------------------------------
    def to_dataframe(self) -> pd.DataFrame:
        names = self.meta.get("coordinate_names") or [f"q{i + 1}" for i in range(self.q.shape[1])]
        cols: dict[str, Array] = {"t": self.t}
        for i, n in enumerate(names):
            cols[n] = self.q[:, i]
        for i, n in enumerate(names):
            cols[f"{n}_dot"] = self.qd[:, i]
        for i, n in enumerate(names):
            cols[f"{n}_ddot"] = self.qdd[:, i]
        for key in ("lam", "phi", "phidot"):
            for j in range(getattr(self, key).shape[1]):
                cols[f"{key}{j + 1}"] = getattr(self, key)[:, j]
        for name, value in self.energies.items():
            cols[f"energy:{name}"] = value
        for name, value in self.forces.items():
            cols[f"force:{name}"] = value
        return pd.DataFrame(cols)

    def save(self, path: str | Path) -> Path:
        """Write ``<path>.csv`` and ``<path>.json`` as one; returns the CSV path.

        Both files are written to temporary files first, then renamed into place as one set
        (:func:`study.integrity.replace_together`): if writing or a rename fails, or is interrupted, the files
        already renamed get their previous content back, so a previous result there stays whole. Only if that,
        too, fails is the pair left part new, part old; the JSON records the CSV's checksum, so such a pair is
        refused when read, never used.
        """
        base = _base(path)
        base.parent.mkdir(parents=True, exist_ok=True)
        self.check_finite()
        csv_text = self.to_dataframe().to_csv(index=False, float_format="%.17g", lineterminator="\n")
        sidecar = _jsonable({
            "shape": {"m": self.q.shape[1], "r": self.lam.shape[1]},
            "energies": list(self.energies),
            "forces": list(self.forces),
            "stats": self.stats,
            "meta": self.meta,
            "csv": {"rows": data_rows(csv_text), "sha256": sha256_text(csv_text)},
        })
        sidecar[JSON_CHECKSUM_KEY] = _json_checksum(sidecar)
        csv_path, json_path = _with(base, ".csv"), _with(base, ".json")
        try:
            replace_together(stage_files({csv_path: csv_text,
                                          json_path: json.dumps(sidecar, indent=1, sort_keys=True)}))
        except PartlyReplacedError as exc:
            raise OSError(exc.errno, f"{base}: result saved only in part: {exc.strerror}; {json_path.name} and "
                                     f"{csv_path.name} do not match: the pair is refused when read, not "
                                     f"reused") from exc
        except OSError as exc:
            raise OSError(exc.errno, f"{base}: result not saved, writing {csv_path.name} and {json_path.name} "
                                     f"failed ({exc}); no file was replaced, any previous result intact") from exc
        return csv_path

    @classmethod
    def verify(cls, path: str | Path) -> dict:
        """Check a saved result before reuse; returns its sidecar. ResultIntegrityError names what is wrong.

        The JSON must parse, record the CSV's row count and SHA-256, and still have its own SHA-256
        (``json_sha256``; an edited statistic or setting fails) and be the very text saved (a sidecar
        rewritten with the same values fails too); the CSV must match what the JSON
        records (a truncated, cut or edited CSV fails).
        """
        base = _base(path)
        side, text = _read_sidecar(base)
        json_path, csv_path = _with(base, ".json"), _with(base, ".csv")
        record = side.get("csv") if isinstance(side.get("csv"), dict) else {}
        if record.get("rows") is None or record.get("sha256") is None:
            raise ResultIntegrityError(f"{csv_path}: no row count and checksum recorded in {json_path.name} "
                                       f"(written by an older version, or edited)")
        recorded = side.pop(JSON_CHECKSUM_KEY, None)
        if not isinstance(recorded, str):
            raise ResultIntegrityError(f"{json_path}: no checksum of its own ({JSON_CHECKSUM_KEY}; written by an "
                                       f"older version, or edited): not reused")
        got = _json_checksum(side)
        if got != recorded:
            raise ResultIntegrityError(f"{json_path}: SHA-256 {got[:12]}... of its content differs from the recorded "
                                       f"{recorded[:12]}... (the file was changed after it was saved)")
        saved_text = json.dumps({**side, JSON_CHECKSUM_KEY: recorded}, indent=1, sort_keys=True)
        if text != saved_text:  # same values, other text: rewritten (by hand or a tool) after it was saved
            raise ResultIntegrityError(f"{json_path}: SHA-256 {sha256_text(text)[:12]}... of its text differs from "
                                       f"{sha256_text(saved_text)[:12]}..., that of the text saved with these values "
                                       f"(the file was rewritten after it was saved)")
        if not csv_path.exists():
            raise ResultIntegrityError(f"{csv_path}: missing (its JSON {json_path.name} exists)")
        verify_text(csv_path, csv_path.read_text(), record.get("rows"), record.get("sha256"))
        return side

    @classmethod
    def load(cls, path: str | Path, verify: bool = True) -> "SimulationResult":
        """Read a saved result; with ``verify`` (default) it is checked first (:meth:`verify`).

        Whether verified or not, a sidecar or CSV that does not describe a result (missing keys, columns
        that do not match) raises ResultIntegrityError naming the file.
        """
        base = _base(path)
        side = cls.verify(base) if verify else _read_sidecar(base)[0]
        json_path, csv_path = _with(base, ".json"), _with(base, ".csv")
        m, r, energy_names, force_names, stats, meta = _layout(side, json_path)
        try:
            df = pd.read_csv(csv_path)
        except FileNotFoundError:
            raise ResultIntegrityError(f"{csv_path}: missing (its JSON {json_path.name} exists)") from None
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
            raise ResultIntegrityError(f"{csv_path}: not a readable CSV ({exc})") from None
        expected = 1 + 3 * m + 3 * r + len(energy_names) + len(force_names)
        columns = [*(f"energy:{n}" for n in energy_names), *(f"force:{n}" for n in force_names)]
        missing = [c for c in columns if c not in df.columns]
        if df.shape[1] != expected or missing:
            raise ResultIntegrityError(
                f"{csv_path}: {df.shape[1]} columns, {expected} expected from {json_path.name} (m = {m} "
                f"coordinates, r = {r} constraints, {len(energy_names)} energies, {len(force_names)} forces)"
                + (f"; missing {', '.join(missing)}" if missing else ""))
        try:
            data = df.to_numpy(dtype=float)
        except (TypeError, ValueError) as exc:
            raise ResultIntegrityError(f"{csv_path}: a value is not a number ({exc})") from None
        t = data[:, 0]
        q, qd, qdd = data[:, 1:1 + m], data[:, 1 + m:1 + 2 * m], data[:, 1 + 2 * m:1 + 3 * m]
        k = 1 + 3 * m
        lam, phi, phidot = data[:, k:k + r], data[:, k + r:k + 2 * r], data[:, k + 2 * r:k + 3 * r]
        energies = {n: df[f"energy:{n}"].to_numpy(dtype=float) for n in energy_names}
        forces = {n: df[f"force:{n}"].to_numpy(dtype=float) for n in force_names}
        return cls(t, q, qd, qdd, lam, phi, phidot, energies, forces, stats, meta)


def check_save_target(path: str | Path, argument: str = "--out") -> None:
    """ValueError unless saving a result at ``path`` would replace nothing but a saved result: ``path`` is not a
    folder, and its ``.csv`` and ``.json`` are absent or the pair of a saved result (a JSON sidecar with its own
    checksum). Writes nothing; a command calls it before any work."""
    base = _base(path)
    if base.is_dir():
        raise ValueError(f"{argument} {path}: a folder; a result is saved as <name>.csv and <name>.json, so give a "
                         f"file name (e.g. {base / 'run'})")
    csv_path, json_path = _with(base, ".csv"), _with(base, ".json")
    for p in (csv_path, json_path):
        if p.exists() and not p.is_file():
            raise ValueError(f"{argument} {path}: {p} is a folder, not a saved result; refused, nothing written")
    if not json_path.exists():
        if csv_path.exists():
            raise ValueError(f"{argument} {path}: {csv_path} exists and is not a saved result (no {json_path.name} "
                             f"beside it); refused, nothing written: give another name")
        return
    try:
        side = _read_sidecar(base)[0]
    except (ResultIntegrityError, OSError):
        side = {}
    if JSON_CHECKSUM_KEY not in side or not isinstance(side.get("csv"), dict):
        raise ValueError(f"{argument} {path}: {json_path} exists and is not a saved result (not the JSON of a "
                         f"saved result's pair); refused, nothing written: give another name")


def _base(path: str | Path) -> Path:
    """The path without a trailing .csv/.json; any other dots are part of the name ('h0.001')."""
    path = Path(path)
    return path.with_name(path.name[:-len(path.suffix)]) if path.suffix in (".csv", ".json") else path


def _with(base: Path, suffix: str) -> Path:
    return base.with_name(base.name + suffix)


def _json_checksum(sidecar: Mapping[str, Any]) -> str:
    """SHA-256 of the sidecar's canonical text without its own checksum (what ``json_sha256`` records)."""
    rest = {k: v for k, v in sidecar.items() if k != JSON_CHECKSUM_KEY}
    return sha256_text(json.dumps(rest, indent=1, sort_keys=True))


def _read_sidecar(base: Path) -> tuple[dict, str]:
    """The JSON sidecar of a saved result and its text; ResultIntegrityError if it is missing or not a JSON object."""
    json_path = _with(base, ".json")
    if not json_path.exists():
        csv_path = _with(base, ".csv")
        also = (f" (its CSV {csv_path.name} exists)" if csv_path.exists()
                else f", and so is {csv_path.name}: no result is saved there")
        raise ResultIntegrityError(f"{json_path}: missing{also}")
    try:
        text = json_path.read_text()
    except UnicodeDecodeError as exc:
        raise ResultIntegrityError(f"{json_path}: not valid JSON ({exc})") from None
    return read_json(json_path, text), text


def _layout(side: Mapping[str, Any], json_path: Path) -> tuple[int, int, list, list, dict, dict]:
    """(m, r, energy names, force names, stats, meta) from a sidecar; ResultIntegrityError if malformed."""
    problems = []
    shape = side.get("shape")
    m = shape.get("m") if isinstance(shape, dict) else None
    r = shape.get("r") if isinstance(shape, dict) else None
    for key, value in (("shape.m", m), ("shape.r", r)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            problems.append(f"{key} is {_short(value)}, not a count")
    names = {}
    for key in ("energies", "forces"):
        value = side.get(key)
        if not isinstance(value, list) or not all(isinstance(n, str) for n in value):
            problems.append(f"{key} is {_short(value)}, not a list of names")
        names[key] = value
    for key in ("stats", "meta"):
        if not isinstance(side.get(key), dict):
            problems.append(f"{key} is {_short(side.get(key))}, not an object")
    if problems:
        raise ResultIntegrityError(f"{json_path}: not the sidecar of a saved result ({'; '.join(problems)})")
    return m, r, names["energies"], names["forces"], side["stats"], side["meta"]


def _short(value: Any, limit: int = 60) -> str:
    text = "missing" if value is None else repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _jsonable(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value
