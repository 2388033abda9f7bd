"""The benchmark's runs as a case list (reference/cases/bench.toml) and its summary.

The case list is standalone: the pipeline's run, reproduce, verify and the report leave it out. Its
summary is checked on hand-made saved results (errors, medians and counts worked out by hand); the
harness's pipeline path on a short reference-path run (saved once, reused, repeats kept apart), and the
quick sweep of one mechanism end to end on a tiny case list.
"""

import numpy as np
import pytest

import study.pipeline as pl
from study.bench import harness
from study.bench.settings import CASE_LIST, CASES, OUTPUT_STEPS, T2_RTOLS, group
from study.bench.summary import summarize
from study.bench.sweeps import plans
from study.results import SimulationResult


# --- the case list -------------------------------------------------------------------------------
def test_bench_list_is_left_out_of_the_studies_and_refused_by_name(tmp_path):
    assert "bench" not in {cl.study for cl in pl.load_case_lists()}
    with pytest.raises(pl.CaseListError, match="standalone.*study run, reproduce and verify leave them out"):
        pl.load_case_lists(studies=["bench"])
    with pytest.raises(pl.CaseListError, match="standalone"):
        pl.run_pipeline(tmp_path / "reports", tmp_path / "cache", studies=["bench"], workers=1)
    assert CASE_LIST.standalone and CASE_LIST.summary == "study.bench.summary"
    assert pl.summary_function(CASE_LIST) is summarize


def test_standalone_must_be_a_reason(tmp_path):
    path = tmp_path / "b.toml"
    path.write_text('[study]\nsummary = "x"\nstandalone = true\n[[group]]\nname = "g"\nmechanism = "quick_return"\n'
                    't_end = 1.0\n')
    with pytest.raises(pl.CaseListError, match="standalone = True must be the reason"):
        pl.load_case_list(path)


def test_bench_list_holds_the_documented_plans():
    """Against the benchmark's description (study/bench/sweeps.py), typed here by hand."""
    assert CASES == {"quick_return": ("smooth_cutting", 5.0, {}),
                     "slider_crank": ("sustained_sliding", 20.0, {"friction": "regularized", "friction_eps": 1e-3}),
                     "four_bar": ("seed", 5.0, {}), "andrews": ("seed", 0.03, {})}
    assert OUTPUT_STEPS == {"quick_return": 0.01, "slider_crank": 0.01, "four_bar": 0.01, "andrews": 1e-3}
    andrews = plans("andrews")
    assert [(engine, method) for engine, method, _ in andrews][-2:] == [("Exudyn tuned", "index3"), ("Exudyn tuned", "index2")]
    for _, _, cases in andrews:   # every fixed step divides the 1e-3 s sampling, from 2e-4 s down
        steps = [c.kwargs.get("step", c.kwargs.get("h")) for c in cases if "rtol" not in c.kwargs]
        assert all(abs(1e-3 / h - round(1e-3 / h)) < 1e-9 for h in steps) and (not steps or steps[0] == 2e-4)
    got = [(engine, method, len(cases)) for engine, method, cases in plans("slider_crank")]
    assert got == [("in-house compiled", "DOP853", 9), ("in-house compiled", "RK45", 9),
                   ("in-house compiled", "RK4", 9), ("in-house reference", "DOP853", 4),
                   ("Exudyn tuned", "index3", 12), ("Exudyn tuned", "index2", 12)]
    rk4 = plans("four_bar")[2][2]
    assert [c.kwargs["step"] for c in rk4] == [0.01 / 2 ** k for k in range(9)]
    dop = plans("four_bar")[0][2]
    assert [(c.kwargs["rtol"], c.kwargs["atol"]) for c in dop] == [(10.0 ** -k, 10.0 ** -(k + 2)) for k in range(4, 13)]
    exu = plans("slider_crank")[4][2][0].kwargs
    assert (exu["h"], exu["configuration"], exu["friction"], exu["eps"]) == (0.01, "tuned", "regularized", 1e-3)
    assert T2_RTOLS == (1e-10, 1e-11, 1e-12, 1e-13, 1e-14)
    scaling = [(c.kwargs["backend"], c.t_end) for c in group("scaling: simulated time")]
    assert scaling == [("compiled", 1.0), ("compiled", 5.0), ("compiled", 20.0), ("compiled", 100.0),
                       ("reference", 1.0), ("reference", 5.0)]


def test_repeat_and_setting_change_the_key_not_the_run():
    case = plans("quick_return")[0][2][0]
    again = harness.repeat_of(case, 2)
    assert again.key() != case.key() and harness.repeat_of(case, 0) == case
    assert again.kwargs["repeat"] == 2 and again.label("repeat") == "2"
    assert harness.with_labels(case, stage="sweep").key() == case.key()
    moved = harness.at_setting(case, 1e-7)
    assert (moved.kwargs["rtol"], moved.kwargs["atol"], moved.label("setting")) == (1e-7, 1e-9, "1e-07")
    exu = harness.at_setting(plans("quick_return")[4][2][0], 0.01 / 3)
    assert exu.kwargs["h"] == 0.01 / 3 and harness.setting(exu) == 0.01 / 3


def test_timed_runs_go_through_the_store_once(tmp_path, monkeypatch):
    """Two timings are two saved runs with the same trajectory; asking again computes nothing."""
    monkeypatch.setenv("STUDY_CACHE_DIR", str(tmp_path))
    case = harness.inhouse_case("quick_return", "seed", 0.05, {}, "reference", "RK45", 1e-6, "test")
    cpu, result = harness.timed(case, 2)
    store = harness.bench_store()
    assert store.root == tmp_path / "bench_runs"
    assert store.has(case) and store.has(harness.repeat_of(case, 1))
    cpus = [store.load(harness.repeat_of(case, k)).stats["cpu_seconds"] for k in (0, 1)]
    assert cpu == pytest.approx(np.median(cpus))
    assert np.array_equal(store.load(case).q, result.q)
    stamps = sorted(p.stat().st_mtime_ns for p in store.root.glob("*.json"))
    assert harness.timed(case, 2)[0] == cpu
    assert sorted(p.stat().st_mtime_ns for p in store.root.glob("*.json")) == stamps


# --- the summary on hand-made saved results ----------------------------------------------------------
def _result(q_first_coordinate, cpu, engine="inhouse", nfev=100, steps=40):
    q = np.zeros((3, 2))
    q[:, 0] = q_first_coordinate
    zeros = np.zeros((3, 1))
    stats = {"steps": steps, "nfev": nfev, ("process_cpu_seconds" if engine == "exudyn" else "cpu_seconds"): cpu}
    return SimulationResult(t=np.array([0.0, 0.5, 1.0]), q=q, qd=np.zeros((3, 2)), qdd=np.zeros((3, 2)), lam=zeros,
                            phi=zeros, phidot=zeros, stats=stats)


def test_summary_from_hand_made_saved_results():
    reference = group("slider_crank: reference")[0]
    check = group("slider_crank: reference check")[0]
    dop, dop_fine = plans("slider_crank")[0][2][:2]
    exu = plans("slider_crank")[4][2][0]
    run = harness.with_labels(dop, stage="sweep")
    fine = harness.with_labels(dop_fine, stage="sweep")
    step = harness.with_labels(harness.at_setting(exu, 0.01 / 3), stage="order-2 step for 1e-06")
    saved = {reference: _result([1.0, 2.0, 3.0], 9.0),
             check: _result([1.0, 2.0, 3.0 + 4e-10], 9.5),
             run: _result([1.0, 2.0 + 3e-4, 3.0 - 5e-4], 0.30, nfev=120),
             harness.repeat_of(run, 1): _result([1.0, 2.0 + 3e-4, 3.0 - 5e-4], 0.10),
             harness.repeat_of(run, 2): _result([1.0, 2.0 + 3e-4, 3.0 - 5e-4], 0.20),
             step: _result([1.0, 2.0, 3.0 + 2e-6], 7.0, engine="exudyn")}

    def load(case):
        for known, result in saved.items():
            if known.key() == case.key():
                return result
        raise pl.MissingResult(f"no saved result for case {case.name} (it failed: SolverError: step too small)")

    listed = [reference, check, run, fine, step, harness.repeat_of(run, 1), harness.repeat_of(run, 2),
              harness.repeat_of(run, 2)]   # a repeat listed twice counts once
    tables = summarize(listed, load)
    refs = tables["references"]
    assert len(refs) == 1 and refs.max_abs_dq_check_vs_reference.iloc[0] == pytest.approx(4e-10, rel=1e-6)
    assert (refs.reference_rtol.iloc[0], refs.check_rtol.iloc[0]) == (5e-15, 1e-14)
    wp = tables["work_precision"]
    assert list(wp.columns) == ["mechanism", "variant", "friction", "engine", "method", "setting", "error", "cpu_s",
                                "repeats", "stage", "note", "nfev", "t_end", "reference", "reference_uncertainty"]
    assert list(wp.engine) == ["in-house compiled", "in-house compiled", "Exudyn tuned"]
    first, failed, order2 = (wp.iloc[i] for i in range(3))
    assert first.error == pytest.approx(5e-4, rel=1e-9) and first.cpu_s == pytest.approx(0.20)  # median(0.3, 0.1, 0.2)
    assert (first.repeats, first.setting, first.nfev, first.method) == (3, 1e-4, 120, "DOP853")
    assert first.friction == "regularized friction, ε = 0.001 m/s" and first.t_end == 20.0
    assert first.reference == "compiled DOP853 rtol 5e-15, atol 5e-17"
    assert first.reference_uncertainty == pytest.approx(4e-10, rel=1e-6)
    assert np.isnan(failed.error) and failed.repeats == 0 and "SolverError: step too small" in failed.note
    assert order2.setting == 0.01 / 3 and order2.stage == "order-2 step for 1e-06"
    assert (order2.cpu_s, order2.repeats) == (7.0, 1) and order2.error == pytest.approx(2e-6, rel=1e-6)


def test_summary_needs_the_reference_of_each_run():
    run = harness.with_labels(plans("four_bar")[0][2][0], stage="sweep")
    with pytest.raises(LookupError, match="no reference 'four_bar: reference' of variant seed over 5 s"):
        summarize([run], lambda case: _result([0.0] * 3, 1.0))
    assert summarize([], lambda case: None) == {}


def test_summary_of_the_20s_quick_return_and_the_scaling_runs():
    """Each run is measured against the reference of its own variant; medians and counts by hand."""
    ref = {c.variant: c for c in group("quick_return 20 s: reference")}
    check = {c.variant: c for c in group("quick_return 20 s: reference check")}
    runs = group("quick_return 20 s: DOP853")
    seed_run = next(c for c in runs if c.variant == "seed" and c.kwargs["rtol"] == 1e-12)
    smooth_run = next(c for c in runs if c.variant == "smooth_cutting" and c.kwargs["rtol"] == 1e-13)
    compiled_5s, reference_1s = group("scaling: simulated time")[1], group("scaling: simulated time")[4]
    saved = {ref["seed"]: _result([0.0, 1.0, 2.0], 1.0), check["seed"]: _result([0.0, 1.0, 2.0 + 2e-10], 1.0),
             ref["smooth_cutting"]: _result([5.0, 5.0, 5.0], 1.0),
             check["smooth_cutting"]: _result([5.0, 5.0 - 7e-10, 5.0], 1.0),
             seed_run: _result([0.0, 1.0 + 3e-9, 2.0], 0.4, nfev=900),
             harness.repeat_of(seed_run, 1): _result([0.0, 1.0 + 3e-9, 2.0], 0.1),
             smooth_run: _result([5.0, 5.0, 5.0 + 1e-8], 0.25),
             compiled_5s: _result([0.0] * 3, 0.05, steps=870),
             harness.repeat_of(compiled_5s, 1): _result([0.0] * 3, 0.07),
             harness.repeat_of(compiled_5s, 2): _result([0.0] * 3, 0.02), reference_1s: _result([0.0] * 3, 0.5)}
    tables = summarize(list(saved), lambda case: saved[case])
    qr = tables["quick_return_20s"].set_index("variant")
    assert qr.loc["seed", "error"] == pytest.approx(3e-9, rel=1e-6) and qr.loc["seed", "cpu_s"] == pytest.approx(0.25)
    assert (qr.loc["seed", "repeats"], qr.loc["seed", "nfev"], qr.loc["seed", "rtol"]) == (2, 900, 1e-12)
    assert qr.loc["seed", "reference_uncertainty"] == pytest.approx(2e-10, rel=1e-6)
    assert qr.loc["smooth_cutting", "error"] == pytest.approx(1e-8, rel=1e-6)
    assert qr.loc["smooth_cutting", "reference_uncertainty"] == pytest.approx(7e-10, rel=1e-6)
    assert qr.loc["smooth_cutting", "reference"] == "compiled RK45 rtol 1e-14"
    assert qr.loc["smooth_cutting", "integrator"] == "DOP853 (compiled)"
    refs = tables["references"]
    assert list(refs.integrator) == ["RK45 (compiled)"] * 2 and list(refs.check_rtol) == [5e-15, 5e-15]
    scaling = tables["scaling_simulated_time"]
    assert list(scaling.backend) == ["compiled", "reference"] and list(scaling.t_end) == [5.0, 1.0]
    assert list(scaling.cpu_s) == pytest.approx([0.05, 0.5]) and list(scaling.repeats) == [3, 1]  # median(.05,.07,.02)
    assert list(scaling.cpu_per_simulated_s) == pytest.approx([0.01, 0.5]) and scaling.steps.iloc[0] == 870
    assert "work_precision" not in tables


# --- the quick sweep end to end, on a tiny case list ------------------------------------------------------
TINY_BENCH = """
[study]
summary = "study.bench.summary"
standalone = "test"

[[group]]
name = "quick_return: reference"
mechanism = "quick_return"
t_end = 1.0
options = { backend = "reference", integrator = "DOP853", rtol = 1e-10, atol = 1e-12, output_step = 0.01 }

[[group]]
name = "quick_return: reference check"
mechanism = "quick_return"
t_end = 1.0
options = { backend = "reference", integrator = "DOP853", rtol = 1e-9, atol = 1e-11, output_step = 0.01 }

[[group]]
name = "quick_return: in-house reference, DOP853"
mechanism = "quick_return"
t_end = 1.0
options = { backend = "reference", integrator = "DOP853", output_step = 0.01 }
sweep.setting = [{ label = "1e-4", rtol = 1e-4, atol = 1e-6 }, { label = "1e-7", rtol = 1e-7, atol = 1e-9 }]
"""


def test_quick_sweep_runs_through_the_pipeline_and_its_summary(tmp_path, monkeypatch):
    """The quick path of one mechanism's sweep on a tiny list: every run and repeat saved in the store,
    the tables made from them, and a second sweep computes nothing."""
    from study.bench import settings, sweeps

    path = tmp_path / "bench.toml"
    path.write_text(TINY_BENCH)
    tiny = pl.load_case_list(path)
    monkeypatch.setenv("STUDY_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(settings, "CASE_LIST", tiny)
    monkeypatch.setattr(sweeps, "CASE_LIST", tiny)
    monkeypatch.setattr(sweeps, "CASES", {"quick_return": ("seed", 1.0, {})})
    executed = sweeps.sweep("quick_return", quick=True)
    store = harness.bench_store()
    assert all(store.has(c) for c in executed)
    groups = [c.group for c in executed if "repeat" not in c.kwargs]
    assert groups == ["quick_return: reference", "quick_return: reference check"] + [
        "quick_return: in-house reference, DOP853"] * 2
    tables = summarize(executed, store.load)
    wp = tables["work_precision"]
    assert list(wp.setting) == [1e-4, 1e-7] and list(wp.stage) == ["sweep", "sweep"]
    assert wp.error.iloc[1] < wp.error.iloc[0] and (wp.error > 0).all()
    # the cheapest run reaching a level is timed repeats(quick) = 2 times (a second case), the others once
    boosted = {c.kwargs["rtol"] for c in executed if "repeat" in c.kwargs}
    assert boosted and all(wp.error[wp.setting == rtol].iloc[0] <= 1e-4 for rtol in boosted)
    assert list(wp.repeats) == [2 if rtol in boosted else 1 for rtol in wp.setting]
    assert len(tables["references"]) == 1
    stamps = sorted(p.stat().st_mtime_ns for p in store.root.glob("*.json"))
    assert sweeps.sweep("quick_return", quick=True) == executed
    assert sorted(p.stat().st_mtime_ns for p in store.root.glob("*.json")) == stamps
