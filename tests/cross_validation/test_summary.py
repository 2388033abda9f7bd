"""The cross-validation study's summary on a tiny case set, and its case list against the tolerances."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from study.params import available_variants
from study.pipeline import CASES_DIR, Case, find, load_case_list, run_case
from study.reference_data import tolerance
from study.studies import cross_validation as xv

REF = (("atol", tolerance("reference_atol")), ("integrator", "DOP853"), ("method", "projection"),
       ("output_step", 0.01), ("rtol", tolerance("reference_rtol")))
EPS = tolerance("friction_eps", table="cross_validation")
FRICTION_IN = (("friction", "regularized"), ("friction_eps", EPS), ("friction_sgn", "tanh"))
FRICTION_X = (("eps", EPS), ("friction", "regularized"))


def _case(group, engine, mechanism, variant, t_end, options, labels=()):
    return Case("cross_validation", group, engine, mechanism, variant, t_end, tuple(sorted(options)), labels)


def tiny_cases() -> list[Case]:
    cases = [_case("slider_crank/sustained_sliding:reference", "inhouse", "slider_crank", "sustained_sliding", 0.2,
                   REF + FRICTION_IN)]
    for solver in ("index3", "index2"):
        for h, label in ((2e-3, "2e-3"), (1e-3, "1e-3")):
            cases.append(_case("slider_crank/sustained_sliding:exudyn", "exudyn", "slider_crank", "sustained_sliding",
                               0.2, (("h", h), ("output_step", 0.01), ("solver", solver)) + FRICTION_X,
                               (("solver", solver), ("h", label))))
    cases.append(_case("quick_return/seed:reference", "inhouse", "quick_return", "seed", 0.05, REF))
    cases.append(_case("quick_return/seed:inhouse", "inhouse", "quick_return", "seed", 0.05,
                       (("integrator", "RK45"), ("method", "projection"), ("output_step", 0.01), ("rtol", 1e-8))))
    for h, label in ((1e-3, "1e-3"), (5e-4, "5e-4")):
        cases.append(_case("quick_return/seed:exudyn", "exudyn", "quick_return", "seed", 0.05,
                           (("friction", "none"), ("h", h), ("output_step", 0.01), ("solver", "index2")),
                           (("solver", "index2"), ("h", label))))
    return cases


@pytest.fixture(scope="module")
def tiny():
    cases = tiny_cases()
    results = {c: run_case(c) for c in cases}
    return cases, results


def test_summarize_tables(tiny):
    cases, results = tiny
    tables = xv.summarize(cases, results.__getitem__)
    assert set(tables) == {"exudyn_agreement", "exudyn_agreement_timing", "exudyn_reactions"}
    agree = tables["exudyn_agreement"]
    assert len(agree) == 4 + 2 + 1                      # Exudyn runs + the in-house method run
    assert not any("cpu" in c or "seconds" in c for c in agree.columns)
    for c in ("mechanism", "variant", "solver", "h", "max_abs_dq", "max_abs_dqd", "max_abs_dF_friction",
              "max_abs_dN", "order_dq", "order_dqd", "order_dF_friction"):
        assert c in agree.columns, c
    sc = agree[(agree.mechanism == "slider_crank") & (agree.solver == "index3")]
    assert list(sc.h) == [2e-3, 1e-3]                   # sorted: larger step first
    assert np.isnan(sc.order_dq.iloc[0]) and np.isfinite(sc.order_dq.iloc[1])
    # the deviations are those of the runs themselves
    ref = results[cases[0]]
    run = results[find(cases, solver="index3", h=1e-3)[0]]
    assert sc.max_abs_dq.iloc[1] == pytest.approx(np.abs(run.q - ref.q).max(), rel=1e-15)
    dF = np.abs(run.forces["friction_guide"] + run.forces["resistance_guide"] - ref.forces["friction_guide"]).max()
    assert sc.max_abs_dF_friction.iloc[1] == pytest.approx(dF, rel=1e-15)
    assert agree[agree.mechanism == "quick_return"].max_abs_dF_friction.isna().all()   # frictionless
    timing = tables["exudyn_agreement_timing"]
    assert len(timing) == len(agree) and (timing.cpu_seconds > 0).all()
    react = tables["exudyn_reactions"]
    assert set(react.mechanism) == {"quick_return"}     # only frictionless sets
    assert set(react.quantity) == {"lam1", "lam2", "joint_block_on_rocker_n", "joint_ram_guide_n"} \
        | {f"joint_{j}_{c}" for j in "OPAED" for c in "xy"}
    np.testing.assert_allclose(react.relative, react.max_abs_diff / react.max_abs_inhouse, rtol=1e-15)


def test_summarize_is_deterministic_and_reports_missing_reference(tiny):
    cases, results = tiny
    a = xv.summarize(cases, results.__getitem__)
    b = xv.summarize(list(reversed(cases)), results.__getitem__)
    for name in ("exudyn_agreement", "exudyn_reactions"):
        pd.testing.assert_frame_equal(a[name], b[name])
    without = [c for c in cases if c.group != "quick_return/seed:reference"]
    with pytest.raises(LookupError, match="quick_return/seed"):
        xv.summarize(without, results.__getitem__)


def test_case_list_covers_every_variant_and_matches_the_tolerance_table():
    """Both mechanisms, all variants (those with friction between moving parts have their Exudyn runs in the
    moving_friction study); horizons, eps and steps as in reference/cross_validation.toml."""
    cl = load_case_list(CASES_DIR / "cross_validation.toml")
    assert cl.summary == "study.studies.cross_validation"
    moving = load_case_list(CASES_DIR / "moving_friction.toml").cases
    for mechanism in ("slider_crank", "quick_return"):
        there = {c.variant for c in moving if c.mechanism == mechanism and c.engine == "exudyn"}
        assert {c.variant for c in cl.cases if c.mechanism == mechanism} | there == set(available_variants(mechanism))

    def tol(key):
        return tolerance(key, table="cross_validation")

    horizons = {("slider_crank", "seed"): tol("friction_horizon_seed"),
                ("slider_crank", "alpha_damping"): tol("friction_horizon_seed"),
                ("slider_crank", "slip_then_stick"): tol("friction_horizon_slip_then_stick"),
                ("quick_return", "guide_friction"): tol("cut_horizon"),
                ("quick_return", "smooth_cutting"): tol("cut_horizon"),
                ("quick_return", "seed"): tol("cut_horizon"),
                ("four_bar", "seed"): tol("four_bar_horizon")}
    eps = {"slider_crank": tol("friction_eps"), "quick_return": tol("quick_return_friction_eps")}
    ladder = {"slider_crank": tol("slider_crank_friction_steps"), "quick_return": tol("cut_steps"),
              "four_bar": tol("four_bar_order_steps")}

    def expected_runs(key, mechanism):
        """(solver, h) of a set's Exudyn runs: h, h/2, h/4 of its ladder, with two documented exceptions."""
        h = ladder[mechanism]
        if key == "quick_return/seed":        # the on/off law: a wider sweep, 8 h ... h/2 (no asymptotic order)
            return {(s, h * 2.0 ** k) for s in ("index3", "index2") for k in (3, 2, 1, 0, -1)}
        if key == "quick_return/guide_friction":   # index 3 stops at 1e-4 s (index3_newton_floor_time)
            return {("index3", h), ("index3", 0.8 * h)} | {("index2", h / k) for k in (1, 2, 4)}
        return {(s, h / k) for s in ("index3", "index2") for k in (1, 2, 4)}

    for case in cl.cases:
        key, role = xv.parse_group(case.group)
        o = case.kwargs
        assert o["output_step"] == 0.01, case.name
        expected_t = horizons.get((case.mechanism, case.variant))
        if case.variant == "sustained_sliding":
            expected_t = tol("friction_horizon_sustained_sliding") if key.endswith("/frictionless") \
                else tol("friction_horizon_reversals")
        assert case.t_end == expected_t, case.name
        if o.get("friction") == "regularized":
            assert o.get("eps", o.get("friction_eps")) == eps[case.mechanism], case.name
    for key in {xv.parse_group(c.group)[0] for c in cl.cases}:
        group = [c for c in cl.cases if xv.parse_group(c.group)[0] == key]
        exu = [c for c in group if c.engine == "exudyn"]
        assert len([c for c in group if xv.parse_group(c.group)[1] == "reference"]) == 1, key
        got = {(c.kwargs["solver"], c.kwargs["h"]) for c in exu}
        assert got == expected_runs(key, group[0].mechanism), (key, sorted(got))
