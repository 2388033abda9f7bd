"""A catalogue of bad inputs and faults: each gives one clear error, and nothing wrong is saved or reused.

Every entry is a setup (which may write files: a saved result, a case list) that returns the action to
try. The runner snapshots the files under the test's folder, runs the action, and asserts

- the outcome: the exception type (library) or the exit code with a single stderr line and no
  traceback (command line);
- the message: every listed fragment, which name the offending value and the rule it breaks;
- the files: unchanged by the action (nothing written), unless the entry expects a write (a damaged
  result recomputed), which its own ``then`` check examines (the damaged file is not reused).

Numbers the checks rely on are read from reference/tolerances.toml; expected values are computed
independently (scipy's own tolerance handling, hand-typed equations in tests/handwritten.py, file sizes).
"""

from __future__ import annotations

import dataclasses
import io
import json
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

import handwritten
from study import pipeline as pl
from study.cli import main
from study.errors import (EquationsError, NonFiniteError, ResultIntegrityError, RunBoundError, RunTooLargeError,
                          SingularConfigurationError)
from study.integrity import RegeneratedWarning, ensure_generated, write_checked
from study.model.eom import SlidingContact
from study.params import load_parameters
from study.results import SimulationResult
from study.simulate import simulate
from study.solver.checks import validate_equations
from study.model.initial_state import InitialConditionError, consistent_initial_conditions


@dataclass
class Entry:
    name: str
    group: str
    setup: Callable  # (tmp_path) -> action; action() raises, or returns argv for the command line
    fragments: tuple[str, ...]
    error: type | None = None  # library entries: the exception type
    exit: int | None = None    # command-line entries: the exit code
    writes: bool = False       # the action may write (then ``then`` checks what)
    then: Callable | None = None
    verdict: str = "good"      # how well the failure is handled: good / weak (see reason)
    reason: str = ""


CATALOGUE: list[Entry] = []


def entry(group, *fragments, error=None, exit=None, writes=False, then=None, verdict="good", reason=""):
    def deco(setup):
        CATALOGUE.append(Entry(setup.__name__, group, setup, fragments, error, exit, writes, then, verdict, reason))
        return setup
    return deco


# --- shared small inputs ---------------------------------------------------------------------------
PENDULUM_Q0, PENDULUM_QD0 = [1.0, 0.0], [0.0, 0.0]  # on the unit circle, at rest: consistent by hand


def pendulum(**changes):
    return dataclasses.replace(handwritten.cartesian_pendulum(), **changes)


def slider_crank_equal_links():
    """The hand-typed slider-crank with l2 = l1: Phi_q = 0 at q = (pi/2, 0), where the two branches meet."""
    v = load_parameters("slider_crank").values
    return handwritten.slider_crank(dataclasses.replace(v, l2=v.l1))


ONE_CASE = """
[study]
summary = "study.studies.sliding_mode"
[[group]]
name = "reference"
mechanism = "quick_return"
t_end = 0.1
options = { integrator = "RK45", rtol = 1e-6, atol = 1e-8, output_step = 0.05 }
"""


def _one_case_store(tmp):
    folder = tmp / "cases"
    folder.mkdir()
    (folder / "one.toml").write_text(ONE_CASE)
    case = pl.load_case_list(folder / "one.toml").cases[0]
    store = pl.Store(tmp / "cache" / "runs")
    pl.run_cases([case], store, pl.InlineExecutor(), stream=io.StringIO())
    return case, store


def _rerun(case, store, tmp):
    log = tmp / "log.txt"

    def action():
        with open(log, "w") as stream:
            summary = pl.run_cases([case], store, pl.InlineExecutor(), stream=stream)
        if summary.rejected and summary.computed == 1:  # reported and recomputed, never reused
            raise ResultIntegrityError(log.read_text())
        raise AssertionError(f"the damaged result was reused: {summary}")
    return action


def _recomputed_matches_fresh(tmp):
    store = pl.Store(tmp / "cache" / "runs")
    case = pl.load_case_list(tmp / "cases" / "one.toml").cases[0]
    reloaded = store.load(case)  # verified
    fresh = pl.run_case(case)
    assert len(reloaded.t) == len(fresh.t) == 3  # 0, 0.05, 0.1 s
    np.testing.assert_array_equal(reloaded.q, fresh.q)


# === 1. saved results, generated code and tables are verified before reuse =========================
def _saved(tmp):
    r = simulate(handwritten.cartesian_pendulum(), PENDULUM_Q0, PENDULUM_QD0, 0.05, output_step=0.01)
    r.save(tmp / "run")
    return tmp / "run.csv", tmp / "run.json"


@entry("saved results", "run.csv", "data rows", "6 recorded", error=ResultIntegrityError)
def csv_cut_to_fewer_rows(tmp):
    csv, _ = _saved(tmp)
    lines = csv.read_text().splitlines(keepends=True)
    csv.write_text("".join(lines[:3]))
    return lambda: SimulationResult.load(tmp / "run")


@entry("saved results", "run.csv", "SHA-256", "changed after it was saved", error=ResultIntegrityError)
def csv_cut_mid_line(tmp):
    csv, _ = _saved(tmp)
    text = csv.read_text()
    csv.write_text(text[:-10] + "\n")  # the last line loses digits, the row count stays
    return lambda: SimulationResult.load(tmp / "run")


@entry("saved results", "run.csv", "SHA-256", error=ResultIntegrityError)
def csv_one_digit_changed(tmp):
    csv, _ = _saved(tmp)
    text = csv.read_text()
    i = text.index("\n") + 3  # a digit of the first sample
    csv.write_text(text[:i] + ("7" if text[i] != "7" else "8") + text[i + 1:])
    return lambda: SimulationResult.load(tmp / "run")


@entry("saved results", "run.json", "not valid JSON", error=ResultIntegrityError)
def json_garbage(tmp):
    _, js = _saved(tmp)
    js.write_text("{ this is not json")
    return lambda: SimulationResult.load(tmp / "run")


@entry("saved results", "run.json", "expected a JSON object", error=ResultIntegrityError)
def json_not_an_object(tmp):
    _, js = _saved(tmp)
    js.write_text("[1, 2, 3]")
    return lambda: SimulationResult.load(tmp / "run")


@entry("saved results", "run.csv", "no row count and checksum recorded", error=ResultIntegrityError)
def json_without_checksum(tmp):
    _, js = _saved(tmp)
    side = json.loads(js.read_text())
    del side["csv"]
    js.write_text(json.dumps(side))
    return lambda: SimulationResult.load(tmp / "run")


@entry("saved results", "run.csv", "missing", error=ResultIntegrityError)
def csv_deleted(tmp):
    csv, _ = _saved(tmp)
    csv.unlink()
    return lambda: SimulationResult.load(tmp / "run")


@entry("saved results", "non-finite", "lam1", "t = 0.02", error=NonFiniteError)
def nan_result_is_not_saved(tmp):
    r = simulate(handwritten.cartesian_pendulum(), PENDULUM_Q0, PENDULUM_QD0, 0.05, output_step=0.01)
    r.lam[2, 0] = np.nan
    return lambda: r.save(tmp / "nan_run")


@entry("pipeline reuse", "saved result rejected, recomputing", "data rows", error=ResultIntegrityError,
       writes=True, then=_recomputed_matches_fresh)
def store_csv_truncated_is_recomputed(tmp):
    case, store = _one_case_store(tmp)
    csv = store.file(case, ".csv")
    csv.write_text("".join(csv.read_text().splitlines(keepends=True)[:2]))
    return _rerun(case, store, tmp)


@entry("pipeline reuse", "saved result rejected, recomputing", "not valid JSON", error=ResultIntegrityError,
       writes=True, then=_recomputed_matches_fresh)
def store_json_garbage_is_recomputed(tmp):
    case, store = _one_case_store(tmp)
    store.file(case, ".json").write_text("garbage")
    return _rerun(case, store, tmp)


@entry("pipeline reuse", "saved result rejected, recomputing", "SHA-256", error=ResultIntegrityError,
       writes=True, then=_recomputed_matches_fresh)
def store_csv_edited_is_recomputed(tmp):
    case, store = _one_case_store(tmp)
    csv = store.file(case, ".csv")
    csv.write_text(csv.read_text().replace("0.05", "0.06", 1))
    return _rerun(case, store, tmp)


@entry("pipeline reuse", "is not used", "data rows", error=pl.CorruptResult)
def store_load_refuses_damaged_result(tmp):
    case, store = _one_case_store(tmp)
    csv = store.file(case, ".csv")
    csv.write_text(csv.read_text().splitlines(keepends=True)[0])
    return lambda: store.load(case)


def _summary_tables(tmp):
    folder = tmp / "cases"
    folder.mkdir()
    (folder / "one.toml").write_text(ONE_CASE)
    record = tmp / "record"
    pl.run_pipeline(tmp / "reports", tmp / "cache", workers=1, folder=folder, stream=io.StringIO(),
                    record_root=record)
    return record, sorted((tmp / "reports" / "tables").glob("sliding_mode*.csv"))


@entry("pipeline reuse", "sliding_mode_", "data rows", "recorded when it was saved", error=ResultIntegrityError)
def table_cut_is_not_read(tmp):
    record, tables = _summary_tables(tmp)
    path = tables[0]
    path.write_text(path.read_text() + "1,2,3\n")  # a row added after the pipeline wrote it
    return lambda: pl.read_table(path, record)


@entry("pipeline reuse", "no pipeline record lists this table", error=ResultIntegrityError)
def table_not_written_by_the_pipeline(tmp):
    record, _ = _summary_tables(tmp)
    stray = tmp / "reports" / "tables" / "stray.csv"
    stray.write_text("a,b\n1,2\n")
    return lambda: pl.read_table(stray, record)


def _generated_rejected(tmp):
    path = tmp / "gen" / "module.py"
    write_checked(path, "COEFFICIENT = 1.25\n")
    path.write_text("COEFFICIENT = 1.26\n")  # one coefficient changed after generation

    def action():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ensure_generated(path, lambda: "COEFFICIENT = 1.25\n")
        assert path.read_text() == "COEFFICIENT = 1.25\n"  # regenerated, the edit is gone
        raise ResultIntegrityError(" | ".join(str(w.message) for w in caught if w.category is RegeneratedWarning))
    return action


entry("generated code", "module.py", "regenerated", "content changed", error=ResultIntegrityError,
      writes=True)(_generated_rejected)


@entry("generated code", "module.py", "no checksum entry", error=ResultIntegrityError)
def generated_code_without_checksum(tmp):
    path = tmp / "gen" / "module.py"
    path.parent.mkdir()
    path.write_text("COEFFICIENT = 1.25\n")  # from a version without checksums
    from study.integrity import verify_checked
    return lambda: verify_checked(path)


@entry("pipeline reuse", "unreadable failure record", error=LookupError)
def failure_record_garbage(tmp):
    case, store = _one_case_store(tmp)
    store.discard(case)
    store.file(case, ".failed.json").write_text("{oops")

    def action():
        raise LookupError(store.failure(case)["error"])
    return action


# === 2. non-finite values are errors ================================================================
@entry("non-finite", "t = 0 s", "forces", "start of the run", error=NonFiniteError)
def nan_forces_from_t0_rk45(tmp):
    eom = pendulum(forces=lambda t, q, qd: np.array([np.nan, -9.81]))
    return lambda: simulate(eom, PENDULUM_Q0, PENDULUM_QD0, 1.0, check=False)


@entry("non-finite", "forces(0, q0, qd0) is not finite", error=EquationsError)
def nan_forces_from_t0_checked(tmp):
    eom = pendulum(forces=lambda t, q, qd: np.array([np.nan, -9.81]))
    return lambda: simulate(eom, PENDULUM_Q0, PENDULUM_QD0, 1.0)


@entry("non-finite", "forces(t, q, qd)", "t = 0.05", error=NonFiniteError)
def nan_forces_after_a_while(tmp):
    eom = pendulum(forces=lambda t, q, qd: np.array([0.0, -9.81 if t < 0.05 else np.inf]))
    return lambda: simulate(eom, PENDULUM_Q0, PENDULUM_QD0, 0.2)


@entry("non-finite", "mass(q)", error=NonFiniteError)
def nan_mass_mid_run(tmp):
    eom = pendulum(mass=lambda q: np.eye(2) if q[1] > -0.01 else np.full((2, 2), np.nan))
    return lambda: simulate(eom, PENDULUM_Q0, PENDULUM_QD0, 0.5)


@entry("non-finite", "gamma(q, qd)", error=NonFiniteError)
def nan_gamma_mid_run(tmp):
    eom = pendulum(gamma=lambda q, qd: np.array([-(qd @ qd) if q[1] > -0.01 else np.nan]))
    return lambda: simulate(eom, PENDULUM_Q0, PENDULUM_QD0, 0.5)


@entry("non-finite", "step h = 0.1 s is likely too large", error=NonFiniteError)
def rk4_step_far_too_large(tmp):
    return lambda: simulate("quick_return", integrator="RK4", step=0.1, t_end=0.3)


# A step that starts on the far side of a switching surface flips the mode there
# (study.laws.events.crossing_finder) rather than stopping with "cannot be located": with h = 0.5 s
# the run goes on and diverges, which the non-finite guard names with the step.
@entry("non-finite", "step h = 0.5 s is likely too large", error=NonFiniteError)
def rk4_step_over_a_switch(tmp):
    return lambda: simulate("quick_return", integrator="RK4", step=0.5, t_end=1.0)


@entry("non-finite", "q0 = [nan  0.] must be finite", error=ValueError)
def nan_initial_state(tmp):
    return lambda: simulate(handwritten.cartesian_pendulum(), [np.nan, 0.0], PENDULUM_QD0, 0.1)


def _failure_recorded_not_cached(tmp):
    store = pl.Store(tmp / "cache" / "runs")
    case = pl.load_case_list(tmp / "cases" / "bad.toml").cases[0]
    assert not store.has(case) and not store.file(case, ".json").exists()
    assert "NonFiniteError" in store.failure(case)["error"]


@entry("non-finite", "NonFiniteError", "step h = 0.1 s", error=RuntimeError, writes=True,
       then=_failure_recorded_not_cached)
def nan_case_is_a_failure_not_a_success(tmp):
    folder = tmp / "cases"
    folder.mkdir()
    (folder / "bad.toml").write_text(ONE_CASE.replace('integrator = "RK45", rtol = 1e-6, atol = 1e-8',
                                                      'integrator = "RK4", step = 0.1').replace("0.1\n", "0.3\n", 1))
    case = pl.load_case_list(folder / "bad.toml").cases[0]

    def action():
        out = pl.run_cases([case], pl.Store(tmp / "cache" / "runs"), pl.InlineExecutor(),
                           stream=io.StringIO())
        raise RuntimeError(next(iter(out.failed.values())))
    return action


# === 3. a user's equations and initial state ========================================================
@entry("user equations", "mass(q0) is not symmetric", "mass_symmetry", error=EquationsError)
def mass_not_symmetric(tmp):
    return lambda: simulate(pendulum(mass=lambda q: np.array([[1.0, 0.5], [0.0, 1.0]])), PENDULUM_Q0, PENDULUM_QD0)


@entry("user equations", "mass(q0) is not positive-definite", "smallest eigenvalue -1", error=EquationsError)
def mass_indefinite(tmp):
    return lambda: simulate(pendulum(mass=lambda q: np.diag([1.0, -1.0])), PENDULUM_Q0, PENDULUM_QD0)


@entry("user equations", "mass(q0) is not positive-definite", "smallest eigenvalue 0", error=EquationsError)
def mass_singular(tmp):
    return lambda: simulate(pendulum(mass=lambda q: np.diag([1.0, 0.0])), PENDULUM_Q0, PENDULUM_QD0)


@entry("user equations", "phi_q(q0) is not the Jacobian of phi", "entry (0, 0) is 2", "gives 1",
       "equations_check", error=EquationsError)
def phi_q_twice_too_large(tmp):
    return lambda: simulate(pendulum(phi_q=lambda q: 2 * q.reshape(1, 2)), PENDULUM_Q0, PENDULUM_QD0)


@entry("user equations", "phi_q(q0) is not the Jacobian of phi", error=EquationsError)
def phi_q_columns_swapped(tmp):
    return lambda: simulate(pendulum(phi_q=lambda q: q[::-1].reshape(1, 2).copy()), PENDULUM_Q0, PENDULUM_QD0)


@entry("user equations", "gamma(q0, qd) at qd0", "-(Phi_q qd)_q qd gives [-1]", error=EquationsError)
def gamma_wrong_sign(tmp):
    return lambda: simulate(pendulum(gamma=lambda q, qd: np.array([qd @ qd])), PENDULUM_Q0, [0.0, 1.0])


@entry("user equations", "gamma(q0, qd) at a unit test velocity", error=EquationsError)
def gamma_wrong_seen_at_rest(tmp):
    # at qd0 = 0 both sides are 0; the unit test velocity shows the missing factor
    return lambda: simulate(pendulum(gamma=lambda q, qd: np.array([-0.5 * (qd @ qd)])), PENDULUM_Q0, PENDULUM_QD0)


@entry("user equations", "q0 = [2, 0] is off the constraints", "initial_state_residual",
       "study.model.initial_state", error=EquationsError)
def pendulum_at_twice_its_length(tmp):
    return lambda: simulate(handwritten.cartesian_pendulum(), [2.0, 0.0], PENDULUM_QD0)


@entry("user equations", "qd0 = [1, 0] violates the velocity constraints", "study.model.initial_state",
       error=EquationsError)
def pendulum_velocity_along_the_rod(tmp):
    return lambda: simulate(handwritten.cartesian_pendulum(), PENDULUM_Q0, [1.0, 0.0])


@entry("user equations", "off the constraints", "max|Phi(q0)| = 5.2", "study.model.initial_state", error=EquationsError)
def slider_crank_printed_state(tmp):
    ps = load_parameters("slider_crank")
    return lambda: simulate("slider_crank", list(ps.initial.printed_q), list(ps.initial.printed_qd), 0.1)


@entry("user equations", "mass(q0) raised ZeroDivisionError", error=EquationsError)
def mass_callable_raises(tmp):
    def mass(q):
        raise ZeroDivisionError("a user's bug")
    return lambda: validate_equations(pendulum(mass=mass), np.array(PENDULUM_Q0), np.array(PENDULUM_QD0))


@entry("user equations", "phi(q0) is not finite", error=EquationsError)
def phi_returns_nan(tmp):
    return lambda: validate_equations(pendulum(phi=lambda q: np.array([np.nan])), np.array(PENDULUM_Q0),
                                      np.array(PENDULUM_QD0))


@entry("user equations", "failed 3 check(s)", "mass(q0) is not symmetric", "phi_q(q0) is not the Jacobian", "gamma",
       error=EquationsError)
def every_problem_in_one_error(tmp):
    eom = pendulum(mass=lambda q: np.array([[1.0, 0.5], [0.0, 1.0]]), phi_q=lambda q: 3 * q.reshape(1, 2))
    return lambda: validate_equations(eom, np.array(PENDULUM_Q0), np.array([0.0, 0.0]))


# === 4. singular configurations =====================================================================
@entry("singular", "singular configuration at t = 0 s", "q = [1.5708, 0]", "singular_ratio",
       error=SingularConfigurationError)
def equal_links_at_the_branch_point(tmp):
    return lambda: simulate(slider_crank_equal_links(), [np.pi / 2, 0.0], [0.001, 0.0], 0.1)


@entry("singular", "singular configuration at t = 0 s", error=SingularConfigurationError)
def equal_links_partitioned(tmp):
    return lambda: simulate(slider_crank_equal_links(), [np.pi / 2, 0.0], [0.001, 0.0], 0.1,
                            acceleration_solver="partitioned")


@entry("singular", "singular configuration at t = 0 s", error=SingularConfigurationError)
def equal_links_orthonormal_unchecked(tmp):
    return lambda: simulate(slider_crank_equal_links(), [np.pi / 2, 0.0], [0.001, 0.0], 0.1,
                            acceleration_solver="orthonormal", check=False)


@entry("singular", "singular configuration", "not Painleve", error=SingularConfigurationError)
def equal_links_with_friction_is_not_painleve(tmp):
    eom = slider_crank_equal_links()
    contact = SlidingContact("slider", 0, tangent_jacobian=lambda q: np.array([-np.sin(q[0]), 0.0]),
                             tangent_bias=lambda q, qd: 0.0, mu_static=0.25, mu_kinetic=0.25)
    eom = dataclasses.replace(eom, contacts=(contact,))

    def action():
        try:
            simulate(eom, [np.pi / 2, 0.0], [0.001, 0.0], 0.1, friction="exact")
        except SingularConfigurationError as exc:
            raise SingularConfigurationError(f"{exc} (not Painleve)") from exc
    return action


@entry("singular", "singular configuration between t =", "rows turned over", error=SingularConfigurationError)
def run_through_the_branch_point(tmp):
    # on the isosceles branch q2 = pi - 2 q1, moving towards q1 = pi/2 (consistent: Phi_q qd = 0 by hand)
    return lambda: simulate(slider_crank_equal_links(), [np.pi / 2 - 0.05, 0.1], [1.0, -2.0], 0.2)


@entry("singular", "Phi_q[:, [1]] is singular", "sigma_min(Phi_v) / sigma_max(Phi_q)", "singular_ratio",
       error=InitialConditionError)
def dead_centre_of_the_dependent_coordinate(tmp):
    v = load_parameters("slider_crank").values
    eom = handwritten.slider_crank(dataclasses.replace(v, l1=2.0, l2=1.0))  # l1 sin q1 = l2 at q1 = pi/6
    return lambda: consistent_initial_conditions(eom, [np.pi / 6, np.pi / 3], [0], [1.0])


# === 5. every run is bounded ========================================================================
@entry("bounds", "max_evaluations = 50", "evaluations reached", error=RunBoundError)
def evaluation_bound(tmp):
    return lambda: simulate(handwritten.cartesian_pendulum(), PENDULUM_Q0, PENDULUM_QD0, 10.0, max_evaluations=50)


@entry("bounds", "steps in a row below min_step = 0.4", error=RunBoundError)
def min_step_bound(tmp):
    return lambda: simulate(handwritten.cartesian_pendulum(), PENDULUM_Q0, PENDULUM_QD0, 10.0, min_step=0.4)


@entry("bounds", "RK4 with step = 1e-06 s", "evaluations", "of CPU", "max_evaluations=", error=RunTooLargeError)
def rk4_fixed_step_obviously_huge(tmp):
    return lambda: simulate("quick_return", integrator="RK4", step=1e-6, t_end=1e3, output_step=10.0)


@entry("bounds", "t_end = 1e+12 s", "1e+14 samples", "87 PiB", "max_output_bytes", error=RunTooLargeError)
def t_end_1e12(tmp):
    return lambda: simulate("quick_return", t_end=1e12)


@entry("bounds", "max_evaluations = 0 must be finite and > 0", error=ValueError)
def zero_evaluation_bound(tmp):
    return lambda: simulate("quick_return", t_end=0.1, max_evaluations=0)


@entry("bounds", "min_step = -1.0 must be finite and > 0", error=ValueError)
def negative_min_step(tmp):
    return lambda: simulate("quick_return", t_end=0.1, min_step=-1.0)


@entry("bounds", "rtol = 1e-16", "below what scipy's RK45 honours", error=ValueError)
def rtol_below_what_scipy_honours(tmp):
    return lambda: simulate("quick_return", t_end=0.1, rtol=1e-16)


@entry("bounds", "rtol = 1e-15", "DOP853", error=ValueError)
def rtol_below_what_dop853_honours(tmp):
    return lambda: simulate("quick_return", t_end=0.1, rtol=1e-15, integrator="DOP853")


# === 6. the command line: one line, non-zero exit, nothing written ==================================
def _cli(*argv):
    return lambda: list(argv)


def _out(tmp):
    return str(tmp / "cli_out" / "run")


@entry("command line", "--option 'omega'", "KEY=VALUE", exit=2)
def cli_option_without_value(tmp):
    return _cli("simulate", "quick_return", "--option", "omega", "--t-end", "0.1", "--out", _out(tmp))


@entry("command line", "rtol = 1e-16", "honours", exit=2)
def cli_rtol_too_small(tmp):
    return _cli("simulate", "quick_return", "--rtol", "1e-16", "--t-end", "0.1", "--out", _out(tmp))


@entry("command line", "--rtol/--atol do not apply to --integrator RK4", exit=2)
def cli_rtol_with_rk4(tmp):
    return _cli("simulate", "quick_return", "--integrator", "RK4", "--step", "1e-3", "--rtol", "1e-6",
                "--t-end", "0.1", "--out", _out(tmp))


@entry("command line", "t_end = 1e+12 s", "max_output_bytes", exit=2)
def cli_t_end_1e12(tmp):
    return _cli("simulate", "quick_return", "--t-end", "1e12", "--out", _out(tmp))


@entry("command line", "RK4 with step = 1e-09 s", "--max-evaluations", exit=2)
def cli_rk4_huge(tmp):
    return _cli("simulate", "quick_return", "--integrator", "RK4", "--step", "1e-9", "--t-end", "20",
                "--out", _out(tmp))


@entry("command line", "the run failed", "step h = 0.1 s is likely too large", exit=1)
def cli_rk4_diverges(tmp):
    return _cli("simulate", "quick_return", "--integrator", "RK4", "--step", "0.1", "--t-end", "0.3",
                "--out", _out(tmp))


@entry("command line", "the run failed", "max_evaluations = 20", exit=1)
def cli_evaluation_bound(tmp):
    return _cli("simulate", "quick_return", "--max-evaluations", "20", "--t-end", "0.5", "--out", _out(tmp))


@entry("command line", "unknown variant", "valid choices", exit=2)
def cli_unknown_variant_is_named(tmp):
    return _cli("simulate", "slider_crank", "--case", "nope", "--t-end", "0.1", "--out", _out(tmp))


@entry("command line", "--out", "is a file, not a folder", exit=2)
def cli_out_under_a_file(tmp):
    (tmp / "afile").write_text("x")
    return _cli("simulate", "quick_return", "--t-end", "0.1", "--out", str(tmp / "afile" / "run"))


@entry("command line", "--out /proc/", "cannot write in /proc", exit=2)
def cli_out_not_writable(tmp):
    return _cli("simulate", "quick_return", "--t-end", "0.1", "--out", "/proc/study_run")


@entry("command line", "--cases", "does not exist", exit=2)
def cli_run_missing_case_folder(tmp):
    return _cli("run", "--cases", str(tmp / "nope"), "--out", str(tmp / "reports_custom"), "--workers", "1")


@entry("command line", "holds no case lists", exit=2)
def cli_run_empty_case_folder(tmp):
    (tmp / "empty").mkdir()
    return _cli("run", "--cases", str(tmp / "empty"), "--out", str(tmp / "reports_custom"), "--workers", "1")


@entry("command line", "is not the default case folder", "give it its own --out", exit=2)
def cli_run_custom_cases_without_out(tmp):
    (tmp / "cases").mkdir()
    (tmp / "cases" / "one.toml").write_text(ONE_CASE)
    return _cli("run", "--cases", str(tmp / "cases"), "--workers", "1")


@entry("command line", "summary = 'study.studies.nope'", "cannot be imported", exit=2)
def cli_run_summary_module_missing(tmp):
    (tmp / "cases").mkdir()
    (tmp / "cases" / "one.toml").write_text(ONE_CASE.replace("study.studies.sliding_mode", "study.studies.nope"))
    return _cli("run", "--cases", str(tmp / "cases"), "--out", str(tmp / "reports_custom"), "--workers", "1")


@entry("command line", "summary = 'study.results'", "has no function summarize", exit=2)
def cli_run_summary_module_without_summarize(tmp):
    (tmp / "cases").mkdir()
    (tmp / "cases" / "one.toml").write_text(ONE_CASE.replace("study.studies.sliding_mode", "study.results"))
    return _cli("run", "--cases", str(tmp / "cases"), "--out", str(tmp / "reports_custom"), "--workers", "1")


@entry("command line", "no case list for ['nope']", exit=2)
def cli_run_unknown_study(tmp):
    (tmp / "cases").mkdir()
    (tmp / "cases" / "one.toml").write_text(ONE_CASE)
    return _cli("run", "nope", "--cases", str(tmp / "cases"), "--out", str(tmp / "reports_custom"))


@entry("command line", "workers = 0 must be an integer >= 1", exit=2)
def cli_run_zero_workers(tmp):
    (tmp / "cases").mkdir()
    (tmp / "cases" / "one.toml").write_text(ONE_CASE)
    return _cli("run", "--cases", str(tmp / "cases"), "--out", str(tmp / "reports_custom"), "--workers", "0")


@entry("command line", "scheduler 'tcp://127.0.0.1:9' cannot be reached", exit=2)
def cli_run_unreachable_scheduler(tmp):
    (tmp / "cases").mkdir()
    (tmp / "cases" / "one.toml").write_text(ONE_CASE)
    return _cli("run", "--cases", str(tmp / "cases"), "--out", str(tmp / "reports_custom"),
                "--scheduler", "tcp://127.0.0.1:9")


@entry("command line", "run.toml", "t_end = -1.0 must be finite and > 0", exit=2)
def cli_run_bad_case_list(tmp):
    (tmp / "cases").mkdir()
    (tmp / "cases" / "run.toml").write_text(ONE_CASE.replace("t_end = 0.1", "t_end = -1.0"))
    return _cli("run", "--cases", str(tmp / "cases"), "--out", str(tmp / "reports_custom"))


# === runner ===========================================================================================
def _files(root: Path) -> dict[str, tuple]:
    """Every file under root with its size and time, except generated-code caches (filled on first use)."""
    return {str(p.relative_to(root)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in root.rglob("*") if p.is_file() and not p.relative_to(root).parts[:2] == ("cache", "codegen")}


@pytest.fixture
def isolated(tmp_path, monkeypatch):
    """The test's folder as cache root and working directory (nothing may land in the repository)."""
    monkeypatch.setenv("STUDY_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    yield tmp_path


@pytest.mark.parametrize("e", CATALOGUE, ids=[e.name for e in CATALOGUE])
def test_catalogue(e, isolated, capsys):
    tmp = isolated
    action = e.setup(tmp)
    before = _files(tmp)
    capsys.readouterr()
    if e.exit is not None:
        code = main(action())
        err = capsys.readouterr().err.strip()
        assert code == e.exit, err
        assert "Traceback" not in err and len(err.splitlines()) == 1, err
        message = err
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # overflow on the way to a non-finite value
            with pytest.raises(e.error) as info:
                action()
        message = str(info.value)
    for fragment in e.fragments:
        assert fragment in message, f"{fragment!r} not in: {message}"
    if e.writes:
        if e.then is not None:
            e.then(tmp)
    else:
        after = _files(tmp)
        assert after == before, f"files written or changed: {sorted(set(after.items()) ^ set(before.items()))}"


def test_catalogue_size_and_verdicts():
    """At least 60 distinct entries, each with a verdict of good or weak, and every weak one with its reason."""
    assert len(CATALOGUE) >= 60, len(CATALOGUE)
    assert len({e.name for e in CATALOGUE}) == len(CATALOGUE)
    assert {e.verdict for e in CATALOGUE} <= {"good", "weak"}  # no entry is silently wrong, stale or hanging
    assert all(e.reason for e in CATALOGUE if e.verdict != "good")
