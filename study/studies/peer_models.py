"""A peer's test models through descriptions: Exudyn's slider-crank test (``sliderCrankFloatingTest``).

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
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import pandas as pd

from study.mechanisms import mechanism
from study.params import load_parameters
from study.pipeline import Case, find_one
from study.reference_data import tolerance
from study.reference_solutions import richardson_second_order
from study.results import SimulationResult

MECHANISMS = ("exudyn_slider_crank", "exudyn_slider_crank_floating")
PUBLISHED = "exudyn_slider_crank_published"
COLUMNS = ["source", "x_slider_fixed_m", "x_slider_floating_m", "sum_abs_x_slider_m", "minus_published_m"]


def x_slider(case: Case, result: SimulationResult) -> float:
    """x of the slider point B at the horizon, through the description's kinematics."""
    if not np.isclose(result.t[-1], case.t_end, rtol=0, atol=1e-12):
        raise ValueError(f"{case.name}: the run ends at t = {result.t[-1]!r}, not at {case.t_end!r}")
    eom = mechanism(load_parameters(case.mechanism, case.variant)).equations()
    return float(np.asarray(eom.points["slider.B"](result.q[-1]), dtype=float).ravel()[0])


def summarize(cases: Sequence[Case], load: Callable[[Case], SimulationResult]) -> dict[str, pd.DataFrame]:
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
    error = abs(sums["extrapolated"] - sums["coarse"])   # the published-step run's error, by Richardson's rule
    factor = tolerance("exudyn_slider_crank_agreement_factor", table="benchmarks")
    verdict = {"published_m": published, "inhouse_minus_published_m": sums["inhouse"] - published,
               "exudyn_published_step_minus_published_m": sums["coarse"] - published,
               "published_run_error_estimate_m": error, "bound_m": factor * error,
               "agrees": abs(sums["inhouse"] - published) <= factor * error,
               "extrapolated_minus_inhouse_m": sums["extrapolated"] - sums["inhouse"]}
    return {"exudyn_test_models": pd.DataFrame(rows, columns=COLUMNS),
            "exudyn_test_models_verdict": pd.DataFrame([verdict]),
            "exudyn_test_models_timing": pd.DataFrame({"source": list(cpu), "cpu_s": list(cpu.values())})}
