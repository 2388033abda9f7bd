"""study.verify: the table comparison of `make verify` and of the perturbation check."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from study.verify import compare_tables, perturbed, rule_for, worst_per_table


def _table(**columns) -> pd.DataFrame:
    return pd.DataFrame(columns)


def test_rules_come_from_reference_with_reasons():
    """Every class of reference/verify.toml states a reason; a listed column gets its class, others the default."""
    run_error = rule_for("sensitivity", "max_abs_dq")
    assert run_error.name == "run_error" and run_error.reason
    assert rule_for("work_precision_orders", "error_fine").name == "fixed_step_error"  # the per-table override
    assert rule_for("work_precision", "max_abs_dq").name == "magnitude_error"
    assert rule_for("anything", "no_such_column").name == "default"
    assert not rule_for("perturbation_check", "worst_abs_diff").compare


def test_numbers_within_and_beyond_their_rule():
    rule = rule_for("andrews_reference", "quantity_value")   # the default rule: relative, no decades
    assert rule.decades == 0 and rule.rtol > 0
    base = 1e-6
    inside = base * (1 + 0.9 * rule.rtol)
    outside = base * (1 + 1.1 * rule.rtol) + rule.atol
    ok = compare_tables("andrews_reference", _table(quantity_value=[base]), _table(quantity_value=[inside]))
    bad = compare_tables("andrews_reference", _table(quantity_value=[base]), _table(quantity_value=[outside]))
    assert ok["passed"].all() and not bad["passed"].any()
    assert bad["worst_rel_diff"].iloc[0] == pytest.approx((outside - base) / base)


def test_decade_rule_judges_the_order_of_magnitude():
    """A class with decades passes a factor below 10**decades either way, fails above it and on a sign change."""
    rule = rule_for("sensitivity", "max_abs_dq")
    assert rule.decades > 0
    factor = 10 ** rule.decades
    base = 1e-6  # far above the class's atol, so only the decade test can pass a large move
    for new, passes in [(base * 0.9 * factor, True), (base / (0.9 * factor), True), (base * 1.1 * factor, False),
                        (base / (1.1 * factor), False), (-base, False)]:
        result = compare_tables("sensitivity", _table(max_abs_dq=[base]), _table(max_abs_dq=[new]))
        assert bool(result["passed"].all()) is passes, (new, passes)


def test_row_rules_select_cells_by_equal_cells():
    """[[rows]] entries override a column's rule in the rows they select, and only there."""
    keys = dict(h_coarse=[1e-5, 2e-5], h_fine=[5e-6, 1e-5])   # the first row is at the reference's floor
    old = _table(**keys, order_published=[4.0, 4.0])
    floor_moved = _table(**keys, order_published=[4.5, 4.0])
    asymptotic_moved = _table(**keys, order_published=[4.0, 4.5])
    assert compare_tables("andrews_orders", old, floor_moved)["passed"].all()  # order_at_floor: not compared
    assert not compare_tables("andrews_orders", old, asymptotic_moved)["passed"].all()


def test_verdicts_must_be_identical():
    old = _table(status=["ok", "ok"], holds=[True, False])
    assert compare_tables("t", old, old.copy())["passed"].all()
    changed = compare_tables("t", old, _table(status=["ok", "failed: x"], holds=[True, True]))
    assert list(changed["passed"]) == [False, False]


def test_event_time_lists_are_compared_number_by_number():
    tol = rule_for("slider_crank_summary", "stick_times").atol
    old = _table(stick_times=["0.0036;4.434"])
    near = _table(stick_times=[f"0.0036;{4.434 + 0.5 * tol!r}"])
    far = _table(stick_times=[f"0.0036;{4.434 + 2 * tol!r}"])
    longer = _table(stick_times=["0.0036;4.434;5"])
    assert compare_tables("slider_crank_summary", old, near)["passed"].all()
    assert not compare_tables("slider_crank_summary", old, far)["passed"].any()
    assert not compare_tables("slider_crank_summary", old, longer)["passed"].any()


def test_shape_change_and_nan():
    old = _table(max_abs_dq=[1.0, math.nan])
    assert compare_tables("t", old, _table(max_abs_dq=[1.0, math.nan]))["passed"].all()
    assert not compare_tables("t", old, _table(max_abs_dq=[1.0, 2.0]))["passed"].all()
    assert not compare_tables("t", old, _table(max_abs_dq=[1.0]))["passed"].all()
    summary = worst_per_table(compare_tables("t", old, _table(max_abs_dq=[1.0, 2.0])))
    assert list(summary["passed"]) == [False] and summary["failed_columns"].iloc[0] == "max_abs_dq"


def test_perturbed_case_has_its_own_key():
    from study.pipeline import load_case_lists

    case = load_case_lists(studies=["work_precision"])[0].cases[0]
    twin = perturbed(case, 4)
    assert twin.kwargs["perturb_ulps"] == 4 and twin.key() != case.key() and twin.name == case.name


def test_margin_and_one_row_per_rule_class():
    """The margin is what the rule allows over what was found; a column whose rows fall under two classes
    ([[rows]] overrides) is reported once per class, so each class's worst difference is its own."""
    rule = rule_for("andrews_reference", "quantity_value")
    base = 1.0
    moved = base * (1 + rule.rtol / 4)   # a quarter of the relative tolerance: margin about 4
    result = compare_tables("andrews_reference", _table(quantity_value=[base]), _table(quantity_value=[moved]))
    assert result["margin"].iloc[0] == pytest.approx((rule.atol + rule.rtol * base) / (moved - base))
    rows = dict(case=["sustained_sliding_regularized", "sustained_sliding_exact"], treatment=["regularized", "exact"])
    old = _table(**rows, nfev=[1000, 1000])
    new = _table(**rows, nfev=[1200, 1010])
    result = compare_tables("slider_crank_summary", old, new).set_index(["column", "rule"]).loc["nfev"]
    assert set(result.index) == {rule_for("slider_crank_summary", "nfev", row={"case": c, "treatment": t}).name
                                 for c, t in zip(rows["case"], rows["treatment"])}
    assert result.loc["magnitude_work", "worst_abs_diff"] == 200
    assert result.loc["work", "worst_abs_diff"] == 10
