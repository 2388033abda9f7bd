"""Friction between moving parts: the quick-return with Coulomb friction in its rocker's slot, and the pipeline's
energy-balance check of every friction run.

* the check (study.pipeline.summaries.energy_check) passes a real run and flags it once its work column is perturbed
  or its dissipation made to drop; the pipeline records the flag, the ``run`` command and ``make verify`` fail on it;
* the exact law's runs on the two backends agree within the adaptive runs' global error;
* the slot's sliding reverses exactly at the kinematic dead centres of the hand kinematics
  (r^2 = l1^2 + h1^2 + 2 l1 h1 sin q1 of the crank pin A from the rocker pivot P: dr/dq1 = 0 at cos q1 = 0), where the
  block cannot be held;
* a stuck block holds only while the force needed to hold it stays within mu_s |N|: from rest at one pose it stays
  stuck under gravity alone and slides under a drive torque, as the held forces of a run with mu_s = 100 (always held,
  the held forces do not depend on mu) predict;
* the study's summary and report section on a short horizon.
"""

from __future__ import annotations

from functools import lru_cache

import dataclasses
import io
import math

import numpy as np
import pandas as pd
import pytest

import study.mechanisms as mechanisms
from study.model import Mechanism
from study.params import load_parameters
from study.pipeline import CASES_DIR, InlineExecutor, Store, find, find_one, load_case_list, run_cases, write_tables
from study.pipeline.execute import run_case
from study.pipeline.summaries import energy_check, energy_flags
from study.reference_data import tolerance
from study.report.context import ReportContext
from study.simulate import simulate
from study.model.initial_state import consistent_initial_conditions
from study.studies import moving_friction as mf

CONTACT = "block_on_rocker"
SHORT = 0.35    # [s] past the first dead centre (0.312 s); a whole number of every Exudyn step of the list


def case_list():
    return load_case_list(CASES_DIR / "moving_friction.toml")


def slot_mechanism(**values) -> Mechanism:
    ps = load_parameters("quick_return", "slot_friction")
    if values:
        ps = dataclasses.replace(ps, values=dataclasses.replace(ps.values, **values))
    return Mechanism(mechanisms.description(ps), ps)


@pytest.fixture(scope="module")
def regularized_run():
    return simulate(slot_mechanism(), t_end=0.4, integrator="DOP853", rtol=1e-10, atol=1e-12, method="projection",
                    friction="regularized", friction_eps=1e-3, backend="reference")


@lru_cache(maxsize=None)
def exact_run(backend: str):
    """(case, result) of the slot friction's exact run on ``backend``, as its case list states it."""
    (case,) = [c for c in find(case_list().cases, group="quick_return/slot_friction:exact")
               if c.kwargs["backend"] == backend]
    return case, run_case(case)


# --- the energy-balance check --------------------------------------------------------------------------------
def test_case_list_runs_the_slot_friction_set_with_every_role():
    cl = case_list()
    assert cl.summary == "study.studies.moving_friction" and cl.section == "moving_friction"
    groups = mf.sets(cl.cases)
    assert list(groups) == ["quick_return/slot_friction", "pin_pendulum/seed", "slider_crank_pins/sustained_sliding"]
    for key, roles in groups.items():
        assert {r: len(c) for r, c in roles.items()} == {"exact": 2, "regularized": 1, "exudyn": 3, "eps": 3}, key
    assert load_parameters("quick_return", "slot_friction").values.mu_slot == 0.15


def _with_work(result, name, values):
    return dataclasses.replace(result, energies={**result.energies, name: values})


def test_energy_check_passes_a_run_and_flags_a_perturbed_work_column(regularized_run):
    r = regularized_run
    ok = energy_check(r)
    assert ok["residual_within_bound"] == "True" and ok["dissipation_nondecreasing"] and not ok["flagged"]
    assert ok["dissipated_J"] > 0 and ok["residual_J"] < ok["residual_bound_J"]
    # a work column off by ten times the bound at the end (a wrong load or friction power): the residual fails
    work = r.energies[f"work_friction_{CONTACT}"]
    ramp = 10 * ok["residual_bound_J"] * (r.t / r.t[-1])
    bad = energy_check(_with_work(r, f"work_friction_{CONTACT}", work - ramp))
    assert bad["residual_within_bound"] == "False" and bad["flagged"]
    assert bad["residual_J"] == pytest.approx(10 * ok["residual_bound_J"], rel=0.01)
    # friction doing positive work between two samples: the dissipation drops
    k = len(r.t) // 2
    positive = work.copy()
    positive[k] = work[k - 1] + 10 * ok["dissipation_bound_J"]
    drop = energy_check(_with_work(r, f"work_friction_{CONTACT}", positive))
    assert not drop["dissipation_nondecreasing"] and drop["flagged"]
    table = pd.DataFrame([{"case": "good", **ok}, {"case": "bad", **bad}, {"case": "drop", **drop}])
    flags = energy_flags(table)
    assert set(flags) == {"bad", "drop"}
    assert "above its bound" in flags["bad"] and "dissipation drops" in flags["drop"]


def test_fixed_step_and_printed_start_are_recorded_not_judged(regularized_run):
    meta = {**regularized_run.meta, "rtol": None, "atol": None, "step": 1e-3}
    fixed = dataclasses.replace(regularized_run, meta=meta)
    check = energy_check(fixed)
    assert check["residual_within_bound"] == "not judged" and math.isnan(check["residual_bound_J"])
    assert energy_check(regularized_run, {"initial": "printed"})["residual_within_bound"] == "not judged"


TINY = """
[study]
description = "tiny"
summary = "study.studies.moving_friction"

[[group]]
name = "quick_return/slot_friction:regularized"
mechanism = "quick_return"
variant = "slot_friction"
t_end = 0.05

[group.options]
integrator = "DOP853"
rtol = 1e-10
atol = 1e-12
friction = "regularized"
friction_eps = 1e-3
backend = "compiled"
"""


def test_the_pipeline_records_the_flag_and_run_and_verify_fail_on_it(tmp_path, monkeypatch):
    from study import cli, cli_pipeline, verify
    from study.pipeline import run_pipeline

    folder = tmp_path / "cases"
    folder.mkdir()
    (folder / "tiny.toml").write_text(TINY)
    cache, out = tmp_path / "cache", tmp_path / "out"
    record = run_pipeline(out, cache, workers=1, folder=folder, stream=io.StringIO())
    table = pd.read_csv(out / "tables" / "energy_balance.csv")
    assert len(table) == 1 and not table["flagged"].iloc[0] and record["energy_balance_flags"] == {}
    # the tiny study only: the snapshot holds no errata or initial-conditions table, so regenerating those (a
    # minute of sympy) would be compared with nothing
    ok, _ = verify.verify_tables(out / "tables", cache, studies=["tiny"], workers=1, cases_dir=folder,
                                 stream=io.StringIO())
    assert ok

    load = Store.load

    def perturbed(self, case):   # the saved run with a wrong drive work (the case is cached: nothing reruns)
        r = load(self, case)
        scale = energy_check(r)["residual_bound_J"]
        return _with_work(r, "work_drive", r.energies["work_drive"] + 100 * scale * r.t / r.t[-1])

    monkeypatch.setattr(Store, "load", perturbed)
    stream = io.StringIO()
    record = run_pipeline(out, cache, workers=1, folder=folder, stream=stream)
    (name,) = record["energy_balance_flags"]
    assert name.startswith("tiny/quick_return/slot_friction:regularized")
    assert f"ENERGY BALANCE of {name}" in stream.getvalue()
    assert bool(pd.read_csv(out / "tables" / "energy_balance.csv")["flagged"].iloc[0])
    stream = io.StringIO()
    ok, _ = verify.verify_tables(out / "tables", cache, studies=["tiny"], workers=1, cases_dir=folder, stream=stream)
    assert not ok and "FAILED energy balance" in stream.getvalue()
    monkeypatch.setattr("study.model.compile.cache_dir", lambda: cache)
    args = cli.build_parser().parse_args(["run", "--cases", str(folder), "--out", str(out), "--workers", "1"])
    assert cli_pipeline.run(args) == 1


# --- the exact law: backends, dead centres, the static limit -------------------------------------------------
def test_backends_agree_on_the_slot_friction_exact_run():
    (case, compiled), (_, reference) = exact_run("compiled"), exact_run("reference")
    assert np.array_equal(compiled.t, reference.t)
    factor = 2 * tolerance("adaptive_global_error_factor") * case.kwargs["rtol"]   # each within its global error
    for field in ("q", "qd"):
        a, b = getattr(compiled, field), getattr(reference, field)
        assert np.abs(a - b).max() <= factor * np.abs(b).max(), field
    a, b = mf.transitions(compiled), mf.transitions(reference)
    kinds = [(x["from"], x["to"]) for x in a]
    assert kinds == [(x["from"], x["to"]) for x in b] == [("slip-", "slip+"), ("slip+", "slip-")]
    for x, y in zip(a, b):
        assert abs(x["t"] - y["t"]) <= tolerance("event_time_agreement_adaptive")


def test_the_slot_reverses_at_the_kinematic_dead_centres_and_is_never_held():
    """Each stop of the block's sliding lies where the hand kinematics put dr/dq1 = 0 (q1 = pi/2 + k pi), and the
    force needed to hold it there exceeds the static limit: the sliding reverses."""
    case, r = exact_run("reference")
    stops = mf.transitions(r)
    assert len(stops) == 2
    for k, x in enumerate(stops):
        assert x["from"] != "stick" and x["to"] != "stick"
        assert not abs(x["f_required"]) <= x["limit"]   # inf, or a limit exceeded: not holdable
        upto = simulate(slot_mechanism(), t_end=x["t"], integrator="DOP853", rtol=case.kwargs["rtol"],
                        atol=case.kwargs["atol"], method="projection", friction="exact", backend="reference",
                        output_step=x["t"])
        q1 = upto.q[-1, 0]
        bound = tolerance("adaptive_global_error_factor") * case.kwargs["rtol"] * abs(q1)
        assert abs(q1 - (1.5 + k) * math.pi) <= bound, (q1, (1.5 + k) * math.pi)


def _at_rest(mech, q1):
    eom = mech.equations()
    guess = np.array(mech.initial_state().q, dtype=float)
    guess[0] = q1
    state = consistent_initial_conditions(eom, guess, [0], [0.0])
    return state.q, state.qd


@pytest.mark.parametrize("drive", [0.0, 2000.0])
def test_stuck_only_while_the_needed_force_is_within_the_static_limit(drive):
    """From rest at q1 = 4 rad: the held forces (friction the slot must supply, normal force) come from a run with
    mu_s = mu_k = 100, always held; the run with the set's mu = 0.15 must stay stuck exactly when they satisfy
    |f_req| <= mu |N|, and while it is stuck its friction force is within mu |N| at every sample."""
    mu = load_parameters("quick_return", "slot_friction").values.mu_slot
    runs = {}
    for coefficient in (100.0, mu):
        mech = slot_mechanism(M=drive, mu_slot=coefficient)
        q0, qd0 = _at_rest(mech, 4.0)
        runs[coefficient] = simulate(mech, q0, qd0, t_end=0.2, integrator="DOP853", rtol=1e-10, atol=1e-12,
                                     friction="exact", output_step=0.01)
    held = runs[100.0]
    assert (held.forces[f"stick_{CONTACT}"] == 1.0).all()
    f_req, normal = held.forces[f"friction_{CONTACT}"][0], held.forces[f"normal_{CONTACT}"][0]
    holds = abs(f_req) <= mu * abs(normal)
    r = runs[mu]
    stuck = r.forces[f"stick_{CONTACT}"] == 1.0
    assert holds == (drive == 0.0)      # the two drives lie on either side of the limit at this pose
    still = tolerance("adaptive_global_error_factor") * 1e-10 * np.abs(r.q).max()   # held: q moves by its error only
    if holds:
        assert stuck.all() and np.abs(r.q - r.q[0]).max() <= still
    else:
        assert not stuck.any() and abs(r.q[-1, 0] - r.q[0, 0]) > still
    force, limit = np.abs(r.forces[f"friction_{CONTACT}"]), mu * np.abs(r.forces[f"normal_{CONTACT}"])
    assert (force[stuck] <= limit[stuck] * (1 + tolerance("round_off"))).all()


# --- the study's tables and report section ---------------------------------------------------------------
def test_summary_and_section_on_a_short_horizon(tmp_path):
    cases = [dataclasses.replace(c, t_end=SHORT) for c in case_list().cases]
    store = Store(tmp_path / "runs")
    summary = run_cases(cases, store, InlineExecutor(), title="tiny", stream=io.StringIO())
    assert not summary.failed, summary.failed
    tables = mf.summarize(cases, store.load)
    assert set(tables) == {"moving_friction_runs", "moving_friction_backends", "moving_friction_phases",
                           "moving_friction_forces", "moving_friction_exudyn", "moving_friction_eps",
                           "moving_friction_timing"}
    for name, frame in tables.items():
        assert len(frame), name
        if not name.endswith("_timing"):
            assert not [c for c in frame.columns if "cpu" in c.lower()], name
    runs = tables["moving_friction_runs"]
    assert runs["residual_within_bound"].isin(["True", "not judged"]).all()
    assert runs["dissipation_nondecreasing"].all()
    assert tables["moving_friction_backends"]["agree"].all()
    phases = tables["moving_friction_phases"]
    phases = phases[phases["set"] == "quick_return/slot_friction"]
    assert list(phases["phase"]) == ["slip-", "slip+"] and phases["started_by"].iloc[1] == "came to rest, not holdable"
    exudyn = tables["moving_friction_exudyn"]
    assert len(exudyn) == 3 * exudyn["set"].nunique()
    # the slot's orders on this horizon (the pins' are asserted by tests/test_exudyn_pin_friction.py; here the
    # pendulum's torque is pre-asymptotic at the coarsest pair, order 1.60 at 0.35 s)
    exudyn = exudyn[exudyn["set"] == "quick_return/slot_friction"]
    orders = exudyn[["order_dq", "order_dqd", "order_dF_friction", "order_dN"]].to_numpy()[1:]
    assert (orders >= tolerance("min_order", table="cross_validation")).all(), orders
    assert tables["moving_friction_eps"]["shrinking"].all()
    reports = tmp_path / "reports"
    write_tables(tables, reports, "python -m study run moving_friction")
    cl = dataclasses.replace(case_list(), cases=tuple(cases))
    ctx = ReportContext(reports, store, {"moving_friction": cl})
    from study.report.sections import moving_friction as section

    lines = section.section(ctx)
    assert lines[0] == "## Friction between moving parts"
    assert "### Quick-return: Coulomb friction in the rocker's slot" in lines
    assert len(ctx.figures_written) == 2 * len(mf.sets(cases))   # forces and convergence per set
    assert find_one(cases, group="quick_return/slot_friction:regularized").t_end == SHORT
