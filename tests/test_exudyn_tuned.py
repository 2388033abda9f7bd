"""Exudyn's tuned configuration (symbolic user functions, modified Newton with one Jacobian per step)
gives the same answers as the Python-user-function configuration, on every described load kind:
a smooth state-dependent point force, an on/off point force with switching modes, a torsion spring
(potential) and a rate-dependent torque, with and without the friction user function."""

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


def test_unknown_configuration_is_refused():
    ps = load_parameters("quick_return", "smooth_cutting")
    with pytest.raises(ValueError, match="unknown Exudyn configuration 'fast'.*python, tuned"):
        exudyn_models.run(ps, 0.01, H, configuration="fast")
