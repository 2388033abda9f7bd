"""Exudyn's tuned configuration (symbolic user functions, modified Newton with one Jacobian per step)
gives the same answers as the Python-user-function configuration, on every described load kind:
a smooth state-dependent point force, an on/off point force with switching modes, a torsion spring
(potential), a spring from a body point to a fixed point and a rate-dependent torque, with and without the friction user function."""

from __future__ import annotations

import numpy as np
import pytest

from study import exudyn_models
from study.params import load_parameters
from study.reference_data import tolerance

H = 1e-3
CASES = [  # mechanism, variant, t_end, solver, friction, law evaluated symbolically when tuned
    ("quick_return", "smooth_cutting", 0.5, "index3", "regularized", "cutting"),
    ("quick_return", "seed", 0.5, "index3", "regularized", "cutting"),
    ("slider_crank", "sustained_sliding", 0.5, "index2", "regularized", "alpha_spring on crank"),
    ("slider_crank", "alpha_damping", 0.5, "index2", "none", "alpha_damper"),
]


@pytest.mark.parametrize("mech, variant, t_end, solver, friction, law", CASES)
def test_tuned_matches_python(mech, variant, t_end, solver, friction, law):
    ps = load_parameters(mech, variant)
    runs = {c: exudyn_models.run(ps, t_end, H, solver=solver, output_step=0.01, friction=friction,
                                 configuration=c) for c in ("python", "tuned")}
    py, tu = runs["python"], runs["tuned"]
    assert py.meta["law_evaluation"][law] == "Python user function"
    assert tu.meta["law_evaluation"][law] == "symbolic user function"
    assert tu.meta["configuration"] == "tuned"
    steps = round(t_end / H)
    per_step = tolerance("exudyn_configuration_agreement_per_step")
    assert np.max(np.abs(tu.q - py.q)) <= per_step * steps * np.max(np.abs(py.q))
    assert np.max(np.abs(tu.lam - py.lam)) <= per_step * steps * np.max(np.abs(py.lam))
    # the evaluation really changed: the tuned run reuses its Jacobian within a step
    assert tu.stats["jacobian_evaluations"] < py.stats["jacobian_evaluations"]


def test_spring_to_a_fixed_point_is_symbolic_and_moves_no_digit_of_the_error():
    """Andrews' spring joins body 3's point D and the fixed point C: tuned, it is a symbolic law of D alone (C's
    inputs are its coordinates). The per-step bound above does not hold here (measured: 1.6e-8 rad after 10 index-2
    steps of 1e-3 s, where it allows 2.2e-9: its Newton residual maps to q through a stiff, light mechanism), so the test holds what the Andrews study needs: the configurations differ by less than the digits
    it reports of each run's error, estimated as |q_h - q_h/2| at 0.03 s."""
    ps = load_parameters("andrews", "seed")
    h = 2e-4
    run = lambda c, step: exudyn_models.run(ps, 0.03, step, solver="index2", output_step=1e-3,  # noqa: E731
                                            friction="none", configuration=c)
    py, tu, fine = run("python", h), run("tuned", h), run("tuned", h / 2)
    assert py.meta["law_evaluation"]["spring on body3.D"] == "Python user function"
    assert tu.meta["law_evaluation"]["spring on body3.D"] == "symbolic user function"
    error = np.max(np.abs(tu.q[-1] - fine.q[-1]))
    assert np.max(np.abs(tu.q - py.q)) <= tolerance("exudyn_configuration_agreement_of_error") * error


def test_unknown_configuration_is_refused():
    ps = load_parameters("quick_return", "smooth_cutting")
    with pytest.raises(ValueError, match="unknown Exudyn configuration 'fast'.*python, tuned"):
        exudyn_models.run(ps, 0.01, H, configuration="fast")
