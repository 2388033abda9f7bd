"""A user's mechanism in a few lines and no parameter file (examples/pendulum/pendulum.py): a uniform bar pinned at
one end, its parameter values the description's own and its initial state given by coordinate name.

Independent reference: the bar's equation by hand, I_O th'' = -m g (l/2) cos th with I_O = m l^2 / 3 (th from the
horizontal, gravity along -y), integrated by scipy at rtol 1e-12.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import study
from study.reference_data import tolerance

SCRIPT = Path(__file__).resolve().parents[1] / "examples" / "pendulum" / "pendulum.py"
MAX_LINES = 15   # issue 35: a simple pendulum through study.validate in at most 15 lines of Python, no TOML file


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("example_pendulum", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_example_is_short_and_needs_no_parameter_file():
    assert len(SCRIPT.read_text().splitlines()) <= MAX_LINES
    assert not list(SCRIPT.parent.glob("*.toml"))


def test_the_pendulum_follows_the_hand_equation(example):
    v = example.pendulum.description.values
    rtol = 1e-10
    r = study.simulate(example.pendulum, t_end=1.0, integrator="DOP853", rtol=rtol, atol=rtol * 1e-2)

    def rhs(t, y):
        return [y[1], -1.5 * v["g"] / v["l"] * np.cos(y[0])]

    hand = solve_ivp(rhs, (0.0, 1.0), [1.0, 0.0], t_eval=r.t, rtol=1e-12, atol=1e-14, method="DOP853")
    assert r.q[0, 0] == 1.0 and r.qd[0, 0] == 0.0
    bound = tolerance("adaptive_global_error_factor") * rtol * np.abs(hand.y[0]).max()
    assert np.abs(r.q[:, 0] - hand.y[0]).max() <= bound


def test_validate_runs_every_engine_and_exudyn_converges_at_order_two(example, tmp_path):
    tables = study.validate(example.pendulum, study.ValidationSettings(t_end=0.5), tmp_path / "out", say=lambda s: None)
    orders = tables["exudyn_orders"]
    assert len(orders) == 4 and orders["meets_min_order"].astype(bool).all(), orders
    assert (tmp_path / "out" / "report.md").exists()


@pytest.mark.parametrize("q0, qd0, fragment", [
    ({"phi": 1.0}, None, "q0['phi']: no coordinate of that name; the coordinates are th"),
    ({"th": float("nan")}, None, "q0['th'] = nan must be a finite number"),
    ({"th": 1.0}, {"x": 0.0}, "qd0['x']: no coordinate of that name"),
    ([1.0], None, "q0 = [1.0] must be a mapping from coordinate names to numbers"),
    ({}, None, "q0 = {} names no coordinate"),
])
def test_a_wrong_initial_state_is_named(example, q0, qd0, fragment):
    with pytest.raises(ValueError) as info:
        study.Mechanism(example.d, q0=q0, qd0=qd0)
    assert fragment in str(info.value)


def test_a_state_given_twice_is_refused(example):
    with pytest.raises(ValueError, match="give one of them"):
        study.Mechanism(example.d, example.pendulum.parameters, q0={"th": 1.0})
