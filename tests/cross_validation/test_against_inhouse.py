"""Exudyn against the in-house high-accuracy reference (DOP853, rtol 1e-12, projection, located switches)."""

import numpy as np
import pytest

from study.exudyn_models import quick_return as exudyn_quick_return
from study.mechanisms import load
from study.reference_data import tolerance
from study.simulate import simulate

OUTPUT_STEP = 0.005  # common sampling of both codes [s]; a multiple of every Exudyn step used


def reference(variant, t_end):
    return simulate("quick_return", variant=variant, t_end=t_end, method="projection", integrator="DOP853",
                    rtol=tolerance("reference_rtol"), atol=tolerance("reference_atol"), output_step=OUTPUT_STEP)


def errors(variant, t_end, solver, steps):
    ps, _ = load("quick_return", variant)
    ref = reference(variant, t_end)
    rows = []
    for h in steps:
        r = exudyn_quick_return.run(ps, t_end, h, solver=solver, output_step=OUTPUT_STEP)
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
    t_end = tolerance("inhouse_reference_horizon_on_off", table="cross_validation")
    h = tolerance("inhouse_order_steps", table="cross_validation")
    ref, rows = errors("seed", t_end, solver, [h, h / 2, h / 4])
    cutting_work = ref.energies["work_cutting"]
    assert np.all(cutting_work == 0.0), "the comparison horizon must end before the cutting force first acts"
    band = tolerance("order_band", table="cross_validation")
    for key in ("dq", "dqd") + (("dlam",) if solver == "index2" else ()):
        observed = orders([row[key] for row in rows])
        assert np.all(np.abs(observed - 2.0) <= band), (key, observed, rows)
    if solver == "index3":
        observed = orders([row["dlam"] for row in rows])
        assert np.all(observed > tolerance("index3_multiplier_min_order", table="cross_validation")), observed


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["index3", "index2"])
def test_quick_return_smooth_law_one_second(solver):
    """Smooth law over 1 s (one cut): order 2 once the steps resolve the tanh ramps (h <= 2.5e-4)."""
    ref, rows = errors("smooth_cutting", 1.0, solver, [2.5e-4, 1.25e-4, 6.25e-5])
    band = tolerance("order_band", table="cross_validation")
    observed = orders([row["dq"] for row in rows])
    assert np.all(np.abs(observed - 2.0) <= band), (observed, rows)
