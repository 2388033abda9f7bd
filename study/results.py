"""The one result type for every run (in-house solver and Exudyn), with lossless save/load.

A result holds sampled time series (time, q, qd, qdd, lambda, Phi, Phidot, energies, forces of
interest), solver statistics and metadata. It is saved as a CSV of the series (17 significant
digits, so the round trip is exact) plus a JSON sidecar with statistics and metadata.
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
from study.integrity import atomic_write, data_rows, read_json, sha256_text, verify_text

Array = np.ndarray

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
        """Write ``<path>.csv`` and ``<path>.json`` atomically; returns the CSV path."""
        base = _base(path)
        base.parent.mkdir(parents=True, exist_ok=True)
        self.check_finite()
        csv_text = self.to_dataframe().to_csv(index=False, float_format="%.17g", lineterminator="\n")
        sidecar = {
            "shape": {"m": self.q.shape[1], "r": self.lam.shape[1]},
            "energies": list(self.energies),
            "forces": list(self.forces),
            "stats": self.stats,
            "meta": self.meta,
            "csv": {"rows": data_rows(csv_text), "sha256": sha256_text(csv_text)},
        }
        atomic_write(_with(base, ".csv"), csv_text)
        atomic_write(_with(base, ".json"), json.dumps(_jsonable(sidecar), indent=1, sort_keys=True))
        return _with(base, ".csv")

    @classmethod
    def verify(cls, path: str | Path) -> dict:
        """Check a saved result before reuse; returns its sidecar. ResultIntegrityError names what is wrong.

        The JSON must parse and record the CSV's row count and SHA-256; the CSV must match both
        (a truncated, cut or edited CSV fails).
        """
        base = _base(path)
        json_path, csv_path = _with(base, ".json"), _with(base, ".csv")
        side = read_json(json_path)
        if not csv_path.exists():
            raise ResultIntegrityError(f"{csv_path}: missing (its JSON {json_path.name} exists)")
        record = side.get("csv") if isinstance(side.get("csv"), dict) else {}
        verify_text(csv_path, csv_path.read_text(), record.get("rows"), record.get("sha256"))
        return side

    @classmethod
    def load(cls, path: str | Path, verify: bool = True) -> "SimulationResult":
        """Read a saved result; with ``verify`` (default) it is checked first (:meth:`verify`)."""
        base = _base(path)
        side = cls.verify(base) if verify else json.loads(_with(base, ".json").read_text())
        df = pd.read_csv(_with(base, ".csv"))
        m, r = side["shape"]["m"], side["shape"]["r"]
        data = df.to_numpy()
        t = data[:, 0]
        q, qd, qdd = data[:, 1:1 + m], data[:, 1 + m:1 + 2 * m], data[:, 1 + 2 * m:1 + 3 * m]
        k = 1 + 3 * m
        lam, phi, phidot = data[:, k:k + r], data[:, k + r:k + 2 * r], data[:, k + 2 * r:k + 3 * r]
        energies = {n: df[f"energy:{n}"].to_numpy() for n in side["energies"]}
        forces = {n: df[f"force:{n}"].to_numpy() for n in side["forces"]}
        return cls(t, q, qd, qdd, lam, phi, phidot, energies, forces, side["stats"], side["meta"])


def _base(path: str | Path) -> Path:
    """The path without a trailing .csv/.json; any other dots are part of the name ('h0.001')."""
    path = Path(path)
    return path.with_name(path.name[:-len(path.suffix)]) if path.suffix in (".csv", ".json") else path


def _with(base: Path, suffix: str) -> Path:
    return base.with_name(base.name + suffix)


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
