"""Spatial equations on the compiled backend: the kernels generated from the same symbolic system as the reference
functions (study.model.codegen, by study.spatial.derive.spatial_system) run the heavy top in the compiled loop
against the independent minimal model of tests/test_spatial_heavy_top.py and against the reference path; Bricard's
redundant rows, which the compiled path's multiplier solve cannot take, are refused by name."""

from __future__ import annotations

import numpy as np
import pytest
from test_spatial_heavy_top import TABLE, heavy_top_start
from test_spatial_heavy_top import test_every_stabilization_holds_the_norm_row_and_the_fixed_point as holds_rows
from test_spatial_heavy_top import \
    test_every_stabilization_matches_the_published_and_the_independent_euler_parameters as matches_references

import study
from study.engines import RK4
from study.fast.frontend import user_model
from study.model.compile import GeneratedEquations
from study.reference_data import tolerance
from study.simulate import simulate
from study.spatial.bricard import bricard_start
from study.spatial.heavy_top import heavy_top_mechanism

RTOL = 1e-12   # the reference test's runs' tolerance; the bound of [spatial_heavy_top_independent] rests on it


@pytest.fixture(scope="module")
def top():
    _, eom, q0, qd0 = heavy_top_start()
    return eom, q0, qd0


@pytest.fixture(scope="module", params=["none", "baumgarte", "projection"])
def compiled_run(request, top):
    """{method: the heavy top's run on the compiled backend} for each stabilization, as the reference test runs it."""
    eom, q0, qd0 = top
    options = dict(integrator="DOP853", rtol=RTOL, atol=RTOL * 1e-2, output_step=0.01)
    return {request.param: simulate(eom, q0, qd0, t_end=tolerance("t_end", TABLE), method=request.param,
                                    backend="compiled", **options)}


def test_the_spatial_equations_are_generated_for_both_backends(top):
    """The reference functions are bound from the generated module of the system the compiled kernels come from."""
    eom, _, _ = top
    assert isinstance(eom, GeneratedEquations) and not eom.system.parameters
    module = user_model(eom).module
    assert module.WORK_NAMES == () and module.N_LOAD_INDICATORS == 0 and module.PARAMETERS == []
    assert eom.mass.__module__ == f"study_codegen_{eom.key}"


def test_the_compiled_top_matches_the_independent_and_the_published_euler_parameters(compiled_run):
    """The reference test's criteria (tests/test_spatial_heavy_top.py) on the compiled run: the Euler parameters at
    0.2 s within [spatial_heavy_top_independent] of the independent model and rounding to the published digits; the
    norm row and the fixed point held to the same bound."""
    (method, res), = compiled_run.items()
    assert res.meta["backend"] == "compiled" and res.stats["nfev"] > 0
    matches_references(compiled_run, method)
    holds_rows(compiled_run, method)


@pytest.mark.parametrize("method", ["none", "baumgarte", "projection"])
def test_both_backends_agree_to_round_off_with_the_same_fixed_steps(top, method):
    """RK4 with backend_sample_steps equal steps: only round-off differs (fast_fixed_step_agreement's reason)."""
    eom, q0, qd0 = top
    h, steps = 1e-4, int(tolerance("backend_sample_steps"))
    kw = dict(t_end=steps * h, method=method, integrator="RK4", step=h, output_step=steps * h / 10)
    fast, ref = simulate(eom, q0, qd0, backend="compiled", **kw), simulate(eom, q0, qd0, **kw)
    assert fast.meta["backend"] == "compiled" and len(fast.t) == len(ref.t) == 11
    assert np.abs(fast.q - ref.q).max() <= tolerance("fast_fixed_step_agreement") * np.abs(ref.q).max()
    assert np.abs(fast.qd - ref.qd).max() <= tolerance("fast_fixed_step_agreement") * np.abs(ref.qd).max()


def test_study_run_takes_a_spatial_mechanism_on_both_backends():
    """study.run routes a SpatialMechanism (the catalogue's heavy top, the system of ``top``: its kernels are
    compiled once for this file) to the compiled path's generated kernels: RK4 with backend_sample_steps equal steps
    on both backends differ by round-off only (fast_fixed_step_agreement's reason). The same on the spatial
    slider-crank, every joint kind but a 55 kB module to compile, is in the slow suite
    (tests/test_spatial_slider_crank.py)."""
    h, steps = 1e-4, int(tolerance("backend_sample_steps"))
    fast, ref = [study.run(heavy_top_mechanism(), study.InHouse(integrator=RK4(h=h), backend=backend,
                                                                output_step=steps * h / 10), steps * h)
                 for backend in ("compiled", "reference")]
    assert fast.meta["backend"] == "compiled" and ref.meta["backend"] == "reference" and len(fast.t) == len(ref.t) == 11
    assert np.abs(fast.q - ref.q).max() <= tolerance("fast_fixed_step_agreement") * np.abs(ref.q).max()
    assert np.abs(fast.qd - ref.qd).max() <= tolerance("fast_fixed_step_agreement") * np.abs(ref.qd).max()


def test_redundant_rows_are_refused_by_name_on_the_compiled_backend():
    """Bricard's mechanism (one row redundant at every configuration) needs a rank-deficient solver, which the
    compiled path does not have: its kernels are refused naming the rows, and simulate refuses the run."""
    _, eom, q0, qd0 = bricard_start()
    with pytest.raises(ValueError, match=r"backend='compiled' cannot run the EquationsOfMotion 'bricard': 1 of its "
                                         r"35 constraint rows are redundant .* use backend='reference' with "
                                         r"acceleration_solver='augmented_lagrangian'"):
        user_model(eom)
    with pytest.raises(ValueError, match=r"backend='compiled' does not support "
                                         r"acceleration_solver='augmented_lagrangian'"):
        simulate(eom, q0, qd0, t_end=0.1, integrator="DOP853", acceleration_solver="augmented_lagrangian",
                 backend="compiled")
