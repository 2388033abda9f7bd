"""The one engine interface (study.engines): run specifications, their plain-dict form, their refusals by name,
and ``study.run`` for both engines against the keyword entry points it replaces inside (simulate, exudyn_run)."""

import numpy as np
import pytest

import study
from study.engines import (ALI3P, DOP853, LSODA, RK4, RK23, RK45, Baumgarte, Default, Exact, Exudyn, InHouse,
                           NoFriction, NoStabilization, Projection, Radau, Regularized, Sign, SlidingMode, run,
                           spec_from_dict)
from study.engines.friction import FRICTIONS
from study.engines.integrators import INTEGRATORS
from study.fast.support import SCIPY_STEPS_ONLY, SUPPORTED_INTEGRATORS
from study.mechanisms import named_mechanism
from study.run_arguments import DEFAULT_FRICTION, INTEGRATOR_NAMES
from study.solver.friction import FRICTION_TREATMENTS

SPECS = [
    InHouse(),
    InHouse(method=Baumgarte(d=0.5, omega=20.0), integrator=DOP853(rtol=1e-10, atol=1e-12), friction=Exact(),
            backend="compiled"),
    InHouse(method=SlidingMode(Lambda=(1.0, 2.0), K=3.0, k=1e-6, sgn="sat", width=1e-6), integrator=Radau(min_step=1e-9),
            friction=Regularized(eps=1e-4, sgn="arctan"), resistance_reading="sliding_only"),
    InHouse(method=Projection(weighting="mass"), integrator=RK4(h=1e-3), friction=Sign(eps=1e-5), output_step=0.05,
            check=False, max_evaluations=1e6, max_output_bytes=1e8),
    InHouse(integrator=ALI3P(h=2e-3), friction=NoFriction()),
    InHouse(integrator=LSODA(), friction=Default(eps=1e-4, sgn="sqrt"), acceleration_solver="augmented_lagrangian"),
    InHouse(integrator=RK23(rtol=1e-6, atol=1e-8), backend="compiled"),
    Exudyn(h=1e-3),
    Exudyn(solver="index2", h=5e-4, output_step=1e-2, friction="none", eps=1e-4, configuration="tuned",
           ignore_singular=True, newton_tolerance=1e-9),
]


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: repr(s)[:60])
def test_a_spec_round_trips_through_its_plain_dict(spec):
    d = spec.to_dict()
    plain = (str, int, float, bool, list)
    assert all(isinstance(v, plain) for v in d.values()), d   # TOML-writable: no None, no objects, no tuples
    assert spec_from_dict(d) == spec
    assert type(spec).from_dict(d).to_dict() == d


def test_the_specs_name_what_the_engines_take():
    assert set(INTEGRATORS) == set(INTEGRATOR_NAMES)
    assert set(FRICTIONS) == {*FRICTION_TREATMENTS, "none", DEFAULT_FRICTION}
    for name in INTEGRATORS:   # the compiled backend's integrators (study.fast.support) are accepted ...
        spec = {"integrator": name, **({"step": 1e-3} if name in ("RK4", "ALI3P") else {})}
        if name in (*SUPPORTED_INTEGRATORS, *SCIPY_STEPS_ONLY):
            InHouse.from_dict({**spec, "backend": "compiled"})
        else:   # ... and the others refused, by name
            with pytest.raises(ValueError, match=f"backend = 'compiled' does not apply to integrator {name}"):
                InHouse.from_dict({**spec, "backend": "compiled"})


def test_a_case_lists_options_are_a_spec():
    """The case lists' vocabulary is the specs' dict form: method options as keys beside the run's."""
    spec = InHouse.from_dict({"method": "baumgarte", "d": 1.0, "omega": 10.0, "integrator": "RK4", "step": 1e-3,
                              "friction": "regularized", "friction_eps": 1e-4, "backend": "compiled"})
    assert spec == InHouse(method=Baumgarte(d=1.0, omega=10.0), integrator=RK4(h=1e-3),
                           friction=Regularized(eps=1e-4), backend="compiled")
    assert InHouse.from_dict({"method": "baumgarte", "alpha": 5.0, "beta": 10.0}).method == Baumgarte(d=0.5, omega=10.0)
    assert spec_from_dict({"engine": "exudyn", "h": 1e-3, "solver": "index2"}) == Exudyn(solver="index2", h=1e-3)
    assert InHouse.from_dict({"friction": None}).friction == NoFriction()
    assert InHouse.from_dict({}) == InHouse(method=NoStabilization(), integrator=RK45(), friction=Default())


@pytest.mark.parametrize("make, message", [
    (lambda: InHouse.from_dict({"integrater": "RK4"}), "integrater: not an option of method 'none' nor of an in-house run"),
    (lambda: InHouse.from_dict({"method": "baumgarte", "Omega": 3.0}), "Omega: not an option of method 'baumgarte'"),
    (lambda: InHouse.from_dict({"integrator": "RK4", "step": 1e-3, "rtol": 1e-6}), "do not apply to integrator RK4"),
    (lambda: InHouse.from_dict({"integrator": "RK4"}), "integrator RK4 is fixed-step: give step"),
    (lambda: InHouse.from_dict({"step": 1e-3}), "step = 0.001 applies to the fixed-step integrators"),
    (lambda: InHouse.from_dict({"friction": "exact", "friction_eps": 1e-3}), "friction_eps = 0.001 applies to friction"),
    (lambda: InHouse.from_dict({"integrator": "Heun"}), "integrator = 'Heun' is not known; valid choices: RK45"),
    (lambda: InHouse(integrator=DOP853(rtol=-1.0)), "DOP853.rtol = -1.0 must be finite and > 0"),
    (lambda: InHouse(integrator=RK4(h=0.0)), "RK4.h = 0.0 must be finite and > 0"),
    (lambda: InHouse(friction=Regularized(sgn="sign")), "Regularized.sgn = 'sign' is not a smooth sgn"),
    (lambda: InHouse(friction=Exact(), backend="gpu"), "backend = 'gpu' is not known; valid choices: reference, compiled"),
    (lambda: InHouse(backend="compiled", acceleration_solver="partitioned"),
     "backend='compiled' does not support acceleration_solver='partitioned'"),
    (lambda: InHouse(method=Baumgarte(), integrator=ALI3P(h=1e-3)), "does not apply to integrator ALI3P"),
    (lambda: InHouse(method="baumgarte"), "method = 'baumgarte' must be a Stabilization object"),
    (lambda: InHouse(integrator="DOP853"), "integrator = 'DOP853' must be a Integrator object"),
    (lambda: Exudyn(h=-1e-3), "h = -0.001 must be a finite number > 0"),
    (lambda: Exudyn(h=1e-3, solver="index4"), "unknown solver 'index4'; valid choices: index3, index2"),
    (lambda: Exudyn(h=1e-3, linear_solver="sparse", ignore_singular=True), "needs the dense linear solver"),
    (lambda: Exudyn.from_dict({"h": 1e-3, "step": 1e-3}), "step: not an option of an Exudyn run; valid options: h"),
    (lambda: Exudyn.from_dict({"solver": "index2"}), "an Exudyn run needs h"),
    (lambda: spec_from_dict({"engine": "adams"}), "engine = 'adams' is not known; valid choices: inhouse, exudyn"),
    (lambda: InHouse.from_dict({"engine": "exudyn"}), "engine = 'exudyn': not an in-house run"),
])
def test_a_spec_refuses_by_name_when_made(make, message):
    with pytest.raises(ValueError) as err:
        make()
    assert message in str(err.value)


@pytest.mark.parametrize("spec, t_end, message", [
    (InHouse(integrator=RK4(h=0.5)), 0.1, "RK4.h = 0.5 s is longer than t_end = 0.1 s"),
    (InHouse(output_step=0.5), 0.1, "output_step = 0.5 s is longer than t_end = 0.1 s"),
    (Exudyn(h=3e-3), 0.01, "must be a whole number of steps h = 0.003"),
    (Exudyn(h=1e-3, output_step=1.5e-3), 0.01, "output_step = 0.0015 must be a whole multiple of h = 0.001"),
])
def test_run_refuses_what_does_not_fit_the_horizon(spec, t_end, message):
    with pytest.raises(ValueError) as err:
        run("slider_crank", spec, t_end)
    assert message in str(err.value)


def test_run_refuses_what_an_engine_does_not_take():
    mech = named_mechanism("slider_crank", "seed")
    with pytest.raises(ValueError, match="q0 = .* does not apply to an Exudyn run"):
        run(mech, Exudyn(h=1e-3), 0.01, q0=[0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="progress = .* does not apply to an Exudyn run"):
        run(mech, Exudyn(h=1e-3), 0.01, progress=print)
    with pytest.raises(ValueError, match="is an EquationsOfMotion: Exudyn builds its model from a description"):
        run(mech.equations(), Exudyn(h=1e-3), 0.01)
    with pytest.raises(ValueError, match="must be a run specification"):
        run(mech, {"integrator": "RK45"}, 0.01)


def _same(a, b):
    return (np.array_equal(a.t, b.t) and np.array_equal(a.q, b.q) and np.array_equal(a.qd, b.qd)
            and a.stats.get("nfev") == b.stats.get("nfev") and a.meta == b.meta)


def test_simulate_is_run_with_the_spec_of_its_keywords():
    mech = named_mechanism("slider_crank", "seed")
    by_keywords = study.simulate(mech, t_end=0.1, method="baumgarte", omega=20.0, integrator="DOP853", rtol=1e-9,
                                 friction="regularized", friction_eps=1e-4)
    by_spec = study.run(mech, InHouse(method=Baumgarte(omega=20.0), integrator=DOP853(rtol=1e-9),
                                      friction=Regularized(eps=1e-4)), 0.1)
    assert _same(by_keywords, by_spec)
    assert by_spec.meta["stabilization"] == "baumgarte" and by_spec.meta["integrator"] == "DOP853"
    assert by_spec.meta["friction"] == "regularized" and by_spec.meta["friction_eps"] == 1e-4


def test_exudyn_run_is_run_with_the_exudyn_spec():
    from study.exudyn_models import run as exudyn_engine

    mech = named_mechanism("slider_crank", "seed")
    spec = Exudyn(solver="index2", h=1e-3, output_step=1e-2, friction="none")
    direct = exudyn_engine(mech, 0.02, 1e-3, solver="index2", output_step=1e-2, friction="none")
    assert _same(study.run(mech, spec, 0.02), direct)
    assert _same(study.exudyn_run(mech, 0.02, 1e-3, solver="index2", output_step=1e-2, friction="none"), direct)


def test_every_committed_case_is_a_spec_that_round_trips():
    """A pipeline case is a serialized specification: every case of the committed case lists (the benchmark's too)
    reads as one, and writes back as the same. Its initial state (initial, perturb_ulps, q0, qd0) and the timing
    repeat are the case's, not the engine's."""
    from study.pipeline import CASES_DIR, load_case_list, load_case_lists

    cases = [c for cl in [*load_case_lists(), load_case_list(CASES_DIR / "bench.toml")] for c in cl.all_cases]
    assert {c.engine for c in cases} == {"inhouse", "exudyn"}
    for case in cases:
        options = {k: v for k, v in case.kwargs.items() if k not in ("repeat", "initial", "perturb_ulps", "q0", "qd0")}
        spec = spec_from_dict({"engine": case.engine, **options})
        assert spec.engine == case.engine
        assert spec_from_dict(spec.to_dict()) == spec, case.name


def test_a_mechanism_name_is_found_as_the_pipeline_finds_it():
    """study.simulate and study.run look a name up through named_mechanism, as a case list does: a spatial study
    mechanism by name runs (it was 'unknown mechanism' through the planar parameter files alone)."""
    r = study.simulate("heavy_top", t_end=0.01, integrator="DOP853", rtol=1e-8, atol=1e-10, output_step=0.005)
    assert r.meta["mechanism"] == "heavy_top" and len(r.t) == 3
    assert study.run("heavy_top", InHouse(integrator=DOP853(rtol=1e-8, atol=1e-10), output_step=0.005),
                     0.01).q.shape == r.q.shape
    with pytest.raises(ValueError, match="unknown mechanism 'nowhere'"):
        study.simulate("nowhere", t_end=0.01)


@pytest.mark.parametrize("make, message", [
    (lambda: Baumgarte(d="x"), r"d = 'x' must be a number"),
    (lambda: Projection(max_iter=2.5), r"max_iter = 2.5 must be a whole number"),
])
def test_a_public_method_constructor_names_a_bad_value(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_a_mechanism_refuses_parameters_that_are_not_a_parameter_set():
    d = study.Description("pendulum", ["th"], {"m": 1.0, "l": 1.0})
    d.ground("O", 0, 0)
    d.body("bar", d.p.m, d.p.m * d.p.l ** 2 / 12, {"O": (-d.p.l / 2, 0)}, angle=d.q[0])
    d.revolute("O", (study.GROUND, "O"), ("bar", "O"))
    with pytest.raises(TypeError, match=r"parameters = \{'m': 1.0\} must be a ParameterSet"):
        study.Mechanism(d, {"m": 1.0})
