"""Spatial mechanisms in-house and in Exudyn (``reference/cases/spatial.toml``): each run's error by its benchmark's
criterion, its energy, and its CPU, for "CPU against Exudyn at equal accuracy".

:func:`summarize` writes
- ``spatial_runs``: per run, its mechanism, engine, setting and horizon; the error by the criterion ``criterion``:
  for the heavy top max|p(0.2 s) - p_independent| over the four Euler parameters against the independent minimal model
  (reference/spatial/heavy_top.toml [independent]), with the distance to the published values and whether each
  rounds to its printed digits; for Bricard and the slider-crank max|r - r_ref| over the bodies' centres and the
  common samples against the mechanism's ':reference' group (the finest in-house run); the energy drift
  max|E - E(0)| over the samples and, in-house, its bound ``energy_drift_factor * rtol * max K`` (the global-error
  rule applied to the energy) with the drift's share of it; an Exudyn run over the benchmark's horizon (group
  ``<mechanism>:exudyn_benchmark``) is held to the bound of the in-house benchmark run (``<mechanism>:benchmark``):
  the same rule with that run's rtol and its own max K; max|Phi| and the function evaluations or steps;
- ``spatial_timing``: the CPU seconds of every run;
- ``spatial_equal_accuracy_timing``: per Exudyn run, the cheapest in-house run at least as accurate, both CPUs and
  their ratio (none when no in-house run is as accurate);
- the tables of the joint-friction cases (groups ``<mechanism>:friction_*``: :mod:`study.studies.spatial_friction`),
  whose runs are in ``spatial_timing`` only.
"""

from __future__ import annotations

import functools
import math
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.pipeline import Case
from study.reference_data import tolerance, values
from study.results import SimulationResult
from study.studies import spatial_friction
from study.studies.spatial_cases import BENCHMARK_ROLES, role, setting

HEAVY_TOP = "spatial/heavy_top"
REFERENCE_ROLE = "reference"


def rounds_to_published(p: np.ndarray) -> bool:
    """Whether every Euler parameter rounds to its published value (half a unit of the last printed digit)."""
    digits = int(tolerance("published_significant_digits", HEAVY_TOP))
    return all(abs(ours - printed) <= 0.5 * 10.0 ** (math.floor(math.log10(abs(printed))) - digits + 1)
               for printed, ours in zip(values("published", HEAVY_TOP), p))


def centres(result: SimulationResult) -> np.ndarray:
    """(samples, bodies x 3): the bodies' centres (the coordinates <body>_x, _y, _z)."""
    names = result.meta["coordinate_names"]
    return result.q[:, [i for i, n in enumerate(names) if n[-2:] in ("_x", "_y", "_z")]]


def accuracy(case: Case, r: SimulationResult, reference: SimulationResult | None) -> dict:
    """The error of a run by its mechanism's criterion (module docstring)."""
    if case.mechanism == "heavy_top":
        p = r.q[-1, 3:7]
        return {"criterion": "max|p(t_end) - p_independent|",
                "error": float(np.abs(p - np.array(values("independent", HEAVY_TOP))).max()),
                "published_distance": float(np.abs(p - np.array(values("published", HEAVY_TOP))).max()),
                "rounds_to_published": rounds_to_published(p)}
    if reference is None or role(case) in (REFERENCE_ROLE, *BENCHMARK_ROLES):
        return {"criterion": "energy" if role(case) in BENCHMARK_ROLES else "reference", "error": np.nan}
    if r.t.shape != reference.t.shape or np.abs(r.t - reference.t).max() > tolerance("round_off") * r.t[-1]:
        raise ValueError(f"{case.name}: its samples are not those of its reference run ({len(r.t)} against "
                         f"{len(reference.t)})")
    return {"criterion": "max|r - r_ref| centres [m]", "error": float(np.abs(centres(r) - centres(reference)).max())}


def benchmark_rtols(cases: Sequence[Case]) -> dict[str, float]:
    """Per mechanism, the rtol of its in-house benchmark run: the bound's rtol of its Exudyn benchmark run."""
    return {c.mechanism: c.kwargs["rtol"] for c in cases if c.engine == "inhouse" and role(c) == BENCHMARK_ROLES[0]}


def energy(case: Case, r: SimulationResult, rtols: dict[str, float]) -> dict:
    """The energy drift, and in-house (or for an Exudyn benchmark run, by the in-house benchmark run's rtol) its
    bound by the global-error rule and the drift's share of it."""
    total = r.energies["kinetic"] + r.energies["potential"]
    drift = float(np.abs(total - total[0]).max())
    if case.engine == "exudyn" and role(case) not in BENCHMARK_ROLES:
        return {"energy_drift_J": drift, "energy_bound_J": np.nan, "drift_over_bound": np.nan}
    if case.engine == "exudyn" and case.mechanism not in rtols:
        raise ValueError(f"{case.name}: an Exudyn benchmark run is held to the bound of its mechanism's in-house "
                         f"benchmark run, and the cases have no group '{case.mechanism}:{BENCHMARK_ROLES[0]}'")
    rtol = rtols[case.mechanism] if case.engine == "exudyn" else case.kwargs["rtol"]
    bound = tolerance("energy_drift_factor") * rtol * float(np.abs(r.energies["kinetic"]).max())
    return {"energy_drift_J": drift, "energy_bound_J": bound, "drift_over_bound": drift / bound}


def equal_accuracy(runs: pd.DataFrame) -> pd.DataFrame:
    """Per Exudyn run, the cheapest in-house run of the same mechanism with an error at most Exudyn's."""
    rows = []
    judged = runs[runs["error"].notna()]
    for _, ex in judged[judged["engine"] == "exudyn"].iterrows():
        own = judged[(judged["engine"] == "inhouse") & (judged["mechanism"] == ex["mechanism"])]
        better = own[own["error"] <= ex["error"]].sort_values("cpu_s")
        row = {"mechanism": ex["mechanism"], "exudyn": ex["setting"], "exudyn_error": ex["error"],
               "exudyn_cpu_s": ex["cpu_s"], "inhouse": "none as accurate", "inhouse_error": np.nan,
               "inhouse_cpu_s": np.nan, "exudyn_over_inhouse_cpu": np.nan}
        if len(better):
            best = better.iloc[0]
            row.update(inhouse=best["setting"], inhouse_error=best["error"], inhouse_cpu_s=best["cpu_s"],
                       exudyn_over_inhouse_cpu=ex["cpu_s"] / best["cpu_s"])
        rows.append(row)
    return pd.DataFrame(rows)


def summarize(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    """The tables of the module docstring."""
    load = functools.cache(load)   # the references and the friction tables read runs the loop reads too
    references = {c.mechanism: load(c) for c in cases if role(c) == REFERENCE_ROLE}
    rtols = benchmark_rtols(cases)
    rows, timing = [], []
    for case in cases:
        r = load(case)
        key = {"mechanism": case.mechanism, "engine": case.engine, "group": role(case), "setting": setting(case)}
        timing.append({**key, "cpu_s": float(r.stats["cpu_seconds"])})
        if spatial_friction.is_friction(case):
            continue
        rows.append({**key, "t_end_s": case.t_end, **accuracy(case, r, references.get(case.mechanism)),
                     **energy(case, r, rtols), "max_abs_phi": float(np.abs(r.phi).max()),
                     "evaluations": r.stats.get("nfev", r.stats.get("steps"))})
    runs = pd.DataFrame(rows)
    cpu = pd.DataFrame(timing)
    return {"spatial_runs": runs, "spatial_timing": cpu,
            "spatial_equal_accuracy_timing": equal_accuracy(runs.merge(cpu, on=list(cpu.columns[:-1]))),
            **spatial_friction.summarize(cases, load)}
