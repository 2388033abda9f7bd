"""The pieces behind the reliability catalogue (test_reliability_catalogue.py), checked against independent values."""

import io
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
from scipy.integrate import RK45

import handwritten
from study import pipeline as pl
from study.cli import main
from study.progress import ProgressPrinter
from study.reference_data import tolerance
from study.run_arguments import check_run_size
from study.simulate import simulate
from study.solver.checks import SingularityMonitor, singularity_measure

from tiny_cases import TINY


def test_min_rtol_is_what_scipy_honours():
    """Below the limit scipy raises rtol (with a warning) to exactly the limit; at the limit it keeps it."""
    limit = tolerance("integrator_min_rtol")
    with pytest.warns(UserWarning):
        low = RK45(lambda t, y: -y, 0.0, [1.0], 1.0, rtol=limit / 10)
    assert low.rtol == pytest.approx(limit, rel=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert RK45(lambda t, y: -y, 0.0, [1.0], 1.0, rtol=limit * 1.001).rtol == limit * 1.001
    simulate(handwritten.cartesian_pendulum(), [1.0, 0.0], [0.0, 0.0], 0.01, rtol=limit * 1.001)  # accepted


@pytest.mark.parametrize("J,scale,expected", [
    ([[3.0, 4.0]], 1.0, 1.0),                      # one row: sigma_min = sigma_max = 5 > scale
    ([[3.0, 4.0]], 50.0, 0.1),                     # ... but small against the mechanism's scale
    ([[1.0, 0.0], [0.0, 1e-3]], 1.0, 1e-3),        # two rows: sigma_min / sigma_max
    ([[1.0, 2.0, 0.0], [2.0, 4.0, 0.0]], 1.0, 0.0),  # rank 1
])
def test_singularity_measure(J, scale, expected):
    assert singularity_measure(np.array(J), scale) == pytest.approx(expected, abs=1e-15)


def test_monitor_stops_at_and_across_a_singular_pose():
    eom = handwritten.cartesian_pendulum()  # Phi_q = q: singular only at the origin
    monitor = SingularityMonitor(eom, np.array([1.0, 0.0]))
    monitor.check(0.0, np.array([1.0, 0.0]))
    monitor.check(0.1, np.array([0.5, 0.1]))
    with pytest.raises(Exception, match="between t = 0.1 s and t = 0.2 s"):
        monitor.check(0.2, np.array([-0.5, -0.1]))  # the row q turned over: the step passed the origin
    with pytest.raises(Exception, match="at t = 0.3 s"):
        SingularityMonitor(eom, np.array([1.0, 0.0])).check(0.3, np.array([1e-9, 0.0]))


def test_checks_do_not_change_a_run():
    a = simulate("quick_return", t_end=0.2)
    b = simulate("quick_return", t_end=0.2, check=False)
    np.testing.assert_array_equal(a.q, b.q)
    assert a.stats["nfev"] == b.stats["nfev"]


def test_confirmed_large_run_is_not_refused():
    eom = handwritten.cartesian_pendulum()
    q0, qd0 = np.array([1.0, 0.0]), np.zeros(2)
    evaluations = 4 * 10**9 + 1
    with pytest.raises(ValueError, match="max_evaluations=4000000001"):
        check_run_size(eom, q0, qd0, 1e3, "RK4", 1e-6, 10.0, None, tolerance("max_evaluations"), 1e9)
    check_run_size(eom, q0, qd0, 1e3, "RK4", 1e-6, 10.0, None, evaluations, 1e9)  # confirmed: accepted


def test_progress_printer_prints_every_progress_steps_steps():
    """A line at every progress_steps-th step (a count: the same lines on any host), none before; each with the
    steps still to t_end at the pace of the last interval."""
    lines = []
    every = int(tolerance("progress_steps"))
    p = ProgressPrinter(2.0, say=lines.append)
    for k in range(1, 2 * every + 1):
        p(k * 0.5 / every)   # 0.5 s of the 2 s per interval
        if k < every:
            assert lines == []
    assert len(lines) == 2, lines
    assert lines[0].startswith(f"t = 0.5 of 2 s (25.0 %), {every} steps; ~{3 * every:.3g} steps to t_end")
    assert lines[1].startswith(f"t = 1 of 2 s (50.0 %), {2 * every} steps; ~{2 * every:.3g} steps to t_end")


def test_custom_case_folder_keeps_its_own_record(tmp_path, monkeypatch):
    monkeypatch.setenv("STUDY_CACHE_DIR", str(tmp_path / "cache"))
    folder = tmp_path / "cases"
    folder.mkdir()
    (folder / "sliding_mode.toml").write_text(TINY)
    out = tmp_path / "custom"
    assert main(["run", "--cases", str(folder), "--out", str(out), "--workers", "1"]) == 0
    assert (out / ".pipeline" / pl.PIPELINE_RECORD).exists()
    assert (out / "tables" / "failed_cases.csv").exists()
    assert not (tmp_path / "cache" / pl.PIPELINE_RECORD).exists()  # the default record is not touched
    assert not (tmp_path / "cache" / "tables").exists()


def test_summary_checked_before_any_case_runs(tmp_path):
    folder = tmp_path / "cases"
    folder.mkdir()
    (folder / "a.toml").write_text(TINY)
    (folder / "b.toml").write_text(TINY.replace("study.studies.sliding_mode", "study.studies.missing"))
    with pytest.raises(pl.CaseListError, match="b.toml"):
        pl.run_pipeline(tmp_path / "r", tmp_path / "cache", workers=1, folder=folder, stream=io.StringIO())
    assert not (tmp_path / "cache" / "runs").exists()  # a.toml's cases did not run either


def test_command_line_failure_is_one_line_in_a_real_process(tmp_path):
    """Outside pytest nothing captures warnings: a diverging run must still print one line (no traceback,
    no overflow warnings) and write nothing."""
    proc = subprocess.run([sys.executable, "-m", "study", "simulate", "quick_return", "--integrator", "RK4",
                           "--step", "0.1", "--t-end", "0.3", "--out", str(tmp_path / "run")],
                          capture_output=True, text=True, env={**os.environ, "STUDY_TRACEBACK": ""})
    assert proc.returncode == 1
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert "step h = 0.1 s is likely too large" in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_unreachable_scheduler_fails_at_the_probe_before_dask_is_asked(monkeypatch):
    """A refused --scheduler address fails at the TCP probe (bounded by scheduler_probe_timeout in
    reference/tolerances.toml), not after Dask's connect timeout: no Dask client is ever made (a count, zero, not
    the seconds it took)."""
    import distributed

    from study.pipeline import make_executor

    clients = []

    class Client:   # Dask's client, counted: the probe must refuse the address before one is made
        def __init__(self, *args, **kwargs):
            clients.append(args)
            raise AssertionError("a Dask client was made for an address the probe should have refused")

    monkeypatch.setattr(distributed, "Client", Client)
    with pytest.raises(OSError, match="'tcp://127.0.0.1:9' cannot be reached"):
        with make_executor(scheduler="tcp://127.0.0.1:9"):
            pass
    assert clients == []
