"""A peer's test models through descriptions: Exudyn's slider-crank test (``sliderCrankFloatingTest``) and its
Bricard test (``bricardMechanism.py``).

The case list ``reference/cases/peer_models.toml`` runs the fixed-frame and the floating-frame mechanism to 0.3 s:
the in-house reference, and Exudyn from the same descriptions (index 2, the published run's step h and h/2). The
model file publishes one number, |x_slider(0.3 s)| of the fixed case plus that of the floating case
(``reference/benchmarks.toml``). :func:`summarize` writes ``exudyn_test_models``: one row per source (the published
value, the in-house reference, Exudyn at h and at h/2, Richardson's extrapolation of the two), with each case's
x_slider(0.3 s), their sum, and the sum's difference from the published value; ``exudyn_test_models_verdict``: the
published run's discretization error estimated by Richardson's rule from the Exudyn runs at h and h/2, and whether
the in-house reference lies within ``exudyn_slider_crank_agreement_factor`` of those errors of the published value;
``exudyn_test_models_timing``: the CPU seconds of each source that is a pair of runs (fixed plus floating frame;
machine-dependent, so in timing/).

The Bricard groups run the mechanism ``exudyn_bricard`` (:mod:`study.spatial.bricard_peer`) over the file's 1 s: the
in-house reference (the augmented Lagrangian, the one acceleration solver for its redundant row), and Exudyn from
the description at the published run's solver (generalized-alpha, index 3) and step h, and at h/2. The file publishes
|q(1 s)| + dof + redundant constraints + the lowest eigenvalue, q Exudyn's ODE2 coordinates
(``reference/benchmarks.toml`` [exudyn_bricard_published]): per rod, the displacement of its reference point (its
first joint) and the change of its Euler parameters since t = 0 (:func:`ode2_coordinates`). The counts and the
eigenvalue are the description's (:func:`counts`, for every source but the published one, whose counts are those
Exudyn's test-suite log prints). :func:`summarize` writes ``exudyn_bricard_test_model`` (one row per source, as
``exudyn_test_models``; Richardson's extrapolation is of the coordinates), ``exudyn_bricard_test_model_verdict`` (the
same rule, with ``exudyn_bricard_agreement_factor``) and ``exudyn_bricard_test_model_timing``.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd
from scipy.linalg import eigh

from study.mechanisms import mechanism, named_mechanism
from study.params import load_parameters
from study.pipeline import Case, find_one
from study.reference_data import tolerance, values
from study.reference_solutions import richardson_second_order
from study.results import SimulationResult
from study.solver.checks import numeric_jacobian
from study.spatial.bricard_peer import NODE_POINT

MECHANISMS = ("exudyn_slider_crank", "exudyn_slider_crank_floating")
PUBLISHED = "exudyn_slider_crank_published"
COLUMNS = ["source", "x_slider_fixed_m", "x_slider_floating_m", "sum_abs_x_slider_m", "minus_published_m"]
BRICARD = "exudyn_bricard"
BRICARD_PUBLISHED = "exudyn_bricard_published"
BRICARD_COLUMNS = ["source", "ode2_norm", "dof", "redundant_constraints", "lowest_eigenvalue", "test_value",
                   "minus_published"]


def _at_horizon(case: Case, result: SimulationResult) -> None:
    if not np.isclose(result.t[-1], case.t_end, rtol=0, atol=1e-12):
        raise ValueError(f"{case.name}: the run ends at t = {result.t[-1]!r}, not at {case.t_end!r}")


def agreement(published: float, inhouse: float, coarse: float, extrapolated: float, factor: float,
              unit: str = "") -> dict:
    """The verdict on a published value: the published run's discretization error estimated by Richardson's rule
    (|extrapolated - coarse|, the Exudyn run at the published step against the extrapolation of it and the run at
    half the step), and whether the in-house reference lies within ``factor`` such errors of the published value;
    ``unit`` suffixes the keys of the quantities."""
    error = abs(extrapolated - coarse)
    return {f"published{unit}": published, f"inhouse_minus_published{unit}": inhouse - published,
            f"exudyn_published_step_minus_published{unit}": coarse - published,
            f"published_run_error_estimate{unit}": error, f"bound{unit}": factor * error,
            "agrees": abs(inhouse - published) <= factor * error,
            f"extrapolated_minus_inhouse{unit}": extrapolated - inhouse}


def x_slider(case: Case, result: SimulationResult) -> float:
    """x of the slider point B at the horizon, through the description's kinematics."""
    _at_horizon(case, result)
    eom = mechanism(load_parameters(case.mechanism, case.variant)).equations()
    return float(np.asarray(eom.points["slider.B"](result.q[-1]), dtype=float).ravel()[0])


def slider_crank(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    """The slider-crank test model's tables (module docstring)."""
    published = tolerance(PUBLISHED, table="benchmarks")
    h = tolerance("exudyn_slider_crank_published_step", table="benchmarks")

    def total(xs: list[float]) -> float:
        return float(sum(abs(x) for x in xs))

    def row(source: str, xs: list[float]) -> dict:
        return dict(zip(COLUMNS, [source, *xs, total(xs), total(xs) - published]))

    cpu = {}

    def xs(source: str, **criteria) -> list[float]:
        pair = [find_one(cases, mechanism=m, **criteria) for m in MECHANISMS]
        results = [load(c) for c in pair]
        cpu[source] = float(sum(r.stats.get("cpu_seconds", np.nan) for r in results))
        return [x_slider(c, r) for c, r in zip(pair, results)]

    reference = find_one(cases, group="inhouse", mechanism=MECHANISMS[0]).kwargs
    sources = {"published": f"published (the test model: Exudyn index 2, h = {h:g} s)",
               "inhouse": f"in-house reference ({reference['integrator']}, rtol {reference['rtol']:g}, "
                          f"{reference['method']})",
               "coarse": f"Exudyn from the descriptions, index 2, h = {h:g} s",
               "fine": f"Exudyn from the descriptions, index 2, h = {h / 2:g} s"}
    inhouse, coarse, fine = (xs(sources["inhouse"], group="inhouse"), xs(sources["coarse"], group="exudyn", h=h),
                             xs(sources["fine"], group="exudyn", h=h / 2))
    extrapolated = list(richardson_second_order(coarse, fine)[0])
    rows = [{"source": sources["published"], "x_slider_fixed_m": np.nan, "x_slider_floating_m": np.nan,
             "sum_abs_x_slider_m": published, "minus_published_m": 0.0},
            row(sources["inhouse"], inhouse), row(sources["coarse"], coarse), row(sources["fine"], fine),
            row("Richardson extrapolation of the two Exudyn runs", extrapolated)]
    sums = {"inhouse": total(inhouse), "coarse": total(coarse), "extrapolated": total(extrapolated)}
    factor = tolerance("exudyn_slider_crank_agreement_factor", table="benchmarks")
    verdict = agreement(published, sums["inhouse"], sums["coarse"], sums["extrapolated"], factor, "_m")
    return {"exudyn_test_models": pd.DataFrame(rows, columns=COLUMNS),
            "exudyn_test_models_verdict": pd.DataFrame([verdict]),
            "exudyn_test_models_timing": pd.DataFrame({"source": list(cpu), "cpu_s": list(cpu.values())})}


def ode2_coordinates(case: Case, result: SimulationResult) -> np.ndarray:
    """Exudyn's ODE2 coordinates of the Bricard test model at the horizon: per rod, its point NODE_POINT (Exudyn's
    node) minus where it starts, and its Euler parameters minus theirs at t = 0 (35 values)."""
    _at_horizon(case, result)
    mech = named_mechanism(case.mechanism)
    eom, q0, q = mech.equations(), mech.initial_state().q, result.q[-1]
    parts = []
    for i, body in enumerate(mech.description.bodies):
        point = eom.points[f"{body}.{NODE_POINT}"]
        parts += [np.ravel(point(q)) - np.ravel(point(q0)), q[7 * i + 3:7 * i + 7] - q0[7 * i + 3:7 * i + 7]]
    return np.concatenate(parts).astype(float)


def counts(name: str) -> tuple[int, int, float]:
    """(degrees of freedom, redundant rows, lowest |eigenvalue|) of a mechanism at its start, as Exudyn's
    ComputeSystemDegreeOfFreedom and ComputeODE2Eigenvalues count them: n - rank(Phi_q) and r - rank(Phi_q), the rank
    to singular_ratio of the largest singular value; the eigenvalues of the stiffness -dQ/dq (central differences)
    against the mass matrix, both on the null space of Phi_q."""
    mech = named_mechanism(name)
    eom, state = mech.equations(), mech.initial_state()
    _, s, vt = np.linalg.svd(eom.phi_q(state.q))
    rank = int(np.sum(s > tolerance("singular_ratio") * s[0]))
    null = vt[rank:].T
    stiffness = -numeric_jacobian(lambda x: eom.forces(0.0, x, state.qd), state.q)
    eigenvalues = eigh(null.T @ stiffness @ null, null.T @ eom.mass(state.q) @ null, eigvals_only=True)
    return eom.n_coordinates - rank, eom.n_constraints - rank, float(np.min(np.abs(eigenvalues)))


def bricard(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    """The Bricard test model's tables (module docstring)."""
    published = tolerance(BRICARD_PUBLISHED, table="benchmarks")
    h = tolerance(f"{BRICARD_PUBLISHED}_step", table="benchmarks")
    runs = {"inhouse": find_one(cases, group="bricard:inhouse"), "coarse": find_one(cases, group="bricard:exudyn", h=h),
            "fine": find_one(cases, group="bricard:exudyn", h=h / 2)}
    results = {k: load(c) for k, c in runs.items()}
    q = {k: ode2_coordinates(runs[k], r) for k, r in results.items()}
    q["extrapolated"] = richardson_second_order(q["coarse"], q["fine"])[0]
    ours = counts(BRICARD)
    o = runs["inhouse"].kwargs
    sources = {"inhouse": f"in-house reference ({o['integrator']}, rtol {o['rtol']:g}, {o['acceleration_solver']})",
               "coarse": f"Exudyn from the description, index 3, h = {h:g} s",
               "fine": f"Exudyn from the description, index 3, h = {h / 2:g} s",
               "extrapolated": "Richardson extrapolation of the two Exudyn runs"}

    def row(source: str, norm: float, counted) -> dict:
        value = norm + sum(counted)
        return dict(zip(BRICARD_COLUMNS, [source, norm, *counted, value, value - published]))

    logged = values(f"{BRICARD_PUBLISHED}_counts", table="benchmarks")
    rows = [row(f"published (the test model: Exudyn index 3, h = {h:g} s)", published - sum(logged), logged)]
    rows += [row(sources[k], float(np.linalg.norm(v)), ours) for k, v in q.items()]
    value = {k: float(np.linalg.norm(v)) + sum(ours) for k, v in q.items()}
    factor = tolerance("exudyn_bricard_agreement_factor", table="benchmarks")
    verdict = agreement(published, value["inhouse"], value["coarse"], value["extrapolated"], factor)
    cpu = {sources[k]: float(r.stats.get("cpu_seconds", np.nan)) for k, r in results.items()}
    return {"exudyn_bricard_test_model": pd.DataFrame(rows, columns=BRICARD_COLUMNS),
            "exudyn_bricard_test_model_verdict": pd.DataFrame([verdict]),
            "exudyn_bricard_test_model_timing": pd.DataFrame({"source": list(cpu), "cpu_s": list(cpu.values())})}


def summarize(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
    """Every test model's tables (module docstring)."""
    return {**slider_crank(cases, load), **bricard(cases, load)}
