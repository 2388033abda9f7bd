"""The slider-crank, sensitivity and work-precision studies: case lists, summaries, sections, physics.

Each case list must parse and expand to the expected cases; each study's ``summarize`` must run on a
tiny set (short-horizon copies of a few of its cases, run through the pipeline's own runner so
shared keys behave as in ``make reproduce``) and give the expected columns, with CPU time only in
``*_timing`` tables; each report section must render from those tables. Physics: RK4's observed
order (tolerances.toml [rk4_order_band]) and the slider-crank's breakaway torque.
"""

from __future__ import annotations

import dataclasses
import importlib
import io
import math

import numpy as np
import pytest

from study.params import load_parameters
from study.pipeline import (CASES_DIR, InlineExecutor, Store, find, find_one, load_case_list, run_cases,
                            write_tables)
from study.reference_data import tolerance
from study.report.context import ReportContext
from study.studies import sensitivity, slider_crank, slider_crank_paper, work_precision

# study -> (number of cases, number of distinct keys, cases per group)
EXPECTED = {
    "slider_crank": (20, 20, {"treatments": 9, "alpha_damping": 2, "printed": 2, "eps_sweep": 6,
                              "resistance_sliding_only": 1}),
    "sensitivity": (114, 106, {"reference": 1, "none": 1, "baumgarte": 20, "sliding_mode_gains": 36,
                               "sliding_mode_sign": 9, "sliding_mode_k": 24, "sliding_mode_width": 20,
                               "horizon_check": 3}),
    "work_precision": (69, 69, {"reference": 1, "adaptive": 48, "rk4": 16, "rk4_order_smooth": 4}),
}
SHORT = 0.05  # [s] horizon of the tiny sets: a few milliseconds of motion are enough to exercise the code


def case_list(study):
    return load_case_list(CASES_DIR / f"{study}.toml")


def short(case, t_end=SHORT):
    return dataclasses.replace(case, t_end=t_end)


def run_tiny(cases, tmp_path):
    """Run cases like the pipeline does (duplicate keys once) and return the store's loader."""
    store = Store(tmp_path / "runs")
    summary = run_cases(cases, store, InlineExecutor(), title="tiny", stream=io.StringIO())
    assert not summary.failed, summary.failed
    return store


def check_tables(tables, expected_columns):
    for name, frame in tables.items():
        assert len(frame), f"table {name} is empty"
        if not name.endswith("_timing"):
            cpu = [c for c in frame.columns if "cpu" in c.lower() or "wall" in c.lower()]
            assert not cpu, f"table {name} has machine-dependent columns {cpu}; they belong in a *_timing table"
    for name, columns in expected_columns.items():
        assert name in tables, f"missing table {name}; got {sorted(tables)}"
        missing = set(columns) - set(tables[name].columns)
        assert not missing, f"table {name} lacks columns {sorted(missing)}"


def render(study, cases, store, tables, tmp_path):
    reports = tmp_path / "reports"
    write_tables(tables, reports, f"python -m study run {study}")
    ctx = ReportContext(reports, store, {study: dataclasses.replace(case_list(study), cases=tuple(cases))})
    lines = importlib.import_module(f"study.report.sections.{study}").section(ctx)
    assert lines[0].startswith("## ")
    return lines, ctx


# --- case lists ------------------------------------------------------------------------------------
@pytest.mark.parametrize("study", sorted(EXPECTED))
def test_case_list_expands_as_expected(study):
    cl = case_list(study)
    n_cases, n_keys, per_group = EXPECTED[study]
    assert cl.summary == f"study.studies.{study}"
    assert len(cl.cases) == n_cases
    assert len({c.key() for c in cl.cases}) == n_keys
    assert {g: len(find(cl.cases, group=g)) for g in per_group} == per_group


# --- summaries and sections on tiny sets ---------------------------------------------------------------
def test_slider_crank_summary_and_section(tmp_path):
    cl = case_list("slider_crank").cases
    picked = [find_one(cl, group="treatments", variant=v, treatment=t)
              for v in ("seed", "slip_then_stick") for t in ("exact", "regularized", "sign")]
    picked += find(cl, group="printed") + [find_one(cl, group="alpha_damping", treatment="exact")]
    picked += find(cl, group="eps_sweep", variant="slip_then_stick")[:1]
    cases = [short(c) for c in picked]
    store = run_tiny(cases, tmp_path)
    tables = slider_crank.summarize(cases, store.load)
    check_tables(tables, {
        "slider_crank_summary": ["case", "variant", "treatment", "initial", "method", "stick_times", "q1_t1",
                                 "dissipated_energy", "energy_balance_error", "max_abs_phi", "nfev"],
        "slider_crank_timing": ["case", "cpu_seconds"],
        "seed_holding_forces": ["f_required", "static_limit", "breakaway_M", "slide_distance"],
        "slider_crank_eps_sweep": ["variant", "friction_eps", "max_abs_dq1_vs_exact", "creep_q1", "nfev"],
        "slider_crank_eps_sweep_timing": ["variant", "friction_eps", "cpu_seconds"],
    })
    summary = tables["slider_crank_summary"]
    assert list(summary["case"][:3]) == ["seed_exact", "seed_regularized", "seed_sign"]
    # the seed case sticks within the 0.05 s (000's data cannot move the mechanism)
    assert summary.set_index("case").loc["seed_exact", "final_phase"] == "stick"
    lines, ctx = render("slider_crank", cases, store, tables, tmp_path)
    assert any(line.startswith("## Slider-crank with Coulomb friction") for line in lines)
    assert len(ctx.figures_written) >= 3


def test_sensitivity_summary_and_section(tmp_path):
    cl = case_list("sensitivity").cases
    picked = [find_one(cl, group="reference"), find_one(cl, group="none"),
              find_one(cl, group="baumgarte", d=0.1, omega=1.0),
              find_one(cl, group="baumgarte", d=1.0, omega=10.0),
              find_one(cl, group="sliding_mode_gains", sgn="tanh", Lambda=10.0, K=10.0),
              find_one(cl, group="sliding_mode_gains", sgn="sat", Lambda=1.0, K=100.0),
              find_one(cl, group="sliding_mode_sign", Lambda=10.0, K=10.0),
              # same key as the gains grid's (tanh, 10, 10): run once, read through the first case
              find_one(cl, group="sliding_mode_k", sgn="tanh", k=1e-6),
              find_one(cl, group="sliding_mode_width", sgn="tanh", width=1e-8),
              find_one(cl, group="horizon_check", setting="none")]
    cases = [short(c) for c in picked]
    store = run_tiny(cases, tmp_path)
    tables = sensitivity.summarize(cases, store.load)
    check_tables(tables, {
        "sensitivity": ["group", "method", "sgn", "d", "omega", "Lambda", "K", "k", "width", "max_abs_phi",
                        "max_abs_phidot", "max_abs_dq_vs_reference", "energy_error_relative", "nfev", "status"],
        "sensitivity_timing": ["group", "cpu_seconds"],
        "sensitivity_horizon": ["setting", "max_abs_phi_short", "max_abs_phi_full", "ratio_full_to_short"],
    })
    table = tables["sensitivity"]
    assert len(table) == len(cases) - 2  # all but the reference and the horizon check
    assert (table["status"] == "ok").all()
    shared = table[(table["sgn"] == "tanh") & (table["Lambda"] == 10) & (table["K"] == 10)]
    assert len(shared) == 3 and shared["max_abs_phi"].nunique() == 1
    lines, _ = render("sensitivity", cases, store, tables, tmp_path)
    assert lines[0] == "## Sensitivity of the stabilization to its gains"


def test_work_precision_summary_section_and_rk4_order(tmp_path):
    """RK4 over the smooth first 0.08 s of the quick-return: the observed order of the three finest steps
    (two pairs) is 4 within tolerances.toml [rk4_order_band]."""
    cl = case_list("work_precision").cases
    order_cases = find(cl, group="rk4_order_smooth")
    horizon = order_cases[0].t_end
    picked = [short(find_one(cl, group="reference"), horizon)] + order_cases
    picked += [short(find_one(cl, group="adaptive", method=m, integrator="RK45", tol="1e-6"), horizon)
               for m in ("none", "projection")]
    picked += [short(find_one(cl, group="rk4", method="baumgarte", step=2e-3), horizon)]
    store = run_tiny(picked, tmp_path)
    tables = work_precision.summarize(picked, store.load)
    check_tables(tables, {
        "work_precision": ["method", "integrator", "rtol", "step", "max_abs_dq", "nfev", "max_abs_phi"],
        "work_precision_timing": ["method", "integrator", "rtol", "step", "cpu_seconds"],
        "work_precision_orders": ["group", "h_coarse", "h_fine", "observed_order"],
    })
    orders = tables["work_precision_orders"]
    smooth = orders[orders["group"] == "rk4_order_smooth"].sort_values("h_fine")
    band = tolerance("rk4_order_band")
    assert len(smooth) == len(order_cases) - 1
    for p in smooth["observed_order"].iloc[:2]:
        assert abs(p - 4.0) <= band, f"observed RK4 order {p:.3f} outside 4 +- {band}"
    assert work_precision.rk4_order_verdict(orders, "rk4_order_smooth", band)["holds"]
    lines, _ = render("work_precision", picked, store, tables, tmp_path)
    assert lines[0] == "## Convergence and work–precision"


# --- slider-crank physics ----------------------------------------------------------------------------
def test_breakaway_torque_is_where_the_holding_force_reaches_the_static_limit():
    """At M = breakaway_M the static balance needs exactly the guide's limit F + mu |N|, with N from
    the same rest balance; slightly below it holds, slightly above it does not."""
    v = load_parameters("slider_crank", "seed").values
    q1 = math.pi / 6
    q = np.array([q1, math.asin(v.l1 * math.sin(q1) / v.l2) - q1])  # the consistent branch
    b = slider_crank_paper.breakaway_torque(v, q)
    assert b["breakaway_M"] > v.M  # 000's drive cannot move it
    at = slider_crank_paper.holding_forces(dataclasses.replace(v, M=b["breakaway_M"]), q)
    limit = v.F + v.mu * abs(b["breakaway_normal"])
    assert abs(at["f_required"] - b["breakaway_f"]) <= tolerance("round_off") * limit
    assert abs(abs(b["breakaway_f"]) - limit) <= tolerance("round_off") * limit
    th = q.sum()
    for factor, holds in ((0.99, True), (1.01, False)):
        f = slider_crank_paper.holding_forces(dataclasses.replace(v, M=factor * b["breakaway_M"]), q)["f_required"]
        normal = v.m3 * v.g + (v.m2 * v.g * v.c2 * math.cos(th) + v.l2 * math.sin(th) * f) / (v.l2 * math.cos(th))
        assert (abs(f) <= v.F + v.mu * abs(normal)) is holds


def test_singular_x_b0_against_the_published_value_only_for_n2_at_10s():
    """x_B0(10 s) minus fourBarMechanismIftomm's published 0.32846 m, at full precision, for N = 2 runs that end at
    10 s; NaN for N = 40 or a run that ends elsewhere."""
    from study.studies import singular

    t, xb = np.array([0.0, 10.0]), np.array([1.0, 0.32846488])
    assert singular.minus_published(2, t, xb) == pytest.approx(4.88e-6, abs=1e-12)
    assert np.isnan(singular.minus_published(40, t, xb))
    assert np.isnan(singular.minus_published(2, np.array([0.0, 9.5]), xb))
