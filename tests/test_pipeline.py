"""The pipeline: case lists, cache keys, caching, failed cases, resume after an interruption,
determinism of the tables, and the Dask executor (on a LocalCluster)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from study import pipeline as pl
from study.pipeline import execute
from study.results import SimulationResult

from shared_cache import linked_cache
from tiny_cases import tiny  # noqa: F401  (a pytest fixture)


def _write(folder, text, name="demo.toml"):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_text(text)
    return folder / name


# --- case lists --------------------------------------------------------------------------------
def test_sweep_expands_to_labelled_cases(tiny):
    cl = pl.load_case_list(tiny / "sliding_mode.toml")
    assert len(cl.cases) == 7
    case = pl.find_one(cl.cases, setting="RK4 h=1e-3", method="baumgarte")
    assert case.kwargs == {"integrator": "RK4", "step": 1e-3, "method": "baumgarte", "d": 1.0, "omega": 10.0,
                           "output_step": 0.05}
    assert case.name == "sliding_mode/runs [setting=RK4 h=1e-3, method=baumgarte]"


def test_exclude_and_field_sweeps(tmp_path):
    path = _write(tmp_path, """
[study]
summary = "x"
[[group]]
name = "g"
mechanism = "slider_crank"
t_end = 1.0
sweep = { variant = ["seed", "sustained_sliding"], method = ["none", "projection"] }
exclude = [{ method = "projection" }, { variant = "seed", method = "none" }]
""")
    cases = pl.load_case_list(path).cases
    assert [(c.variant, c.kwargs) for c in cases] == [("sustained_sliding", {"method": "none"})]


@pytest.mark.parametrize("group,message", [
    ('name = "g"\nmechanism = "quick_return"\nt_end = 1.0\nengine = "matlab"', "engine = 'matlab'"),
    ('name = "g"\nmechanism = "quick_return"\nt_end = -1.0', "t_end = -1.0 must be finite and > 0"),
    ('name = "g"\nmechanism = "quick_return"\nt_end = 1.0\nsweeps = {}', "unknown keys ['sweeps']"),
    ('name = "g"\nmechanism = "quick_return"\nt_end = 1.0\nsweep = { omega = 3 }', "sweep.omega = 3 must be a non-empty list"),
    ('name = "g"\nt_end = 1.0', "'mechanism' and 't_end' are required"),
    ('name = "g"\nmechanism = "quick_return"\nt_end = 1.0\nengine = "exudyn"', "needs the step 'h'"),
    ('name = "g"\nmechanism = "quick_return"\nt_end = 1.0\nengine = "exudyn"\n'
     'options = { h = 1e-3, linear_solver = "lu" }',
     "unknown linear solver 'lu'; valid choices: dense, sparse"),
    ('name = "g"\nmechanism = "quick_return"\nt_end = 1.0\nengine = "exudyn"\n'
     'options = { h = 1e-3, newton_tolerance = 0.0 }', "newton_tolerance = 0.0 must be a number in (0, 1)"),
    ('name = "g"\nmechanism = "quick_return"\nt_end = 1.0\nengine = "exudyn"\n'
     'options = { h = 3e-3 }', "t_end = 1.0 must be a whole number of steps h = 0.003"),
    ('name = "g"\nmechanism = "quick_return"\nt_end = 1.0\nsweep = { method = ["none"] }\n'
     'exclude = [{ methd = "none" }]', "names ['methd'], which no case of the group sets"),
])
def test_case_list_errors_name_the_file_group_and_value(tmp_path, group, message):
    path = _write(tmp_path, f'[study]\nsummary = "x"\n[[group]]\n{group}\n')
    with pytest.raises(pl.CaseListError) as err:
        pl.load_case_list(path)
    assert message in str(err.value) and "demo.toml" in str(err.value)


def test_keys_follow_inputs_not_names():
    base = pl.Case("s", "g", "inhouse", "quick_return", "seed", 1.0, (("method", "none"),))
    renamed = pl.Case("other", "h", "inhouse", "quick_return", "seed", 1.0, (("method", "none"),), (("a", "b"),))
    assert base.key() == renamed.key()
    for changed in (pl.Case("s", "g", "inhouse", "quick_return", "seed", 2.0, (("method", "none"),)),
                    pl.Case("s", "g", "inhouse", "quick_return", "smooth_cutting", 1.0, (("method", "none"),)),
                    pl.Case("s", "g", "inhouse", "quick_return", "seed", 1.0, (("method", "projection"),)),
                    pl.Case("s", "g", "exudyn", "quick_return", "seed", 1.0, (("method", "none"),))):
        assert changed.key() != base.key()


def test_every_committed_case_list_expands():
    lists = pl.load_case_lists()
    assert {"sliding_mode"} <= {cl.study for cl in lists}
    for cl in lists:
        assert cl.cases, cl.study
        assert len({c.name for c in cl.cases}) == len(cl.cases), f"{cl.study}: two cases share a name"


# --- running, caching, failures ----------------------------------------------------------------
def test_cached_cases_are_not_rerun(tiny, tmp_path):
    store = pl.Store(tmp_path / "runs")
    cases = pl.load_case_list(tiny / "sliding_mode.toml").cases
    first = pl.run_cases(cases, store, pl.InlineExecutor())
    assert (first.computed, first.cached, first.failed) == (7, 0, {})
    stamps = {p: p.stat().st_mtime_ns for p in (tmp_path / "runs").rglob("*.json")}
    second = pl.run_cases(cases, store, pl.InlineExecutor())
    assert (second.computed, second.cached) == (0, 7)
    assert stamps == {p: p.stat().st_mtime_ns for p in (tmp_path / "runs").rglob("*.json")}
    assert store.load(cases[0]).meta["case"]["key"] == cases[0].key()


def test_failed_case_is_recorded_and_others_go_on(tmp_path):
    path = _write(tmp_path / "cases", """
[study]
summary = "x"
[[group]]
name = "g"
mechanism = "quick_return"
t_end = 0.05
sweep = { max_evaluations = [100000, 5, 200000] }
""")
    cases = pl.load_case_list(path).cases
    store = pl.Store(tmp_path / "runs")
    out = pl.run_cases(cases, store, pl.InlineExecutor())
    assert out.computed == 2 and list(out.failed) == ["demo/g [max_evaluations=5]"]
    assert out.failed["demo/g [max_evaluations=5]"].startswith("RunBoundError: quick_return: 5 evaluations reached")
    bad = pl.find_one(cases, max_evaluations=5)
    assert store.failure(bad)["error"] == out.failed[bad.name] and "Traceback" in store.failure(bad)["traceback"]
    with pytest.raises(LookupError, match="it failed"):
        store.load(bad)
    table = pl.failures_table([pl.load_case_list(path)], store)
    assert list(table["case"]) == [bad.name]
    again = pl.run_cases(cases, store, pl.InlineExecutor())  # failures are retried, successes are not
    assert (again.cached, again.computed, len(again.failed)) == (2, 0, 1)


def test_expected_errors_are_results_and_a_run_that_finishes_instead_is_a_failure(tmp_path):
    """expect_error: a case that stops with the named error is an expected stop (recorded, not failed);
    one that stops with another error, or finishes, is a failure."""
    path = _write(tmp_path / "cases", """
[study]
summary = "x"
[[group]]
name = "g"
mechanism = "quick_return"
t_end = 0.05
expect_error = "RunBoundError"
sweep = { max_evaluations = [100000, 5] }
[[group]]
name = "other"
mechanism = "quick_return"
t_end = 0.05
expect_error = "SingularConfigurationError"
sweep = { max_evaluations = [5] }
""")
    cases = pl.load_case_list(path).cases
    store = pl.Store(tmp_path / "runs")
    out = pl.run_cases(cases, store, pl.InlineExecutor())
    assert list(out.expected) == ["demo/g [max_evaluations=5]"]
    assert out.expected["demo/g [max_evaluations=5]"].startswith("RunBoundError: quick_return: 5 evaluations reached")
    assert out.failed == {"demo/g [max_evaluations=100000]": "expected to stop with RunBoundError, but the run finished",
                          "demo/other [max_evaluations=5]": out.failed["demo/other [max_evaluations=5]"]}
    assert out.failed["demo/other [max_evaluations=5]"].startswith("RunBoundError")
    table = pl.failures_table([pl.load_case_list(path)], store).set_index("case")
    assert table.loc["demo/g [max_evaluations=5]", "expected"]
    assert not table.loc["demo/other [max_evaluations=5]", "expected"]
    # a second run takes the recorded expected stop as the case's result; the unexpected failure runs again
    again = pl.run_cases(cases, store, pl.InlineExecutor())
    assert again.expected == out.expected and (again.cached, again.computed) == (2, 0)   # the finished run, the record
    assert list(again.failed) == ["demo/other [max_evaluations=5]"]


@pytest.mark.parametrize("value", ["", 3, "not a name"])
def test_expect_error_must_name_an_error_class(tmp_path, value):
    if value == "":
        return  # the default: expected to finish
    path = _write(tmp_path / "cases", f"""
[study]
summary = "x"
[[group]]
name = "g"
mechanism = "quick_return"
t_end = 0.05
expect_error = {value!r}
""".replace("'", '"'))
    with pytest.raises(pl.CaseListError, match="expect_error .* must name an error class"):
        pl.load_case_list(path)


def test_progress_line_counts_done_remaining_failed(tiny, tmp_path, capsys):
    import io

    stream = io.StringIO()
    cases = pl.load_case_list(tiny / "sliding_mode.toml").cases[:2]
    pl.run_cases(cases, pl.Store(tmp_path / "runs"), pl.InlineExecutor(), title="tiny", stream=stream)
    last = stream.getvalue().strip().splitlines()[-1]
    assert "2/2 done, 0 remaining, 0 failed" in last and last.startswith("tiny (0 cached)")


# --- determinism and executors -----------------------------------------------------------------
def _tables(reports):
    return {p.name: p.read_bytes() for p in sorted((reports / "tables").glob("*.csv"))}


def test_tables_are_byte_identical_across_runs_and_executors(tiny, tmp_path):
    """Two cold runs (inline, and a 2-process pool) give byte-identical tables; timing lives apart."""
    a = pl.run_pipeline(tmp_path / "a", tmp_path / "cache_a", workers=1, folder=tiny, stream=open(os.devnull, "w"))
    b = pl.run_pipeline(tmp_path / "b", tmp_path / "cache_b", workers=2, folder=tiny, stream=open(os.devnull, "w"))
    assert a["studies"]["sliding_mode"]["computed"] == b["studies"]["sliding_mode"]["computed"] == 7
    ta, tb = _tables(tmp_path / "a"), _tables(tmp_path / "b")
    assert set(ta) == {"sliding_mode_runs.csv", "sliding_mode_claims.csv", "failed_cases.csv", "energy_balance.csv"}
    assert ta == tb
    assert (tmp_path / "a" / "timing" / "sliding_mode_timing.csv").exists()
    assert "cpu" not in ta["sliding_mode_runs.csv"].decode().splitlines()[0]


def test_dask_local_cluster_gives_the_same_tables(tiny, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        record = pl.run_pipeline(tmp_path / "dask", tmp_path / "cache_d", scheduler=client, folder=tiny,
                                 stream=open(os.devnull, "w"))
    assert record["studies"]["sliding_mode"]["computed"] == 7
    pl.run_pipeline(tmp_path / "local", tmp_path / "cache_l", workers=1, folder=tiny, stream=open(os.devnull, "w"))
    assert _tables(tmp_path / "dask") == _tables(tmp_path / "local")


def test_interrupted_run_resumes_without_recomputing(tiny, tmp_path):
    """SIGINT after the first saved result; the rerun reuses everything saved and completes (the saved runs in a
    cache root of its own, the generated code and compiled kernels the usual ones)."""
    env = {**os.environ, "STUDY_CACHE_DIR": str(linked_cache(tmp_path / "cache"))}
    cmd = [sys.executable, "-m", "study", "run", "--workers", "1", "--cases", str(tiny), "--out", str(tmp_path / "r")]
    # A shell's background job ignores SIGINT and its children inherit that; restore the default so
    # Python installs its KeyboardInterrupt handler in the child, as in an interactive Ctrl-C.
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    runs = tmp_path / "cache" / "runs"
    while not list(runs.glob("*.json")) and proc.poll() is None:   # until the first result, or the run's end
        time.sleep(0.01)
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=600)  # hang guard: SIGINT ends the run within a second; one ignoring it would hang
    saved = sorted(runs.glob("*.json"))
    assert 1 <= len(saved) < 7, f"interruption came too late to test resuming ({len(saved)} saved)"
    assert not list(runs.glob("*.tmp")), "a temporary file was left behind"
    for path in saved:  # every saved result is complete
        SimulationResult.load(path)
    done = subprocess.run(cmd, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert f"({len(saved)} cached)" in done.stderr and f"{7 - len(saved)}/{7 - len(saved)} done" in done.stderr
    assert len(list(runs.glob("*.json"))) == 7


def test_labels_with_dots_keep_cases_apart(tmp_path):
    """'0.05' and '0.025' in the readable file name must not truncate it at the dot (two files, not one)."""
    path = _write(tmp_path / "cases", """
[study]
summary = "x"
[[group]]
name = "g"
mechanism = "quick_return"
t_end = 0.1
sweep = { output_step = [0.05, 0.025] }
""")
    cases = pl.load_case_list(path).cases
    store = pl.Store(tmp_path / "runs")
    pl.run_cases(cases, store, pl.InlineExecutor())
    assert [len(store.load(c).t) for c in cases] == [3, 5]
    assert len(list((tmp_path / "runs").rglob("*.json"))) == 2


def test_equal_inputs_share_one_saved_result(tmp_path):
    """The same run in two groups (other names and labels) is computed once and found by both."""
    path = _write(tmp_path / "cases", """
[study]
summary = "x"
[[group]]
name = "a"
mechanism = "quick_return"
t_end = 0.05
options = { method = "none" }
[[group]]
name = "b"
mechanism = "quick_return"
t_end = 0.05
sweep = { method = ["none", "projection"] }
""")
    cases = pl.load_case_list(path).cases
    store = pl.Store(tmp_path / "runs")
    out = pl.run_cases(cases, store, pl.InlineExecutor())
    assert out.computed == 2 and all(store.has(c) for c in cases)


def test_skipped_summary_removes_its_stale_tables(tiny, tmp_path):
    """If a case a summary needs fails, the study's tables from an earlier run are removed, not kept."""
    quiet = open(os.devnull, "w")
    pl.run_pipeline(tmp_path / "r", tmp_path / "cache", workers=1, folder=tiny, stream=quiet)
    assert (tmp_path / "r" / "tables" / "sliding_mode_runs.csv").exists()
    broken = (tiny / "sliding_mode.toml").read_text().replace('method = "projection"',
                                                              'method = "projection", max_evaluations = 5')
    (tiny / "sliding_mode.toml").write_text(broken)  # the reference now fails
    record = pl.run_pipeline(tmp_path / "r", tmp_path / "cache", workers=1, folder=tiny, stream=quiet)
    assert "failed" in record["studies"]["sliding_mode"]["summary_error"]
    assert not (tmp_path / "r" / "tables" / "sliding_mode_runs.csv").exists()
    assert not (tmp_path / "r" / "timing" / "sliding_mode_timing.csv").exists()
    assert "sliding_mode/reference" in (tmp_path / "r" / "tables" / "failed_cases.csv").read_text()


def test_result_from_other_code_is_refused(tiny, tmp_path, monkeypatch):
    """A worker whose code differs (e.g. a stale Dask worker) must not save under this process's key."""
    real = execute._run_case_timed
    monkeypatch.setattr(execute, "_run_case_timed", lambda case: (*real(case)[:2], "0000000000000000"))
    cases = pl.load_case_list(tiny / "sliding_mode.toml").cases[:1]
    store = pl.Store(tmp_path / "runs")
    out = pl.run_cases(cases, store, pl.InlineExecutor())
    assert out.computed == 0 and "code version 0000000000000000" in out.failed[cases[0].name]
    assert not store.has(cases[0])


def test_at_references_read_the_reference_tables(tmp_path):
    """'@key' and '@table:key' stand for reference entries, in options, sweeps and t_end; unknown ones are named."""
    path = _write(tmp_path, """
[study]
summary = "x"
[[group]]
name = "g"
mechanism = "quick_return"
t_end = "@cross_validation:cut_horizon"
options = { rtol = "@reference_rtol" }
sweep = { atol = ["@reference_atol"], setting = [{ friction = "regularized", friction_eps = "@cross_validation:friction_eps" }] }
""")
    from study.reference_data import tolerance

    (case,) = pl.load_case_list(path).cases
    assert case.t_end == tolerance("cut_horizon", table="cross_validation")
    assert case.kwargs == {"rtol": tolerance("reference_rtol"), "atol": tolerance("reference_atol"),
                           "friction": "regularized", "friction_eps": tolerance("friction_eps", table="cross_validation")}
    _write(tmp_path, path.read_text().replace("@reference_rtol", "@no_such_entry"))
    with pytest.raises(pl.CaseListError, match="'@no_such_entry' names no reference entry"):
        pl.load_case_list(path)


@pytest.mark.parametrize("engine", ["inhouse", "exudyn"])
def test_case_key_covers_every_module_a_run_imports(engine):
    """A case's code version hashes the source of every module reachable from its engine's entry modules: imports
    inside functions (the run helpers in study/solver/run.py); not the report or the command line, and not the
    description modules, whose content the mechanism's fingerprint covers (next tests)."""
    from study.imports import dependencies
    from study.sources import PACKAGE_ROOT

    files = dependencies(*pl.ENTRY_MODULES[engine], exclude=pl.keys.DESCRIPTIONS)
    covered = {str(p.relative_to(PACKAGE_ROOT)) for p in files}
    assert {"model/derive.py", "model/joints.py", "solver/friction/contact.py", "mechanisms/__init__.py",
            "params.py", "pipeline/execute.py"} <= covered
    if engine == "inhouse":
        assert {"fast/loop.py", "solver/run.py", "solver/assemble.py"} <= covered
    else:
        assert "exudyn_models/translate.py" in covered
    assert not {p for p in covered if p.startswith(("report/", "studies/", "cli.py", "mechanisms/quick_return"))}


def _fresh_keys(monkeypatch):
    """Forget every mechanism and fingerprint this process has built (a new run after an edit)."""
    from study import mechanisms

    monkeypatch.setattr(mechanisms, "_MECHANISMS", {})
    mechanisms.named_mechanism.cache_clear()
    pl.keys.mechanism_hash.cache_clear()


def test_an_edited_description_recomputes_its_own_cases_only(monkeypatch):
    """A change to one mechanism's description changes the keys of its cases and of no other mechanism's."""
    import dataclasses

    from study import mechanisms

    cases = [pl.Case("s", "g", "inhouse", m, "seed", 1.0, (("method", "none"),)) for m in ("quick_return", "slider_crank")]
    before = [c.key() for c in cases]
    catalogue, entry = mechanisms.CATALOGUE, mechanisms.CATALOGUE["quick_return"]

    def edited(ps):
        d = entry.describe(ps)
        d.torque("extra", "crank", 0.5 * d.p.m1)
        return d

    monkeypatch.setattr(mechanisms, "CATALOGUE", {**catalogue, "quick_return": dataclasses.replace(entry, describe=edited)})
    _fresh_keys(monkeypatch)
    after = [c.key() for c in cases]
    assert after[0] != before[0] and after[1] == before[1]
    monkeypatch.setattr(mechanisms, "CATALOGUE", catalogue)
    _fresh_keys(monkeypatch)
    assert [c.key() for c in cases] == before


YOKE = Path(__file__).resolve().parents[1] / "examples" / "scotch_yoke"


def _yoke_list(folder, text=None):
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("scotch_yoke.py", "scotch_yoke.toml"):
        (folder / name).write_text((YOKE / name).read_text() if text is None or name.endswith(".toml") else text)
    return _write(folder, '[study]\nsummary = "x"\n[[group]]\nname = "yoke"\nmechanism = "scotch_yoke.py"\n'
                          't_end = 0.2\nsweep = { method = ["none", "projection"] }\n'
                          'options = { integrator = "DOP853", rtol = 1e-9, atol = 1e-11, output_step = 0.05 }\n')


def test_a_case_list_takes_a_users_mechanism_file(tmp_path, monkeypatch):
    """A case list names a user's file (relative to the list); the pipeline runs it as simulate runs the file's
    mechanism; the key follows the description's content, not the file's folder or its comments."""
    import numpy as np

    import study

    cases = pl.load_case_list(_yoke_list(tmp_path / "a")).cases
    assert cases[0].mechanism == str((tmp_path / "a" / "scotch_yoke.py").resolve())
    store = pl.Store(tmp_path / "runs")
    outcome = pl.run_cases(cases, store, pl.InlineExecutor())
    assert (outcome.computed, outcome.failed) == (2, {})
    direct = study.simulate(study.load_mechanism(tmp_path / "a" / "scotch_yoke.py"), t_end=0.2, method="projection",
                            integrator="DOP853", rtol=1e-9, atol=1e-11, output_step=0.05)
    np.testing.assert_array_equal(store.load(cases[1]).q, direct.q)

    source = (YOKE / "scotch_yoke.py").read_text()
    keys = [c.key() for c in cases]
    elsewhere = pl.load_case_list(_yoke_list(tmp_path / "b", "# a comment\n" + source)).cases
    _fresh_keys(monkeypatch)
    assert [c.key() for c in elsewhere] == keys
    heavier = source.replace("p.mc * p.rc ** 2 / 12", "p.mc * p.rc ** 2 / 3")
    assert heavier != source
    edited = pl.load_case_list(_yoke_list(tmp_path / "c", heavier)).cases
    _fresh_keys(monkeypatch)
    assert all(e.key() != k for e, k in zip(edited, keys))


def test_a_users_file_with_a_problem_is_named_by_the_case_list(tmp_path):
    path = _yoke_list(tmp_path, "def describe(ps):\n    raise RuntimeError('not written yet')\n")
    with pytest.raises(pl.CaseListError, match="demo.toml group 'yoke': mechanism = .*scotch_yoke.py.*not written yet"):
        pl.load_case_list(path)


def test_dependencies_follow_function_imports_and_parent_packages(tmp_path, monkeypatch):
    """A planted package: its entry imports a helper inside a function; the helper brings its package's __init__,
    and a module nothing imports is left out."""
    from study import imports

    pkg = tmp_path / "study"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "entry.py").write_text("def f():\n    from study.sub import helper\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "helper.py").write_text("X = 1\n")
    (pkg / "unused.py").write_text("Y = 1\n")
    monkeypatch.setattr(imports, "PACKAGE", pkg)
    imports.dependencies.cache_clear()
    try:
        found = {p.relative_to(pkg).as_posix() for p in imports.dependencies("study.entry")}
    finally:
        imports.dependencies.cache_clear()
    assert found == {"entry.py", "sub/__init__.py", "sub/helper.py"}
