"""The command line: simulate writes a result and a one-line summary; bad input is named."""

import functools
import importlib
from pathlib import Path

import numpy as np
import pytest

from study import SimulationResult
from study.cli import main
from study.reference_data import tolerance


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
    (["--t-end", "-1"], "--t-end = -1.0 must be finite and > 0"),
    (["--variant", "nope"], "unknown variant (valid choices: seed, smooth_cutting, guide_friction, slot_friction)"),
])
def test_simulate_bad_input(tmp_path, capsys, args, message):
    code, err = _refused(capsys, ["simulate", "quick_return", *args, "--out", str(tmp_path / "x")])
    assert code == 2 and message in err and not (tmp_path / "x.csv").exists()


def _refused(capsys, args):
    """Exit code and stderr of the command line in this process (tests/test_reliability.py runs a real one)."""
    try:
        code = main(args)
    except SystemExit as exc:   # argparse's own refusals
        code = exc.code
    return code, capsys.readouterr().err


# --- friction, variant, backend, bench ---------------------------------------------------------
def _run(tmp_path, capsys, name, *args):
    out = tmp_path / name
    assert main(["simulate", "slider_crank", "--t-end", "0.5", *args, "--out", str(out)]) == 0
    return SimulationResult.load(out.with_suffix(".csv")), capsys.readouterr().out.strip()


def test_simulate_applies_the_parameter_sets_friction_by_default(tmp_path, capsys):
    default, line = _run(tmp_path, capsys, "default")
    exact, exact_line = _run(tmp_path, capsys, "exact", "--friction", "exact")
    none, none_line = _run(tmp_path, capsys, "none", "--friction", "none")
    assert "friction exact [parameter set's default]" in line
    assert "friction exact:" in exact_line and "friction none (asked: the friction of guide left out):" in none_line
    assert default.meta["friction"] == exact.meta["friction"] == "exact" and none.meta["friction"] is None
    assert (default.meta["friction_default"], exact.meta["friction_default"]) == (True, False)
    assert none.meta["friction_left_out"] == ["guide"] and default.meta["friction_left_out"] == []
    # the default run is the exact run, sample for sample, and not the frictionless one
    np.testing.assert_array_equal(default.q, exact.q)
    np.testing.assert_array_equal(default.forces["friction_guide"], exact.forces["friction_guide"])
    assert "friction_guide" not in none.forces
    assert np.max(np.abs(default.q - none.q)) > tolerance("cli_friction_effect")
    # the seed's guide holds the slider (it sticks within milliseconds): friction balances it
    assert default.forces["stick_guide"][-1] == 1


def test_simulate_regularized_friction_options(tmp_path, capsys):
    wide, line = _run(tmp_path, capsys, "wide", "--friction", "regularized", "--friction-eps", "1e-2",
                      "--friction-sgn", "arctan")
    narrow, _ = _run(tmp_path, capsys, "narrow", "--friction", "regularized", "--friction-eps", "1e-4")
    assert "friction regularized (arctan, eps = 0.01 m/s)" in line
    assert (wide.meta["friction_eps"], wide.meta["friction_sgn"]) == (1e-2, "arctan")
    assert (narrow.meta["friction_eps"], narrow.meta["friction_sgn"]) == (1e-4, "tanh")
    assert np.max(np.abs(wide.q - narrow.q)) > 0  # the width reaches the law


def test_simulate_quick_return_seed_has_no_friction_by_default(tmp_path, capsys):
    out = tmp_path / "qr"
    assert main(["simulate", "quick_return", "--variant", "smooth_cutting", "--t-end", "0.05", "--out", str(out)]) == 0
    assert "friction none [parameter set's default]" in capsys.readouterr().out
    r = SimulationResult.load(out.with_suffix(".csv"))
    assert r.meta["variant"] == "smooth_cutting" and r.meta["friction"] is None


def test_simulate_passes_variant_backend_and_friction(monkeypatch, tmp_path):
    """--variant and its alias --case, --backend and the friction options reach study.simulate."""
    module = importlib.import_module("study.simulate")  # not the function the package re-exports by that name
    seen = []

    @functools.wraps(module.simulate)  # keeps the signature, from which the CLI reads its defaults
    def fake(mechanism, **kwargs):
        seen.append(kwargs)
        raise ValueError("stop here")

    monkeypatch.setattr(module, "simulate", fake)
    base = ["simulate", "slider_crank", "--out", str(tmp_path / "x")]
    assert main(base + ["--variant", "slip_then_stick", "--backend", "compiled", "--friction", "sign",
                        "--friction-eps", "2e-3"]) == 2
    assert main(base + ["--case", "sustained_sliding", "--friction", "none"]) == 2
    assert main(base + ["--case", "sustained_sliding"]) == 2
    assert [(k["variant"], k["backend"], k["friction"], k["friction_eps"]) for k in seen] == [
        ("slip_then_stick", "compiled", "sign", 2e-3), ("sustained_sliding", "reference", "none", None),
        ("sustained_sliding", "reference", "default", None)]


@pytest.mark.parametrize("args,message", [
    (["--friction", "magic"], "invalid choice: 'magic'"),
    (["--backend", "gpu"], "invalid choice: 'gpu'"),
    (["--friction", "regularized", "--friction-eps", "0"], "--friction-eps = 0.0 must be finite and > 0"),
])
def test_simulate_bad_friction_or_backend(tmp_path, capsys, args, message):
    code, err = _refused(capsys, ["simulate", "slider_crank", "--t-end", "0.1", *args, "--out", str(tmp_path / "x")])
    assert code == 2 and message in err and not (tmp_path / "x.csv").exists()


def test_every_command_help_shows_an_example(capsys):
    from study.cli import EXAMPLES, build_parser

    commands = set(build_parser()._subparsers._group_actions[0].choices)
    assert commands == set(EXAMPLES) and "bench" in commands
    for command, example in EXAMPLES.items():
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = capsys.readouterr().out
        assert f"example:\n  {example}" in text
        assert example.split()[3] == command  # the example runs this command


def test_bench_subcommand_runs_the_benchmark(monkeypatch, tmp_path):
    """`study bench` parses the benchmark's own options and runs it (python -m study.bench does the same)."""
    from study.bench import command

    seen = []
    monkeypatch.setattr(command, "run", lambda args: seen.append(args) or 0)
    assert main(["bench", "--quick", "--skip-compile", "--out", str(tmp_path)]) == 0
    assert command.main(["--quick", "--out", str(tmp_path)]) == 0
    assert [(a.quick, a.skip_compile, a.out) for a in seen] == [(True, True, tmp_path), (True, False, tmp_path)]


# --- describe ----------------------------------------------------------------------------------

def test_describe_prints_the_four_bar_and_a_consistent_state(capsys):
    """Checked against the four-bar's hand geometry, not against the description code: three bodies
    hung from two ground pivots by a chain of four revolute joints leave exactly one joint (B, the
    coupler-rocker joint, last in the chain) as the loop closure; the printed q(0) must close the
    loop a e(q1) + b e(q2) = d e_x + c e(q3) to the round-off of its 10 printed digits."""
    from study.params import load_parameters

    assert main(["describe", "four_bar"]) == 0
    out = capsys.readouterr().out
    for body in ("crank", "coupler", "rocker"):
        assert f"  {body}: mass" in out
    assert "  B: revolute, coupler.B = rocker.B [cut, rows B_x, B_y]" in out
    assert sum(line.endswith("[tree]") for line in out.splitlines()) == 3
    assert "gravity g along -y" in out
    q = np.array(eval(next(l for l in out.splitlines() if l.strip().startswith("q(0)")).split("=")[1].split("]")[0] + "]"))
    v = load_parameters("four_bar").values
    gap = v.a * np.exp(1j * q[0]) + v.b * np.exp(1j * q[1]) - v.d - v.c * np.exp(1j * q[2])
    assert abs(gap) < 10 * tolerance("describe_printed_digits") * (v.a + v.b + v.c + v.d)


def test_describe_lists_variants_with_their_changes(capsys):
    assert main(["describe", "quick_return", "--variant", "guide_friction"]) == 0
    out = capsys.readouterr().out
    assert "guide_friction: study's own case" in out and "mu_guide = 0.1" in out
    assert "ram_guide: prismatic" in out and "Coulomb contact mu_s = mu_guide" in out
    assert "switching function" not in out          # the smooth law has tanh ramps, no switches
    assert main(["describe", "quick_return"]) == 0   # the seed's on/off law switches on the ram's speed
    assert "switching function v_D: vx(ram.D)" in capsys.readouterr().out


def test_describe_unknown_mechanism_names_the_choices(capsys):
    code, err = _refused(capsys, ["describe", "pendulum"])
    assert code == 2 and "unknown mechanism 'pendulum'" in err and "four_bar" in err


def test_describe_takes_a_users_mechanism_file(capsys):
    """A user's file (describe(ps) and a parameter file beside it) is described like a study mechanism."""
    path = Path(__file__).resolve().parents[1] / "examples" / "scotch_yoke" / "scotch_yoke.py"
    assert main(["describe", str(path)]) == 0
    out = capsys.readouterr().out
    assert "rail: prismatic" in out and "by the travel x" in out and "q(0)" in out
