"""The studies' compiled sweeps agree with the reference path on their samples.

Every case list group with ``backend = "compiled"`` and ``reference_sample = n`` names every n-th
case to be run on both paths (study.pipeline.CaseList.samples), the reference-path twin over the horizon
the agreement bound's reason assumes (study.pipeline.cases.sample_horizon). Here each pair runs over a
shorter horizon still (CHECK_T_END, so the test stays fast) and must agree within
study.pipeline.sample_agreement's bound, whose tolerances and reasons are in reference/tolerances.toml.
"""

from __future__ import annotations

import pytest

from study.pipeline import CaseListError, load_case_list, load_case_lists, sample_agreement
from study.simulate import simulate

CHECK_T_END = 0.3   # [s] cut further to the twin's horizon where that is shorter

PAIRS = [(cl.study, case, twin) for cl in load_case_lists() for case, twin in cl.samples]
#: Options that change a run's numbers but not the compiled code it runs (tolerances, steps, gains, widths)
NUMBERS = ("rtol", "atol", "step", "d", "omega", "K", "Lambda", "k", "width", "friction_eps", "output_step")


def _path(case) -> tuple:
    """What selects a sample's code on both paths: the mechanism, its variant and every option but NUMBERS."""
    return (case.mechanism, case.variant, *sorted((k, v) for k, v in case.kwargs.items() if k not in NUMBERS))


def _marked(pairs):
    """The first pair of each code path (_path) in make test; a pair that repeats a path with other numbers runs
    in the slow suite (make verify): test_sample_agrees_with_reference_path's first pair of that path covers its
    claim in make test."""
    seen, out = set(), []
    for pair in pairs:
        key = _path(pair[1])
        out.append(pytest.param(*pair, id=pair[1].name, marks=[pytest.mark.slow] if key in seen else []))
        seen.add(key)
    return out


def test_some_study_runs_compiled_with_samples():
    assert PAIRS, "no case list samples a compiled group"
    assert all(case.kwargs["backend"] == "compiled" and twin.kwargs["backend"] == "reference"
               for _, case, twin in PAIRS)
    # the twins are not part of the study's cases (its summary never sees them)
    for cl in load_case_lists():
        assert not set(t for _, t in cl.samples) & set(cl.cases)


@pytest.mark.parametrize("study, case, twin", _marked(PAIRS))
def test_sample_agrees_with_reference_path(study, case, twin):
    """A compiled sample and its reference-path twin agree. make test checks one pair per code path (mechanism,
    variant, integrator, method, sgn, friction law); the pairs that repeat a path with other tolerances, steps or
    gains are slow (make verify), each covered in make test by the first pair of its path."""
    short = {k: v for k, v in case.kwargs.items() if k != "backend"}
    t_end = min(CHECK_T_END, twin.t_end)
    fast = simulate(case.mechanism, variant=case.variant, t_end=t_end, backend="compiled", **short)
    ref = simulate(case.mechanism, variant=case.variant, t_end=t_end, backend="reference", **short)
    verdict = sample_agreement(fast, ref, case.kwargs)
    assert verdict["agree"], f"{case.name}: max|dq| {verdict['max_abs_dq']:.3g} > {verdict['bound']:.3g} ({verdict['rule']})"


def test_backend_keys_are_checked(tmp_path):
    path = tmp_path / "x.toml"
    head = '[study]\nsummary = "study.studies.sensitivity"\n[[group]]\nname = "g"\nmechanism = "quick_return"\nt_end = 1.0\n'
    path.write_text(head + 'backend = "fast"\n')
    with pytest.raises(CaseListError, match="backend = 'fast' must be one of"):
        load_case_list(path)
    path.write_text(head + 'reference_sample = 2\n')
    with pytest.raises(CaseListError, match="reference_sample needs backend = 'compiled'"):
        load_case_list(path)
    path.write_text(head + 'backend = "compiled"\nreference_sample = 0\n')
    with pytest.raises(CaseListError, match="reference_sample = 0 must be a whole number >= 1"):
        load_case_list(path)
    path.write_text(head + 'backend = "compiled"\nreference_sample = 2\nsweep.rtol = [1e-6, 1e-7, 1e-8]\n')
    cl = load_case_list(path)
    assert len(cl.cases) == 3 and len(cl.samples) == 2 and len(cl.all_cases) == 5
