"""The one code generator (study.model.codegen): its blocks, and its two targets written from the same equations,
planar (study.model.codegen.planar_system) and spatial (study.spatial.derive.spatial_system).

The compiled module is executed here as plain Python (its ``kernel`` decorator replaced by the identity), so these
tests compare what the two targets compute without compiling anything.
"""

import math

import numpy as np
import pytest
import sympy as sp

from study.mechanisms import description
from study.model.codegen import block_lines, compiled_source, planar_system, reference_source
from study.model.compile import compile_description
from study.model.coordinates import lower
from study.model.derive import derive
from study.params import load_parameters
from study.reference_data import tolerance
from study.spatial import spatial_equations
from study.spatial.bricard import bricard
from study.spatial.heavy_top import heavy_top

X, Y = sp.symbols("x y")


def _run(lines: list[str], **values) -> dict:
    scope = {"math": math, **values}
    exec("\n".join(line.strip() for line in lines), scope)
    return scope


def test_a_block_computes_a_shared_subexpression_once():
    root = sp.sqrt(X + Y)
    lines = block_lines([("a", root * Y + root), ("b", root * X)], "    ")
    assert sum(line.count("math.sqrt") for line in lines) == 1
    scope = _run(lines, x=1.5, y=2.5)          # sqrt(4) = 2: every value below is exact
    assert (scope["a"], scope["b"]) == (7.0, 3.0)


def test_zero_targets_are_left_out_only_when_asked():
    targets = [("a", X * 0), ("b", X + 1)]
    assert [line.split(" = ")[0].strip() for line in block_lines(targets, "", skip_zeros=True)] == ["b"]
    assert _run(block_lines(targets, ""), x=2.0)["a"] == 0


def test_a_planar_block_is_sympys_basic_cse_and_a_spatial_one_skips_factor_terms():
    """The prepared (memoized) expressions give exactly sp.cse(optimizations="basic") when factored (planar systems:
    their generated code and tables do not move), and sp.cse with sub_pre/sub_post only when not (spatial ones)."""
    from sympy.simplify.cse_opts import sub_post, sub_pre

    from study.model.codegen import _PRINTER

    b = lower(description(load_parameters("slider_crank")), "relative")
    system = planar_system(b, derive(b))
    assert system.factored and not spatial_equations(heavy_top()).system.factored
    targets = [(f"M{i}", e) for i, e in enumerate(system.mass)] + [(f"Q{i}", e) for i, e in
                                                                     enumerate(system.velocity_terms)]
    for factored, optimizations in ((True, "basic"), (False, [(sub_pre, sub_post)])):
        replacements, reduced = sp.cse([e for _, e in targets], symbols=sp.numbered_symbols("x_"),
                                       optimizations=optimizations)
        expected = [f"{x} = {_PRINTER.doprint(e)}" for x, e in replacements]
        assert block_lines(targets, "", factored=factored) == \
            expected + [f"{name} = {_PRINTER.doprint(e)}" for (name, _), e in zip(targets, reduced)]


def test_both_targets_begin_with_the_generated_code_header():
    from test_sizes import GENERATED_HEADER

    b = lower(description(load_parameters("slider_crank")), "relative")
    system = planar_system(b, derive(b))
    assert reference_source(system).startswith(GENERATED_HEADER)
    assert compiled_source(system).startswith(GENERATED_HEADER)


def _compiled_module(system, monkeypatch) -> dict:
    import study.kernels.cache

    monkeypatch.setattr(study.kernels.cache, "kernel", lambda signature: (lambda f: f))
    scope = {}
    exec(compile(compiled_source(system), f"<compiled {system.name}>", "exec"), scope)
    return scope


def _equations(mechanism: str):
    """(equations, the system they were generated from, its parameter values in PARAMETERS order)."""
    if mechanism == "bricard":
        eom = spatial_equations(bricard())
        return eom, eom.system, np.zeros(0)
    b = lower(description(load_parameters(mechanism)), "relative")
    system = planar_system(b, derive(b))
    return compile_description(b), system, np.array([float(b.values[name]) for name in system.parameters])


def _relative(a, b):
    return np.max(np.abs(np.asarray(a) - b), initial=0.0) / max(np.max(np.abs(b), initial=0.0), 1e-300)


@pytest.mark.parametrize("mechanism", ["quick_return", "slider_crank_pins", "bricard"])
def test_the_compiled_target_computes_what_the_reference_target_computes(mechanism, monkeypatch):
    """Every output of the compiled kernels against the reference functions at one state: the same symbolic
    equations, blocked differently (one block per kernel, one per reference function), agree to round-off; the
    switching functions are one block in both and agree exactly. Bricard's mechanism: a spatial system (five bodies,
    Euler parameters, the joints' and the norm rows)."""
    eom, system, p = _equations(mechanism)
    mod = _compiled_module(system, monkeypatch)
    assert mod["PARAMETERS"] == list(system.parameters)
    m, r, k = eom.n_coordinates, eom.n_constraints, len(eom.contacts) + len(eom.pin_frictions)
    rng = np.random.default_rng(0)
    t, q, qd = 0.3, rng.normal(size=m), rng.normal(size=m)
    live = np.zeros(mod["N_LOAD_INDICATORS"])
    mod["indicators"](t, q, qd, p, np.zeros(0), live)
    mode = np.where(live >= 0, 1, -1)
    if eom.indicators is not None:
        assert np.array_equal(live, eom.indicators(t, q, qd))
    M, Q, phi, J, gamma = np.zeros((m, m)), np.zeros(m), np.zeros(r), np.zeros((r, m)), np.zeros(r)
    Jt, bt, powers = np.zeros((k, m)), np.zeros(k), np.zeros(mod["N_WORK"])
    mod["evaluate"](t, q, qd, mode, p, np.zeros(0), M, Q, phi, J, gamma, Jt, bt, powers)
    rates = [(c.tangent_jacobian, c.tangent_bias) for c in eom.contacts]
    rates += [(pin.rate_jacobian, pin.rate_bias) for pin in eom.pin_frictions]
    loads = eom.applied_forces(t, q, qd, tuple(mode))
    pairs = [(M, eom.mass(q)), (Q, eom.forces(t, q, qd, tuple(mode))), (phi, eom.phi(q)), (J, eom.phi_q(q)),
             (gamma, eom.gamma(q, qd)), (Jt, np.array([jac(q) for jac, _ in rates]).reshape(k, m)),
             (bt, np.array([bias(q, qd) for _, bias in rates])),
             (powers, np.array([loads[name] @ qd for name in mod["WORK_NAMES"]]))]
    for got, want in pairs:
        assert _relative(got, want) <= tolerance("round_off")
    K = (np.zeros(r), np.zeros((r, m)), np.zeros((m, m)))
    mod["kinematics"](q, p, *K)
    for got, want in zip(K, (eom.phi(q), eom.phi_q(q), eom.mass(q))):
        assert _relative(got, want) <= tolerance("round_off")
