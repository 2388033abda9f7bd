"""The spatial study (reference/cases/spatial.toml, study.studies.spatial, study.report.sections.spatial): the
spatial registry by name, the equal-accuracy pairing, and the section on tiny tables typed here."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from study.mechanisms import named_mechanism
from study.params import ParameterError
from study.pipeline import Case
from study.pipeline.tables import write_tables
from study.reference_data import tolerance
from study.report.context import ReportContext
from study.report.sections import spatial as section
from study.results import SimulationResult
from study.studies import spatial_friction
from study.studies.spatial import equal_accuracy, summarize


@pytest.mark.parametrize("name", ["heavy_top", "bricard", "spatial_slider_crank"])
def test_the_pipeline_finds_the_spatial_mechanisms_by_name(name):
    m = named_mechanism(name)
    assert m.kind == "spatial" and m.name == name


def test_a_spatial_mechanism_has_only_its_seed():
    with pytest.raises(ParameterError, match="variant = 'other' is not a variant of the spatial mechanism heavy_top"):
        named_mechanism("heavy_top", "other")


def _runs() -> pd.DataFrame:
    rows = [("heavy_top", "inhouse", "inhouse", "DOP853 rtol=1e-06 projection", 2e-6, 0.05),
            ("heavy_top", "inhouse", "inhouse", "DOP853 rtol=1e-08 projection", 1e-8, 0.04),
            ("heavy_top", "exudyn", "exudyn", "index3 h=0.0002", 2e-4, 0.10),
            ("bricard", "exudyn", "exudyn", "index3 h=0.002", 1e-9, 0.5),
            ("bricard", "inhouse", "inhouse", "DOP853 rtol=1e-06 none", 1e-5, 0.01)]
    return pd.DataFrame(rows, columns=["mechanism", "engine", "group", "setting", "error", "cpu_s"])


def test_equal_accuracy_takes_the_cheapest_inhouse_run_at_least_as_accurate():
    table = equal_accuracy(_runs())
    top = table[table["mechanism"] == "heavy_top"].iloc[0]
    assert top["inhouse"] == "DOP853 rtol=1e-08 projection" and top["exudyn_over_inhouse_cpu"] == pytest.approx(2.5)
    brick = table[table["mechanism"] == "bricard"].iloc[0]
    assert brick["inhouse"] == "none as accurate" and pd.isna(brick["exudyn_over_inhouse_cpu"])


def test_the_section_states_sliding_modes_energy_against_its_bound(tmp_path):
    runs = pd.DataFrame([
        {"mechanism": "heavy_top", "engine": "inhouse", "group": "methods", "setting": "DOP853 rtol=1e-12 none",
         "t_end_s": 0.2, "error": 1e-13, "published_distance": 1.6e-6, "rounds_to_published": True,
         "energy_drift_J": 4e-8, "energy_bound_J": 5e-7, "drift_over_bound": 0.08, "max_abs_phi": 1e-12},
        {"mechanism": "heavy_top", "engine": "inhouse", "group": "methods",
         "setting": "DOP853 rtol=1e-12 sliding_mode", "t_end_s": 0.2, "error": 3e-9, "published_distance": 1.6e-6,
         "rounds_to_published": True, "energy_drift_J": 2.5e-6, "energy_bound_J": 5e-7, "drift_over_bound": 5.0,
         "max_abs_phi": 2e-10}])
    timing = runs[["mechanism", "engine", "group", "setting"]].assign(cpu_s=[0.1, 0.2])
    write_tables({"spatial_runs": runs, "spatial_timing": timing}, tmp_path, "test")
    ctx = ReportContext(reports_dir=tmp_path, store=None, case_lists={})
    text = "\n".join(section.section(ctx))
    assert text.startswith("## Spatial mechanisms")
    assert ("**DOP853 rtol=1e-12 sliding_mode does not conserve the top's energy to the bound**: drift 2.5e-06 J, "
            "5 × its bound 5e-07 J") in text
    assert "The others stay within: at most 0.08 of the bound." in text
    assert "sliding_mode drifts 5 × its energy bound" in section.finding(ctx)


def test_the_finding_leaves_out_joint_friction_when_its_tables_have_no_rows(tmp_path):
    """A case list without friction runs writes the friction tables empty: the answer omits them, no crash."""
    runs = pd.DataFrame([
        {"mechanism": "heavy_top", "engine": engine, "group": engine, "setting": "s", "t_end_s": 0.2,
         "error": error, "published_distance": 1.6e-6, "rounds_to_published": True, "energy_drift_J": 1e-9,
         "energy_bound_J": 1e-8, "drift_over_bound": 0.1, "max_abs_phi": 1e-12}
        for engine, error in (("inhouse", 1e-9), ("exudyn", 1e-5))])
    empty = pd.DataFrame(columns=["mechanism", "law", "stuck_joints", "stick_times"])
    orders = pd.DataFrame(columns=["quantity", "order", "verdict"])
    write_tables({"spatial_runs": runs, "spatial_friction": empty, "spatial_friction_orders": orders}, tmp_path,
                 "test")
    answer = section.finding(ReportContext(reports_dir=tmp_path, store=None, case_lists={}))
    assert answer.startswith("the heavy top to 1e-09 in-house and 1e-05 in Exudyn") and "joint friction" not in answer


def test_the_section_says_when_the_study_has_not_run(tmp_path):
    text = "\n".join(section.section(ReportContext(reports_dir=tmp_path, store=None, case_lists={})))
    assert "the study `spatial` has not run" in text


def _friction_case(group: str, engine: str, t_end: float, **options) -> Case:
    return Case(study="spatial", group=f"carriage:{group}", engine=engine, mechanism="carriage", variant="seed",
                t_end=t_end, options=tuple(sorted(options.items())))


def _friction_result(t: np.ndarray, offset: float, transitions=()) -> SimulationResult:
    """Two coordinates, one joint row and one norm row, one joint with friction: every quantity the reference's
    plus ``offset`` (a function of the quantity's name, for the Exudyn runs' errors)."""
    n = len(t)
    work = -2.0 * t
    return SimulationResult(
        t=t, q=np.zeros((n, 2)) + offset("q"), qd=np.zeros((n, 2)) + offset("qd"), qdd=np.zeros((n, 2)),
        lam=np.column_stack([10.0 + offset("lam") * np.ones(n), 7.0 + 5.0 * np.ones(n)]), phi=np.zeros((n, 2)),
        phidot=np.zeros((n, 2)),
        energies={"kinetic": 3.0 + work + offset("energy") * t, "potential": np.zeros(n),
                  "work_friction_slide": work + offset("work")},
        forces={"normal_slide": 10.0 + offset("normal") * np.ones(n), "friction_slide": 3.0 + offset("friction")
                * np.ones(n)},
        stats={"cpu_seconds": 0.1, "friction_transitions": list(transitions)},
        meta={"constraint_names": ["slide_tx", "body_norm"], "mechanism": "carriage"})


STEPS = (2e-3, 1e-3, 5e-4)


def _friction_tables() -> dict[str, pd.DataFrame]:
    """The friction tables of synthetic runs whose errors are known: C h^2 (q, the multipliers, the friction force
    and work, Exudyn's energy balance), C h (the normal force), and under order_error_floor (qd); an exact run with
    a stick and a slip event."""
    t = np.linspace(0.0, 0.6, 7)
    floor = tolerance("order_error_floor", "cross_validation")

    def errors(h):
        return lambda name: {"normal": 3.0 * h, "qd": 0.1 * floor}.get(name, 50.0 * h ** 2)
    transitions = [{"t": 0.0, "contact": None, "initial": {}}, {"t": 0.3, "contact": "slide", "to": "stick"},
                   {"t": 0.5, "contact": "slide", "to": "slip+"}]
    loaded = {_friction_case("friction_exact", "inhouse", 2.0, integrator="DOP853", rtol=1e-10, friction="exact"):
              _friction_result(t, lambda name: 0.0, transitions),
              _friction_case("friction_reference", "inhouse", 0.6, integrator="DOP853", rtol=1e-12,
                             friction="regularized", friction_eps=0.05): _friction_result(t, lambda name: 0.0)}
    for h in STEPS:
        loaded[_friction_case("friction_exudyn", "exudyn", 0.6, h=h, eps=0.05, solver="index3")] = \
            _friction_result(t, errors(h))
    other = _friction_case("reference", "inhouse", 0.6, integrator="DOP853", rtol=1e-12)
    return spatial_friction.summarize([*loaded, other], loaded.__getitem__)


def test_the_friction_tables_judge_each_quantity_by_its_order_or_its_floor():
    """Each quantity's verdict from its known errors (C h^2: 'order >= min_order', C h: 'below min_order', under
    the floor: 'at floor'); the exact run's located stick events only, the energy balance with the friction's work
    and the work dissipated; a case of another group left out."""
    tables = _friction_tables()
    runs, orders = tables["spatial_friction"], tables["spatial_friction_orders"]
    exact = runs[runs["group"] == "friction_exact"].iloc[0]
    assert (exact["law"], exact["stuck_joints"], exact["stick_times"]) == ("exact", "slide", "0.3")
    assert exact["energy_balance_error"] == 0.0 and exact["dissipated_J"] == pytest.approx(1.2)
    assert list(runs["law"]) == ["exact", "regularized eps=0.05", *["regularized eps=0.05"] * 3]
    verdicts = orders.groupby("quantity")["verdict"].first().to_dict()
    assert verdicts == {"q": "order >= min_order", "qd": "at floor", "joint multipliers": "order >= min_order",
                        "normal_slide": "below min_order", "friction_slide": "order >= min_order",
                        "work_friction_slide": "order >= min_order", "energy balance": "order >= min_order"}
    q = orders[orders["quantity"] == "q"].sort_values("h", ascending=False)
    assert list(q["h"]) == list(STEPS) and np.allclose(q["max_abs_diff"], [50.0 * h ** 2 for h in STEPS])
    assert np.allclose(q["order"].iloc[1:], 2.0)


def test_the_section_reads_the_friction_tables(tmp_path):
    write_tables(_friction_tables(), tmp_path, "test")
    write_tables({"spatial_runs": pd.DataFrame([{"mechanism": "other", "engine": "inhouse", "group": "methods",
                                                 "setting": "s"}])}, tmp_path, "test")
    text = "\n".join(section.section(ReportContext(reports_dir=tmp_path, store=None, case_lists={})))
    assert "The exact law in-house (DOP853 rtol=1e-10 none, 2 s) sticks slide at 0.3 s;" in text
    assert ("q, joint multipliers, friction_slide, work_friction_slide, energy balance: observed orders 2 to 2; "
            "qd: no discretization error (every error at most its floor); normal_slide: **below min_order**") in text


def test_the_carriage_cases_take_the_reference_files_steps_and_width():
    """The case list's friction_carriage groups run at reference/spatial/friction_carriage.toml's [exudyn_steps] and
    [eps] (whose reasons are the steps' and the width's), the regularized in-house run at the same eps."""
    from study.pipeline import CASES_DIR, load_case_list
    from study.reference_data import values

    cases = [c for c in load_case_list(CASES_DIR / "spatial.toml").cases if c.mechanism == "friction_carriage"]
    exudyn = [c for c in cases if c.engine == "exudyn"]
    assert sorted(c.kwargs["h"] for c in exudyn) == sorted(values("exudyn_steps", "spatial/friction_carriage"))
    eps = tolerance("eps", "spatial/friction_carriage")
    assert {c.kwargs["eps"] for c in exudyn} == {eps}
    assert [c.kwargs["friction_eps"] for c in cases if c.kwargs.get("friction") == "regularized" and
            c.engine == "inhouse"] == [eps]


def _benchmark_case(group: str, engine: str, **options) -> Case:
    return Case(study="spatial", group=f"bricard:{group}", engine=engine, mechanism="bricard", variant="seed",
                t_end=10.0, options=tuple(sorted(options.items())))


def _energy_result(kinetic: list[float], drift: float) -> SimulationResult:
    """Three samples whose kinetic energy is ``kinetic`` and whose total energy ends ``drift`` from its start."""
    t, k = np.array([0.0, 5.0, 10.0]), np.array(kinetic)
    zeros = np.zeros((3, 1))
    return SimulationResult(t=t, q=zeros, qd=zeros, qdd=zeros, lam=zeros, phi=zeros, phidot=zeros,
                            energies={"kinetic": k, "potential": -k + np.array([0.0, 0.0, drift])},
                            stats={"cpu_seconds": 0.5, "steps": 3}, meta={"mechanism": "bricard"})


INHOUSE_BENCHMARK = _benchmark_case("benchmark", "inhouse", integrator="DOP853", rtol=1e-9, method="none")
EXUDYN_BENCHMARK = _benchmark_case("exudyn_benchmark", "exudyn", h=6.25e-5, solver="index3", configuration="tuned")


def _benchmark_tables(exudyn_drift: float) -> dict[str, pd.DataFrame]:
    """The in-house benchmark run (rtol 1e-9, max K 5 J, drift 1e-7 J: bound 5e-7 J) and Exudyn's (max K 3 J, its
    bound by the in-house rtol 3e-7 J) with the drift given."""
    loaded = {INHOUSE_BENCHMARK: _energy_result([0.0, 5.0, 2.0], 1e-7),
              EXUDYN_BENCHMARK: _energy_result([0.0, 3.0, 1.0], exudyn_drift)}
    return summarize(list(loaded), loaded.__getitem__)


def test_exudyns_benchmark_run_is_held_to_the_inhouse_runs_bound_with_its_own_max_k():
    runs = _benchmark_tables(2e-7)["spatial_runs"].set_index("group")
    assert list(runs.index) == ["benchmark", "exudyn_benchmark"]
    assert runs.loc["benchmark", "energy_bound_J"] == pytest.approx(tolerance("energy_drift_factor") * 1e-9 * 5.0)
    exudyn = runs.loc["exudyn_benchmark"]
    assert exudyn["setting"] == "index3 h=6.25e-05 tuned" and exudyn["criterion"] == "energy"
    assert exudyn["energy_drift_J"] == pytest.approx(2e-7, rel=1e-6)
    assert exudyn["energy_bound_J"] == pytest.approx(tolerance("energy_drift_factor") * 1e-9 * 3.0)
    assert exudyn["drift_over_bound"] == pytest.approx(2e-7 / (tolerance("energy_drift_factor") * 3e-9), rel=1e-6)


def test_an_exudyn_benchmark_run_without_the_inhouse_one_is_refused_by_name():
    with pytest.raises(ValueError, match="spatial/bricard:exudyn_benchmark: .*no group 'bricard:benchmark'"):
        summarize([EXUDYN_BENCHMARK], lambda case: _energy_result([0.0, 3.0, 1.0], 2e-7))


@pytest.mark.parametrize("drift, verdict, keeps", [(2e-7, "within", "keeps"),
                                                    (6e-7, "**above**", "**does not keep**")])
def test_the_section_and_the_finding_state_bricards_energy_in_house_and_in_exudyn(tmp_path, drift, verdict, keeps):
    """Each engine's drift against its bound, the verdict and the CPU; the finding keeps the energy only when both
    runs do (the in-house bound 5e-7 J, Exudyn's 3e-7 J: 6e-7 J is twice it)."""
    tables = {name: _benchmark_tables(drift)[name] for name in ("spatial_runs", "spatial_timing")}
    write_tables(tables, tmp_path, "test")
    ctx = ReportContext(reports_dir=tmp_path, store=None, case_lists={})
    text = "\n".join(section.section(ctx))
    assert ("- in-house (DOP853 rtol=1e-09 none): max abs(E − E(0)) = 1e-07 J, 0.2 of its bound 5e-07 J: within "
            "the rule, in 0.5 s of CPU.") in text
    ratio = f"{drift / 3e-7:.2g}"
    assert (f"- Exudyn (index3 h=6.25e-05 tuned): max abs(E − E(0)) = {drift:g} J, {ratio} of its bound 3e-07 J: "
            f"{verdict} the rule, in 0.5 s of CPU.") in text
    assert f"| exudyn | index3 h=6.25e-05 tuned | 10 | – | {drift:g} | 3e-07 | {drift / 3e-7:.3g} | " \
           f"{verdict.strip('*')} | 0.5 |" in text
    runs = tables["spatial_runs"]
    write_tables({"spatial_runs": pd.concat([runs, runs.assign(mechanism="heavy_top", group="methods")])}, tmp_path,
                 "test")
    assert (f"Bricard's mechanism (A04) {keeps} its energy over 10 s within the in-house run's bound, in-house at 0.2 "
            f"of it (DOP853 rtol=1e-09 none) and Exudyn at {ratio} of it (index3 h=6.25e-05 tuned)"
            ) in section.finding(ctx)


def test_exudyns_bricard_benchmark_case_runs_the_reference_files_step_over_the_benchmarks_horizon():
    """The case list's Exudyn run of A04 over [t_end] at [exudyn_energy_step] (tuned), beside the in-house run at
    [inhouse_rtol] whose bound it is held to."""
    from study.pipeline import CASES_DIR, load_case_list

    cases = {c.group: c for c in load_case_list(CASES_DIR / "spatial.toml").cases if c.mechanism == "bricard"}
    exudyn, inhouse = cases["bricard:exudyn_benchmark"], cases["bricard:benchmark"]
    assert exudyn.engine == "exudyn" and exudyn.t_end == inhouse.t_end == tolerance("t_end", "spatial/bricard")
    assert exudyn.kwargs["h"] == tolerance("exudyn_energy_step", "spatial/bricard")
    assert (exudyn.kwargs["solver"], exudyn.kwargs["configuration"]) == ("index3", "tuned")
    assert inhouse.kwargs["rtol"] == tolerance("inhouse_rtol", "spatial/bricard")
