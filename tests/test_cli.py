"""The command line: simulate writes a result and a one-line summary; bad input is named."""

import subprocess
import sys

import pytest

from study import SimulationResult
from study.cli import main


def test_simulate_writes_result(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", "quick_return", "--case", "smooth_cutting", "--method", "baumgarte",
                 "--option", "omega=20", "--t-end", "0.2", "--out", str(out)]) == 0
    line = capsys.readouterr().out.strip()
    assert "max|Phi|" in line and "energy error" in line and "CPU" in line
    r = SimulationResult.load(out.with_suffix(".csv"))
    assert r.meta["omega"] == 20.0 and r.meta["variant"] == "smooth_cutting" and r.t[-1] == pytest.approx(0.2)


@pytest.mark.parametrize("args,message", [
    (["--method", "magic"], "invalid choice: 'magic'"),
    (["--integrator", "Euler"], "invalid choice: 'Euler'"),
    (["--rtol", "0"], "rtol = 0.0 must be finite and > 0"),
    (["--t-end", "-1"], "t_end = -1.0 must be finite and > 0"),
    (["--case", "nope"], "unknown variant (valid choices: seed, smooth_cutting, guide_friction)"),
])
def test_simulate_bad_input(tmp_path, args, message):
    proc = subprocess.run([sys.executable, "-m", "study", "simulate", "quick_return", *args, "--out",
                           str(tmp_path / "x")], capture_output=True, text=True)
    assert proc.returncode != 0
    assert message in proc.stderr
