"""Friction between moving parts: sliding contacts whose guide is itself a moving body, and revolute joints with
friction (pins).

Case list ``reference/cases/moving_friction.toml``. Its groups are named ``<set>:<role>`` (one set per mechanism
and variant) with role

* ``exact``: the exact law (event-located stick/slip), swept over both backends;
* ``regularized``: the in-house regularized law (tanh, eps), the reference of the Exudyn runs;
* ``exudyn``: Exudyn's regularized law with the same eps at h, h/2, h/4;
* ``eps``: the in-house regularized law at a sequence of eps, each against the exact run.

A set may lack roles (a mechanism the exact law or Exudyn cannot run); every table holds the rows its runs allow.
Every run of a set shares the horizon and output step, so comparisons use common samples.

:func:`summarize` returns the tables

``moving_friction_runs``
    one row per run: dissipated energy and energy-balance residual with its bound and verdicts
    (:func:`study.pipeline.summaries.energy_check`, the pipeline's own check), constraint residual, cost;
``moving_friction_backends``
    the exact run on the compiled path against the reference path: max|dq| and its bound
    (:func:`study.pipeline.summaries.sample_agreement`), and the largest difference of their transition times against
    ``event_time_agreement_adaptive``;
``moving_friction_phases``
    the exact run's stick and slip intervals per contact and pin, with what started each (the initial state, a
    contact coming to rest and being held or not, a stuck contact reaching its static limit) and the ratio
    |f_req| / limit at that transition;
``moving_friction_forces``
    friction force and normal force of each contact (a pin: friction torque and |R|) against time (exact and regularized), the stick flag, the dissipated
    energy and the energy-balance residual of the exact run;
``moving_friction_exudyn``
    Exudyn against the in-house regularized run: max|dq|, max|dqd|, max|dF|, max|dN|, the dissipated energy's
    difference, and the observed order between successive h;
``moving_friction_eps``
    each regularized run against the exact one and the observed order in eps between successive eps;
``moving_friction_timing``
    the CPU seconds of every run.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study import mechanisms
from study.compare import common_samples, observed_orders
from study.params import load_parameters
from study.pipeline import Case
from study.pipeline.summaries import dissipation, energy_check, sample_agreement
from study.reference_data import tolerance
from study.results import SimulationResult
from study.studies.cross_validation import deviations, normal_force, tangential_force

ROLES = ("exact", "regularized", "exudyn", "eps")
Load = Callable[[Case], SimulationResult]
DIFFERENCES = ("max_abs_dq", "max_abs_dqd", "max_abs_dF_friction", "max_abs_dN", "abs_ddissipated_J")
LABEL_COLUMNS = ["engine", "backend", "solver", "h", "friction_eps"]
RUN_COLUMNS = ["set", "role", *LABEL_COLUMNS, "friction", "t_end", "dissipated_J", "residual_J", "residual_bound_J",
               "residual_within_bound", "dissipation_nondecreasing", "max_abs_phi", "transitions", "steps", "nfev"]
BACKEND_COLUMNS = ["set", "t_end", "max_abs_dq", "bound", "rule", "agree", "transitions", "max_abs_dt_transitions",
                   "transition_time_bound", "transitions_agree"]
FORCE_COLUMNS = ["set", "contact", "kind", "t", "friction", "normal", "stick", "friction_regularized",
                 "normal_regularized", "dissipated_J", "residual_J"]


def parse_group(group: str) -> tuple[str, str]:
    """'quick_return/slot_friction:exact' -> ('quick_return/slot_friction', 'exact')."""
    key, sep, role = group.rpartition(":")
    if not sep or role not in ROLES:
        raise ValueError(f"group {group!r} is not '<set>:<role>' with role in {ROLES}")
    return key, role


def sets(cases: Sequence[Case]) -> dict[str, dict[str, list[Case]]]:
    """{set: {role: cases}} in case-list order."""
    out: dict[str, dict[str, list[Case]]] = {}
    for case in cases:
        key, role = parse_group(case.group)
        out.setdefault(key, {r: [] for r in ROLES})[role].append(case)
    return out


@lru_cache(maxsize=None)
def contacts(mechanism: str, variant: str) -> tuple[tuple[str, str], ...]:
    """(name, kind) of every joint with friction of a study mechanism: 'slider' (force [N]) or 'pin' (torque [N m])."""
    d = mechanisms.description(load_parameters(mechanism, variant))
    return tuple((j.name, "slider") for j in d.contacts()) + tuple((j.name, "pin") for j in d.pins())


def exact_case(roles: dict[str, list[Case]]) -> Case | None:
    """The set's exact run the others are compared with: the compiled one, else the first."""
    exact = roles["exact"]
    compiled = [c for c in exact if c.kwargs.get("backend") == "compiled"]
    return (compiled or exact or [None])[0]


def transitions(result: SimulationResult) -> list[dict]:
    """The exact run's located transitions (contact, time, from, to, f_required, normal, limit)."""
    return [x for x in result.stats.get("friction_transitions", []) if x.get("contact")]


def phases(result: SimulationResult, contact: str) -> list[dict]:
    """The exact run's intervals of one contact: phase, t_start, t_end, what started it and |f_req| / limit there."""
    initial = result.stats["friction_transitions"][0]["initial"][contact]
    out = [{"phase": initial, "t_start": float(result.t[0]), "started_by": "initial state",
            "f_required_over_limit": np.nan}]
    for x in transitions(result):
        if x["contact"] != contact:
            continue
        ratio = abs(x["f_required"]) / x["limit"] if x["limit"] > 0 else math.inf
        if x["from"] == "stick":
            why = "static limit reached"
        elif x["to"] == "stick":
            why = "came to rest, held"
        else:
            why = "came to rest, not holdable"
        out.append({"phase": x["to"], "t_start": float(x["t"]), "started_by": why, "f_required_over_limit": ratio})
    for now, after in zip(out, out[1:] + [None]):
        now["t_end"] = float(result.t[-1]) if after is None else after["t_start"]
    return out


def _label(case: Case) -> dict:
    o = case.kwargs
    if case.engine == "exudyn":
        return {"engine": "exudyn", "backend": "", "solver": o.get("solver", "index3"), "h": float(o["h"]),
                "friction_eps": float(o["eps"])}
    return {"engine": "inhouse", "backend": o.get("backend", "reference"), "solver": o.get("integrator", "RK45"),
            "h": float(o.get("step", np.nan)), "friction_eps": float(o.get("friction_eps", np.nan))}


def runs_table(groups: dict, load: Load) -> pd.DataFrame:
    rows = []
    for key, roles in groups.items():
        for role in ROLES:
            for case in roles[role]:
                r = load(case)
                check = energy_check(r, case.kwargs)
                rows.append({"set": key, "role": role, **_label(case), "friction": check["friction"],
                             "t_end": case.t_end, "dissipated_J": check["dissipated_J"],
                             "residual_J": check["residual_J"], "residual_bound_J": check["residual_bound_J"],
                             "residual_within_bound": check["residual_within_bound"],
                             "dissipation_nondecreasing": check["dissipation_nondecreasing"],
                             "max_abs_phi": float(np.abs(r.phi).max()) if r.phi.size else 0.0,
                             "transitions": len(transitions(r)) if check["friction"] == "exact" else np.nan,
                             "steps": int(r.stats.get("steps", 0)), "nfev": int(r.stats.get("nfev", 0))})
    return pd.DataFrame(rows, columns=RUN_COLUMNS)


def backends_table(groups: dict, load: Load) -> pd.DataFrame:
    rows = []
    for key, roles in groups.items():
        by = {c.kwargs.get("backend"): c for c in roles["exact"]}
        if "compiled" not in by or "reference" not in by:
            continue
        compiled, reference = load(by["compiled"]), load(by["reference"])
        agree = sample_agreement(compiled, reference, by["compiled"].kwargs)
        a, b = transitions(compiled), transitions(reference)
        same = [(x["contact"], x["from"], x["to"]) for x in a] == [(x["contact"], x["from"], x["to"]) for x in b]
        dt = max((abs(x["t"] - y["t"]) for x, y in zip(a, b)), default=0.0) if same else np.nan
        bound = tolerance("event_time_agreement_adaptive")
        rows.append({"set": key, "t_end": by["compiled"].t_end, "max_abs_dq": agree["max_abs_dq"],
                     "bound": agree["bound"], "rule": agree["rule"], "agree": agree["agree"], "transitions": len(a),
                     "max_abs_dt_transitions": dt, "transition_time_bound": bound,
                     "transitions_agree": bool(same and dt <= bound)})
    return pd.DataFrame(rows, columns=BACKEND_COLUMNS)


def phases_table(groups: dict, load: Load) -> pd.DataFrame:
    rows = []
    for key, roles in groups.items():
        case = exact_case(roles)
        if case is None:
            continue
        r = load(case)
        for name, kind in contacts(case.mechanism, case.variant):
            for p in phases(r, name):
                rows.append({"set": key, "contact": name, "kind": kind, "backend": case.kwargs.get("backend"), **p})
    cols = ["set", "contact", "kind", "backend", "phase", "t_start", "t_end", "started_by", "f_required_over_limit"]
    return pd.DataFrame(rows, columns=cols)


def forces_table(groups: dict, load: Load) -> pd.DataFrame:
    frames = []
    for key, roles in groups.items():
        case = exact_case(roles)
        if case is None:
            continue
        r = load(case)
        reg = load(roles["regularized"][0]) if roles["regularized"] else None
        ia, ib = common_samples(r, reg) if reg is not None else (np.arange(len(r.t)), None)
        balance = r.energy_balance()
        for name, kind in contacts(case.mechanism, case.variant):
            frame = pd.DataFrame({"set": key, "contact": name, "kind": kind, "t": r.t[ia],
                                  "friction": r.forces[f"friction_{name}"][ia],
                                  "normal": r.forces[f"normal_{name}"][ia], "stick": r.forces[f"stick_{name}"][ia]})
            if reg is not None:
                frame["friction_regularized"] = reg.forces[f"friction_{name}"][ib]
                frame["normal_regularized"] = reg.forces[f"normal_{name}"][ib]
            frame["dissipated_J"] = dissipation(r)[ia]
            frame["residual_J"] = (balance - balance[0])[ia]
            frames.append(frame)
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=FORCE_COLUMNS)


def _compare(run: SimulationResult, ref: SimulationResult) -> dict:
    """max|dq|, max|dqd|, and max|dF|, max|dN| over every friction entry (a pin's torque [N m] and |R| [N])."""
    d = deviations(run, ref)
    ia, ib = common_samples(run, ref)
    names = [name for name, _ in contacts(ref.meta["mechanism"], ref.meta["variant"])]
    for key, force in (("max_abs_dF_friction", tangential_force), ("max_abs_dN", normal_force)):
        d[key] = max(float(np.abs(force(run, n)[ia] - force(ref, n)[ib]).max()) for n in names)
    return {**{k: d[k] for k in DIFFERENCES[:4]},
            "abs_ddissipated_J": float(abs(dissipation(run)[ia][-1] - dissipation(ref)[ib][-1]))}


def _orders(frame: pd.DataFrame, by: str) -> pd.DataFrame:
    """order_<d>: the observed order between each row's ``by`` and the previous (larger) one of its set."""
    for d in DIFFERENCES:
        frame[f"order_{d.removeprefix('max_abs_').removeprefix('abs_')}"] = np.nan
    for _, idx in frame.groupby("set", sort=False).groups.items():
        sub = frame.loc[idx]
        for d in DIFFERENCES:
            e, x = sub[d].to_numpy(float), sub[by].to_numpy(float)
            for k in range(1, len(sub)):
                if e[k - 1] > 0 and e[k] > 0:
                    frame.loc[sub.index[k], f"order_{d.removeprefix('max_abs_').removeprefix('abs_')}"] = \
                        float(observed_orders(x[k - 1:k + 1], e[k - 1:k + 1])[0])
    return frame


def exudyn_table(groups: dict, load: Load) -> pd.DataFrame:
    rows = []
    for key, roles in groups.items():
        if not roles["regularized"] or not roles["exudyn"]:
            continue
        ref = load(roles["regularized"][0])
        for case in sorted(roles["exudyn"], key=lambda c: (c.kwargs.get("solver", "index3"), -c.kwargs["h"])):
            o = case.kwargs
            rows.append({"set": key, "solver": o.get("solver", "index3"), "h": float(o["h"]),
                         "friction_eps": float(o["eps"]), **_compare(load(case), ref)})
    return _orders(pd.DataFrame(rows, columns=["set", "solver", "h", "friction_eps", *DIFFERENCES]), "h")


def eps_table(groups: dict, load: Load) -> pd.DataFrame:
    rows = []
    for key, roles in groups.items():
        case = exact_case(roles)
        if case is None or not roles["eps"]:
            continue
        exact = load(case)
        for run in sorted(roles["eps"], key=lambda c: -c.kwargs["friction_eps"]):
            rows.append({"set": key, "friction_eps": float(run.kwargs["friction_eps"]), **_compare(load(run), exact)})
    frame = _orders(pd.DataFrame(rows, columns=["set", "friction_eps", *DIFFERENCES]), "friction_eps")
    frame["shrinking"] = [bool(i == 0 or frame.loc[i, "set"] != frame.loc[i - 1, "set"]
                               or frame.loc[i, "max_abs_dq"] < frame.loc[i - 1, "max_abs_dq"]) for i in frame.index]
    return frame


def timing_table(groups: dict, load: Load) -> pd.DataFrame:
    rows = []
    for key, roles in groups.items():
        for role in ROLES:
            for case in roles[role]:
                r = load(case)
                cpu = r.stats.get("process_cpu_seconds", r.stats.get("cpu_seconds", np.nan))
                rows.append({"set": key, "role": role, **_label(case), "cpu_seconds": float(cpu)})
    return pd.DataFrame(rows, columns=["set", "role", *LABEL_COLUMNS, "cpu_seconds"])


def summarize(cases: Sequence[Case], load: Load) -> dict[str, pd.DataFrame]:
    """The study's tables (see the module docstring); pure: it only reads saved results through ``load``."""
    groups = sets(cases)
    return {"moving_friction_runs": runs_table(groups, load), "moving_friction_backends": backends_table(groups, load),
            "moving_friction_phases": phases_table(groups, load), "moving_friction_forces": forces_table(groups, load),
            "moving_friction_exudyn": exudyn_table(groups, load), "moving_friction_eps": eps_table(groups, load),
            "moving_friction_timing": timing_table(groups, load)}
