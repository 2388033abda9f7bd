"""ALI3P, the index-3 augmented Lagrangian with mass-orthogonal projections (study.solver.index3).

Independent references: the exact motion of the N-four-bar's parallelogram branch
(study.reference_solutions, a one-degree-of-freedom ODE derived by hand, not from the study's model) and, for a
mechanism with applied loads, a DOP853 run of the index-1 equations at the reference tolerance. Bounds: the
benchmark's own high-precision criterion (reference/benchmarks.toml) and the lower bound on an observed
second order (min_order, reference/cross_validation.toml); the trapezoidal rule is second-order.
"""

from __future__ import annotations

import numpy as np
import pytest

from study import EquationsOfMotion
from study.errors import SimulationError
from study.mechanisms import initial_state, load
from study.reference_data import tolerance
from study.reference_solutions import n_four_bar_b0
from study.simulate import simulate
from study.solver.index3 import ALI3P, integrate_index3
from study.solver.run import build_dynamics, output_times

MIN_ORDER = tolerance("min_order", table="cross_validation")


def _a02(t_end: float, step: float, variant: str = "seed"):
    r = simulate("n_four_bar", variant=variant, t_end=t_end, integrator="ALI3P", step=step, output_step=0.01)
    ps = load("n_four_bar", variant)[0]
    v = ps.values
    reference = n_four_bar_b0(r.t, int(v.N), v.L, v.g, v0=-v.L * ps.initial.qd_independent[0])[0]
    E = r.energies["kinetic"] + r.energies["potential"]
    return r, float(np.abs(v.L * np.cos(r.q[:, 0]) - reference).max()), float(np.abs(E - E[0]).max())


def test_a02_passes_the_singular_positions_at_the_benchmarks_high_precision():
    r, error, _ = _a02(10.0, 2e-3)
    assert error <= tolerance("a02_high_precision", table="benchmarks")
    assert np.abs(r.phi).max() <= 1e-12   # the Newton iteration's tolerance, 1e-12 (1 + |q|), with |q| < 1e2
    assert r.stats["newton_limit_steps"] == 0


def test_error_and_energy_drift_converge_at_second_order_through_the_crossings():
    """Over 3 s (four crossings of a horizontal position), h = 4e-3 and 2e-3 s: steps at which the trapezoidal
    rule's error is within its asymptotic range (the motion's period is ~2 s, so h * omega <= 1.3e-2)."""
    (_, e1, d1), (_, e2, d2) = (_a02(3.0, h) for h in (4e-3, 2e-3))
    assert np.log2(e1 / e2) >= MIN_ORDER, (e1, e2)
    assert np.log2(d1 / d2) >= MIN_ORDER, (d1, d2)


def test_applied_loads_and_their_work_converge_at_second_order():
    """The slider-crank without friction (drive torque and applied loads on the piston), 1 s, against DOP853 at the
    reference tolerance: the coordinates and the work of every load converge at second order."""
    kw = dict(t_end=1.0, friction=None, output_step=0.01)
    ref = simulate("slider_crank", integrator="DOP853", rtol=tolerance("reference_rtol"),
                   atol=tolerance("reference_atol"), **kw)
    works = [k for k in ref.energies if k.startswith("work_")]
    assert works, "the slider-crank has applied loads"
    errors = []
    for h in (8e-3, 4e-3):   # errors ~1e-10: far above the reference's own (~1e-13), inside the asymptotic range
        r = simulate("slider_crank", integrator="ALI3P", step=h, **kw)
        errors.append([np.abs(r.q - ref.q).max()] + [np.abs(r.energies[k] - ref.energies[k]).max() for k in works])
    orders = np.log2(np.array(errors[0]) / np.array(errors[1]))
    assert (orders >= MIN_ORDER).all(), (errors, orders)


def test_without_constraints_it_is_the_trapezoidal_rule():
    """A unit oscillator x'' = -x (no constraint rows) over one period: second-order convergence to cos t."""
    eom = EquationsOfMotion(1, 0, mass=lambda q: np.eye(1), forces=lambda t, q, qd: -q, phi=lambda q: np.zeros(0),
                            phi_q=lambda q: np.zeros((0, 1)), gamma=lambda q, qd: np.zeros(0))
    errors = []
    for h in (2e-2, 1e-2):
        r = simulate(eom, [1.0], [0.0], t_end=2 * np.pi, integrator="ALI3P", step=h, output_step=0.1)
        errors.append(np.abs(r.q[:, 0] - np.cos(r.t)).max())
    assert np.log2(errors[0] / errors[1]) >= MIN_ORDER, errors


def test_a_step_that_does_not_converge_stops_the_run_naming_the_time():
    ps, eom = load("n_four_bar")
    st = initial_state(ps, eom)
    dyn, y0, _ = build_dynamics(eom, st.q, st.qd, method="none", acceleration_solver="augmented_lagrangian",
                                friction=None, friction_eps=1e-3, friction_sgn="tanh")
    with pytest.raises(SimulationError, match=r"did not converge in the step to t = 0.01 s: after 1 iterations"):
        integrate_index3(dyn, y0, 1.0, output_times(1.0, 0.1), 1e-2, ALI3P(max_iter=1, accept_factor=1.0))


@pytest.mark.parametrize("extra, message", [
    ({"method": "projection"}, "method = 'projection' does not apply to integrator ALI3P: it holds the position"),
    ({"acceleration_solver": "multiplier"}, "acceleration_solver = 'multiplier' does not apply to integrator ALI3P"),
    ({"friction": "exact", "mechanism": "slider_crank"}, "friction = 'exact' does not apply to integrator ALI3P"),
    ({"backend": "compiled"}, "backend = 'compiled' does not apply to integrator ALI3P: it runs on the reference"),
    ({"step": None}, "integrator ALI3P is fixed-step: give step"),
    ({"rtol": 1e-8}, "rtol/atol do not apply to integrator ALI3P"),
])
def test_what_ali3p_does_not_use_is_refused_by_name(extra, message):
    kw = {"mechanism": "n_four_bar", "t_end": 1.0, "integrator": "ALI3P", "step": 1e-3} | extra
    with pytest.raises(ValueError, match=message):
        simulate(kw.pop("mechanism"), **kw)
