"""Exudyn (generated from the descriptions) against the in-house high-accuracy reference (DOP853,
rtol 1e-12, projection, located switches)."""

import numpy as np
import pytest

from study.exudyn_models import run as exudyn_run
from study.params import load_parameters
from study.reference_data import tolerance
from study.simulate import simulate

OUTPUT_STEP = 0.005  # common sampling of both codes [s]; a multiple of every Exudyn step used


def tol(key):
    return tolerance(key, table="cross_validation")


def reference(mechanism, variant, t_end):
    return simulate(mechanism, variant=variant, t_end=t_end, method="projection", integrator="DOP853",
                    rtol=tolerance("reference_rtol"), atol=tolerance("reference_atol"), output_step=OUTPUT_STEP)


def errors(mechanism, variant, t_end, solver, steps):
    ps = load_parameters(mechanism, variant)
    ref = reference(mechanism, variant, t_end)
    rows = []
    for h in steps:
        r = exudyn_run(ps, t_end, h, solver=solver, output_step=OUTPUT_STEP)
        rows.append({
            "h": h,
            "dq": np.abs(r.q - ref.q).max(),
            "dqd": np.abs(r.qd - ref.qd).max(),
            "dlam": np.abs(r.lam - ref.lam).max() / np.abs(ref.lam).max(),
        })
    return ref, rows


def orders(values):
    values = np.asarray(values)
    return np.log2(values[:-1] / values[1:])


@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_quick_return_converges_to_inhouse_reference_at_order_2(solver):
    """On/off law up to the first force switch: q, qd and the reactions converge at order 2."""
    t_end = tol("inhouse_reference_horizon_on_off")
    h = tol("inhouse_order_steps")
    ref, rows = errors("quick_return", "seed", t_end, solver, [h, h / 2, h / 4])
    cutting_work = ref.energies["work_cutting"]
    assert np.all(cutting_work == 0.0), "the comparison horizon must end before the cutting force first acts"
    band = tol("order_band")
    for key in ("dq", "dqd") + (("dlam",) if solver == "index2" else ()):
        observed = orders([row[key] for row in rows])
        assert np.all(np.abs(observed - 2.0) <= band), (key, observed, rows)
    if solver == "index3":
        observed = orders([row["dlam"] for row in rows])
        assert np.all(observed > tol("index3_multiplier_min_order")), observed


@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_four_bar_converges_to_inhouse_reference_at_order_2(solver):
    """The four-bar, added through its description only: Exudyn's model generated from the same
    description converges to the in-house reference at order 2 in q and qd (and the cut joint's
    multipliers: at order 2 with index 2, faster than first order with index 3)."""
    h = tol("four_bar_order_steps")
    steps = [h, h / 2, h / 4]
    _, rows = errors("four_bar", "seed", tol("four_bar_horizon"), solver, steps)
    floor = tol("order_error_floor")
    for key in ("dq", "dqd"):
        e = [row[key] for row in rows]
        assert min(e) > floor, (key, e)
        observed = orders(e)
        assert np.all(observed >= tol("four_bar_min_order")), (key, observed, rows)
        assert np.all(observed <= 2.0 + tol("order_band")), (key, observed, rows)
    observed = orders([row["dlam"] for row in rows])
    if solver == "index2":
        assert np.all(np.abs(observed - 2.0) <= tol("order_band")), ("dlam", observed, rows)
    else:
        assert np.all(observed > tol("index3_multiplier_min_order")), ("dlam", observed, rows)


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_quick_return_smooth_law_one_second(solver):
    """Smooth law over 1 s (one cut): order 2 once the steps resolve the tanh ramps (h <= 2.5e-4)."""
    ref, rows = errors("quick_return", "smooth_cutting", 1.0, solver, [2.5e-4, 1.25e-4, 6.25e-5])
    band = tol("order_band")
    observed = orders([row["dq"] for row in rows])
    assert np.all(np.abs(observed - 2.0) <= band), (observed, rows)
