"""Haug's spatial slider-crank (examples/spatial_slider_crank/spatial_slider_crank.py), a user's spatial mechanism,
through ``study.run`` and ``study.validate``: Exudyn converges to the in-house motion at order 2.

Independent reference for the start: the crank tip B turns about x at omega, v_B = omega x (B - O); the coupler's
length |B - C| is fixed, so (B - C) . (v_B - v_C) = 0 with v_C = (v, 0, 0) along the guide gives the slider's v.
"""

from __future__ import annotations

import runpy
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import study
from study.reference_data import tolerance
from study.spatial import SpatialDescriptionError, SpatialMechanism

SCRIPT = Path(__file__).resolve().parents[1] / "examples" / "spatial_slider_crank" / "spatial_slider_crank.py"


@pytest.fixture(scope="module")
def example():
    return SimpleNamespace(**runpy.run_path(str(SCRIPT)))   # the user's script, run as a user runs it


def test_the_start_has_one_degree_of_freedom_and_the_slider_speed_by_hand(example):
    m = example.slider_crank
    eom, state = m.equations(), m.initial_state()
    assert m.kind == "spatial" and (eom.n_coordinates, eom.n_constraints) == (21, 20)
    assert np.linalg.matrix_rank(eom.phi_q(state.q)) == 20
    omega, pivot, tip, slider = np.array([-2 * np.pi, 0, 0]), np.array([0, 0.1, 0.12]), np.array([0, 0.1, 0.2]), \
        np.array([0.2, 0.0, 0.0])
    v_tip = np.cross(omega, tip - pivot)
    v_slider = ((tip - slider) @ v_tip) / (tip - slider)[0]
    names = eom.coordinate_names
    assert abs(state.qd[names.index("slider_x")] - v_slider) <= tolerance("spatial_newton") * abs(v_slider)
    assert abs(state.qd[names.index("crank_e1")] - omega[0] / 2) <= tolerance("spatial_newton") * abs(omega[0])


def test_a_planar_description_is_never_a_spatial_mechanism_nor_the_reverse(example):
    planar = study.Description("pendulum", ["th"], {"m": 1.0})
    with pytest.raises(SpatialDescriptionError, match="'pendulum' is a Description, not a SpatialDescription"):
        SpatialMechanism(planar, positions={})
    with pytest.raises(TypeError, match="got SpatialDescription; a spatial description's mechanism is "
                                        "study.spatial.SpatialMechanism"):
        study.Mechanism(example.slider_crank.description, q0={"x": 0.0})


@pytest.mark.slow
def test_study_run_takes_the_spatial_mechanism_on_both_backends(example):
    """study.run routes a SpatialMechanism to the compiled path's generated spatial equations: RK4 with
    backend_sample_steps equal steps on both backends differ by round-off only (fast_fixed_step_agreement's reason).
    Slow: compiling this mechanism's module (55 kB) is most of a cold `make test`'s longest file; the fast suite
    checks the same route on the heavy top (tests/test_spatial_compiled.py)."""
    from study.engines import RK4

    h = 1e-3
    steps = int(tolerance("backend_sample_steps"))
    runs = [study.run(example.slider_crank, study.InHouse(integrator=RK4(h=h), backend=backend, output_step=steps * h / 10),
                      steps * h) for backend in ("compiled", "reference")]
    fast, ref = runs
    assert fast.meta["backend"] == "compiled" and len(fast.t) == len(ref.t) == 11
    assert np.abs(fast.q - ref.q).max() <= tolerance("fast_fixed_step_agreement") * np.abs(ref.q).max()
    assert np.abs(fast.qd - ref.qd).max() <= tolerance("fast_fixed_step_agreement") * np.abs(ref.qd).max()


def test_a_spatial_mechanism_has_one_coordinate_set(example):
    with pytest.raises(ValueError, match="coordinates = 'absolute': a spatial mechanism has one coordinate set"):
        example.slider_crank.equations("absolute")


def _validate(example, tmp_path, t_end):
    tables = study.validate(example.slider_crank, study.ValidationSettings(t_end=t_end), tmp_path / "out",
                            say=lambda s: None)
    orders = tables["exudyn_orders"]
    assert len(orders) == 4 and orders["meets_min_order"].astype(bool).all(), orders
    assert orders["above_error_floor"].astype(bool).all(), orders
    assert (tables["in_house"]["error"] == "").all(), tables["in_house"]
    assert len(tables["reactions"]) == 17   # the joint rows: revolute 5, spherical 3, universal 4, prismatic 5
    assert (tmp_path / "out" / "report.md").exists()


def test_validate_exudyn_converges_at_order_two_short(example, tmp_path):
    _validate(example, tmp_path, 0.2)


@pytest.mark.slow
def test_validate_exudyn_converges_at_order_two_over_one_second(example, tmp_path):
    _validate(example, tmp_path, 1.0)


def test_the_studys_copy_is_the_users_example(example):
    """study/spatial/slider_crank.py restates the example (the installed package cannot reach examples/): the two
    must stay the same description and start, or the spatial study would report on another mechanism."""
    from study.spatial.slider_crank import spatial_slider_crank

    ours, users = spatial_slider_crank(), example.slider_crank
    assert ours.description.fingerprint() == users.description.fingerprint()
    assert ours.start == users.start
