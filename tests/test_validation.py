"""``study validate``: a user's mechanism (the Scotch yoke example, which no file of study/ names) through every
in-house method and Exudyn, through the public API and the command line.

Independent check: Exudyn's own solvers, on a model generated from the same description but integrated by Exudyn's
formulation, must converge to the in-house reference at their order 2 (``min_order``, reference/cross_validation.toml);
the yoke's translation coordinate is recovered from Exudyn's body poses (study.exudyn_models.translate), so a mapping
error there shows as an O(1) deviation that does not shrink with h.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import study
from study.cli import main
from study.mechanisms import mechanism, named_mechanism
from study.reference_data import tolerance
from study.results import SimulationResult

YOKE = Path(__file__).resolve().parents[1] / "examples" / "scotch_yoke" / "scotch_yoke.py"


@pytest.fixture(scope="module")
def yoke_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("yoke")
    tables = study.validate(study.load_mechanism(YOKE), study.ValidationSettings(t_end=0.5), out, say=lambda _: None)
    return out, tables


def test_exudyn_converges_to_the_in_house_reference_at_second_order(yoke_report):
    _, tables = yoke_report
    orders = tables["exudyn_orders"]
    assert set(orders["solver"]) == {"index3", "index2"} and set(orders["quantity"]) == {"q", "qd"}
    assert orders["above_error_floor"].all()
    assert (orders["min_order"] >= tolerance("min_order", table="cross_validation")).all(), orders.to_string()
    assert (tables["exudyn_convergence"]["error"] == "").all()


def test_every_method_follows_the_reference_within_its_tolerance(yoke_report):
    """Each everyday run (rtol 1e-8) and the reference (rtol 1e-12) stay within the adaptive runs' global error bound
    of the exact motion, so within twice the everyday bound of each other. The sliding mode is left out: its sgn term
    at the default gains moves this motion by ~1e-7 rad, a property of the law (tests/test_examples.py)."""
    out, tables = yoke_report
    runs = tables["in_house"].set_index("run")
    assert set(runs.index) == {"reference", *(f"method {m}" for m in ("none", "baumgarte", "sliding_mode",
                                                                       "projection"))}
    assert (runs["error"] == "").all()
    q_scale = np.abs(SimulationResult.load(out / "runs" / "inhouse_reference").q).max()
    bound = 2 * tolerance("adaptive_global_error_factor") * 1e-8 * q_scale
    for method in ("none", "baumgarte", "projection"):
        assert runs.loc[f"method {method}", "max_abs_dq_vs_reference"] <= bound, method


def test_report_and_figures_are_written_from_saved_runs(yoke_report):
    out, tables = yoke_report
    text = (out / "report.md").read_text()
    for heading in ("Consistent initial state", "In-house methods", "Exudyn", "Joint reactions", "Figures"):
        assert f"## {heading}" in text
    for figure in ("trajectories", "constraint_violation", "exudyn_convergence"):
        assert (out / "figures" / f"{figure}.png").stat().st_size > 10_000
    saved = pd.read_csv(out / "tables" / "exudyn_convergence.csv", keep_default_na=False)
    assert len(saved) == 6
    reactions = tables["reactions"]
    assert set(reactions["reaction"]) >= {"joint_O_x", "joint_O_y", "joint_A_x", "joint_A_y", "joint_rail_n",
                                          "joint_slot_n"}


def test_command_line_names_what_is_wrong(tmp_path, capsys):
    assert main(["validate", str(tmp_path / "missing.py"), "--out", str(tmp_path / "o")]) == 2
    assert "missing.py" in capsys.readouterr().err
    script = tmp_path / "nothing.py"
    script.write_text("x = 1\n")
    assert main(["validate", str(script), "--out", str(tmp_path / "o")]) == 2
    assert "describe(ps)" in capsys.readouterr().err
    assert main(["validate", str(YOKE), "--t-end", "0.333", "--out", str(tmp_path / "o")]) == 2
    assert "t_end = 0.333" in capsys.readouterr().err


def test_pin_friction_goes_through_every_treatment_and_exudyn(tmp_path):
    """A mechanism whose only friction is in a pin (the study's pin_pendulum) is validated with friction on: every
    treatment in-house, and Exudyn at the regularized law against the regularized reference (not frictionless).
    The bar starts at rest, so the tanh band is crossed at once: at the default width 1e-3 rad/s that takes ~2e-4 s,
    inside Exudyn's first step, and its observed orders are 1.03-1.06 (measured); at 0.2 rad/s the steps resolve it."""
    mech = mechanism(study.load_parameters("pin_pendulum"))
    tables = study.validate(mech, study.ValidationSettings(t_end=0.3, friction_eps=0.2), tmp_path, say=lambda _: None)
    runs = tables["in_house"].set_index("run")
    assert {"friction exact", "friction sign (RK4)"} <= set(runs.index) and (runs["error"] == "").all()
    reference = SimulationResult.load(tmp_path / "runs" / "inhouse_reference")
    assert reference.meta["friction"] == "regularized" and reference.energies["work_friction_pin"][-1] < 0
    assert (tables["exudyn_convergence"]["error"] == "").all()
    assert (tables["exudyn_orders"]["min_order"] >= tolerance("min_order", table="cross_validation")).all()


CART = Path(__file__).resolve().parents[1] / "examples" / "cart_pendulum" / "cart_pendulum.py"


def _cart(tmp_path, **settings):
    lines = []
    tables = study.validate(study.load_mechanism(CART), study.ValidationSettings(t_end=0.5, levels=2, **settings),
                            tmp_path, say=lines.append)
    return tables["exudyn_orders"].set_index(["solver", "quantity"]), [line for line in lines if "observed" in line]


def test_an_order_below_its_bound_with_regularized_friction_names_the_width_and_the_remedy(tmp_path):
    """The cart with rail friction at the default width (1e-3 m/s): Exudyn's velocity orders fall below min_order
    (measured 1.32 and 1.32 at h = 2e-3, 1e-3 s over 0.5 s) while the positions keep order 2, and the summary names
    the likely cause, the width unresolved near sticking, with the remedy, instead of a generic finding."""
    orders, lines = _cart(tmp_path)
    min_order = tolerance("min_order", table="cross_validation")
    assert (orders.loc[(slice(None), "qd"), "min_order"] < min_order).all(), orders
    assert (orders.loc[(slice(None), "q"), "min_order"] >= min_order).all(), orders
    below = [line for line in lines if "below" in line]
    assert len(below) == 2 and all(", qd:" in line for line in below), lines
    for line in below:
        assert "friction_eps = 0.001 m/s" in line and "not resolved" in line and "near sticking" in line
        assert "a larger friction_eps (--friction-eps)" in line and "a smaller --h" in line
        assert "a finding" not in line
    assert (tmp_path / "report.md").read_text().count("Remedy: a larger friction_eps") == 2


@pytest.mark.slow
def test_the_remedy_named_for_an_unresolved_width_restores_second_order(tmp_path):
    """The remedy the summary names works: at friction_eps = 0.05 m/s the same steps resolve the law, and every
    observed order is second order again (measured 2.000 for q and qd on both solvers)."""
    orders, lines = _cart(tmp_path, friction_eps=0.05)
    assert (orders["min_order"] >= tolerance("min_order", table="cross_validation")).all(), orders
    assert not any("below" in line for line in lines), lines


def test_an_order_below_its_bound_without_friction_stays_a_finding():
    """Without friction the width is no cause: the generic finding, with no friction remedy. With friction the width
    is named in the unit of its rate: m/s for a planar slider and a spatial prismatic joint, rad/s for a spatial
    revolute joint (friction_carriage has one of each)."""
    from study.validation_report import order_lines

    orders = pd.DataFrame([{"solver": "index3", "quantity": "qd", "orders": "1.2", "above_error_floor": True,
                            "meets_min_order": False}])
    (line,) = order_lines(orders, study.load_mechanism(YOKE), 1e-3)
    assert "a finding" in line and "friction_eps" not in line
    (line,) = order_lines(orders, study.load_mechanism(CART), 1e-3)
    assert "friction_eps = 0.001 m/s)" in line and "a finding" not in line
    (line,) = order_lines(orders, named_mechanism("friction_carriage"), 1e-3)
    assert "friction_eps = 0.001 m/s or rad/s)" in line and "a finding" not in line


# --- the validation is a case list run through the pipeline ----------------------------------------------------------
PENDULUM = Path(__file__).resolve().parents[1] / "examples" / "pendulum" / "pendulum.py"


def test_the_case_list_is_the_pipelines_keyed_by_the_mechanisms_content():
    """Every run is a pipeline case whose options are its engine's run specification; the key of a Mechanism passed
    in from Python follows its content (an equal one loaded again: the same keys; another initial state: none)."""
    import importlib.util

    from study.engines import Exudyn, InHouse, spec_from_dict
    from study.pipeline import Case
    from study.validation import validation_cases

    settings = study.ValidationSettings(t_end=0.5)
    cases = validation_cases(study.load_mechanism(YOKE), settings)
    assert all(isinstance(c, Case) for c in cases)
    assert [c.engine for c in cases] == ["inhouse"] * 5 + ["exudyn"] * 6
    specs = [spec_from_dict({"engine": c.engine, **c.kwargs}) for c in cases]
    assert all(isinstance(s, InHouse) for s in specs[:5]) and all(isinstance(s, Exudyn) for s in specs[5:])
    assert [s.h for s in specs[5:]] == settings.steps * 2
    keys = [c.key() for c in cases]
    assert len(set(keys)) == len(cases)
    assert [c.key() for c in validation_cases(study.load_mechanism(YOKE), settings)] == keys
    spec = importlib.util.spec_from_file_location("example_pendulum", PENDULUM)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    moved = study.Mechanism(example.d, q0={"th": 1.1}, qd0={"th": 0.0})
    first, second = (validation_cases(m, settings) for m in (example.pendulum, moved))
    assert not {c.key() for c in first} & {c.key() for c in second}


def test_a_second_validation_of_the_same_mechanism_reads_its_runs_back(tmp_path, monkeypatch):
    """The runs are saved in the pipeline's store: a second validation of an equal mechanism (loaded again) at the
    same settings runs nothing and writes the same tables."""
    monkeypatch.setenv("STUDY_CACHE_DIR", str(tmp_path / "cache"))
    settings = study.ValidationSettings(t_end=0.1)
    first, second = [], []
    before = study.validate(study.load_mechanism(YOKE), settings, tmp_path / "a", say=first.append)
    after = study.validate(study.load_mechanism(YOKE), settings, tmp_path / "b", say=second.append)
    assert "[1/5] in-house reference" in first and not any("re-used" in line for line in first)
    assert not any(line.startswith("[") for line in second), second
    assert any(line.startswith(f"11 of 11 runs re-used from {tmp_path / 'cache' / 'runs'}") for line in second)
    assert len(list((tmp_path / "cache" / "runs").glob("*.json"))) == 11
    for name, table in before.items():
        pd.testing.assert_frame_equal(table, after[name])
    assert (tmp_path / "b" / "runs" / "inhouse_reference.csv").read_bytes() == \
        (tmp_path / "a" / "runs" / "inhouse_reference.csv").read_bytes()


def test_a_failed_run_is_a_row_with_its_error_and_a_failed_reference_stops(tmp_path, monkeypatch):
    """A run that stops is recorded by the pipeline and shown as a row with its error; the reference, which every
    other run is compared with, must succeed."""
    from study.errors import SimulationError
    from study.pipeline import execute

    real = execute.run_case

    def failing(group):
        def run_case(case, progress=None):
            if case.group == group:
                raise SimulationError(f"{group} stopped on purpose")
            return real(case, progress)
        return run_case

    settings = study.ValidationSettings(t_end=0.1)
    monkeypatch.setenv("STUDY_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(execute, "run_case", failing("method none"))
    tables = study.validate(study.load_mechanism(YOKE), settings, tmp_path / "a", say=lambda _: None)
    runs = tables["in_house"].set_index("run")
    assert runs.loc["method none", "error"] == "SimulationError: method none stopped on purpose"
    assert (runs.drop(index="method none")["error"] == "").all()
    monkeypatch.setenv("STUDY_CACHE_DIR", str(tmp_path / "other_cache"))   # nothing saved: the reference runs
    monkeypatch.setattr(execute, "run_case", failing("reference"))
    with pytest.raises(SimulationError, match="the in-house reference run failed.*reference stopped on purpose"):
        study.validate(study.load_mechanism(YOKE), settings, tmp_path / "b", say=lambda _: None)
