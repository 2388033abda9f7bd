"""The benchmark's targets table and its report section, from small synthetic benchmark files.

No timing is asserted: the CSVs are made up, the tests check that the verdicts follow the
thresholds and that the section quotes the saved numbers.
"""

import json

import numpy as np
import pandas as pd
import pytest

from study.bench.accuracy import cheapest, ratios
from study.bench.harness import repeats_for
from study.bench.sweeps import order2_step
from study.bench.targets import THRESHOLDS, evaluate_targets
from study.pipeline.tables import record_written
from study.report.context import ReportContext
from study.report.render import fmt_number
from study.report.sections import benchmarks


def _accel(us_loop=0.83):
    rows = []
    for mech, variant, fric in (("quick_return", "smooth_cutting", False), ("slider_crank", "sustained_sliding", True)):
        for path, us, n in (("reference (Python)", 35.7, 1000), ("compiled, in compiled loop", us_loop, 20000),
                            ("compiled, one call from Python", 54.2, 1000)):
            rows.append({"mechanism": mech, "variant": variant, "friction_solve": fric, "path": path,
                         "us_per_evaluation": us, "calls_per_timing": n, "repeats": 5})
    return pd.DataFrame(rows)


def _work_precision():
    """Two mechanisms; Exudyn reaches 1e-4 and 1e-6 but not 1e-8."""
    rows = []
    for mech, variant, t_end in (("quick_return", "smooth_cutting", 5.0), ("slider_crank", "sustained_sliding", 20.0)):
        for engine, method, runs in (
                ("in-house compiled", "DOP853", [(1e-6, 3e-4, 0.006), (1e-9, 4e-7, 0.0123), (1e-12, 5e-9, 0.027)]),
                ("in-house reference", "DOP853", [(1e-8, 5e-5, 0.61)]),
                ("Exudyn tuned", "index3", [(1e-3, 2e-3, 0.45), (1e-4, 5e-5, 4.5), (2e-5, 8.1e-7, 22.25)]),
                ("Exudyn (Python user functions)", "index3", [(1e-3, 2e-3, 0.9), (2e-5, 8.1e-7, 61.0)])):
            for setting, err, cpu in runs:
                rows.append({"mechanism": mech, "variant": variant, "t_end": t_end, "engine": engine, "method": method,
                             "setting": setting, "error": err, "cpu_s": cpu, "repeats": 5 if cpu < 5 else 1,
                             "stage": "sweep", "note": ""})
    return pd.DataFrame(rows)


def _qr20(best_error=4e-9, uncertainty=3e-10):
    rows = []
    for variant in ("smooth_cutting", "seed"):
        for rtol, err, cpu in ((1e-12, 7e-8, 0.105), (1e-13, best_error, 0.143), (1e-14, best_error / 2, 0.21)):
            rows.append({"variant": variant, "t_end": 20.0, "integrator": "DOP853 (compiled)", "rtol": rtol,
                         "atol": rtol * 1e-2, "error": err, "cpu_s": cpu, "repeats": 5, "steps": 7000, "events": 0,
                         "reference_rtol": 5e-15, "reference_uncertainty": uncertainty})
    return pd.DataFrame(rows)


def _scaling(cpu_100=0.355):
    return pd.DataFrame({"backend": ["compiled"] * 4, "t_end": [1.0, 5.0, 20.0, 100.0],
                         "cpu_s": [0.0040, 0.0180, 0.0715, cpu_100], "steps": [220, 870, 3370, 16750],
                         "cpu_per_simulated_s": [0.004, 0.0036, 0.0036, cpu_100 / 100], "repeats": [5] * 4})


def _memory(bytes_small=17730):
    return pd.DataFrame({"backend": ["compiled"] * 3, "t_end": [20.0, 100.0, 100.0], "output_step": [0.01, 0.01, 1.0],
                         "samples": [2001, 10001, 101], "steps": [3376, 16758, 16758],
                         "peak_traced_bytes": [306327, 1527254, bytes_small],
                         "bytes_per_sample": [306327 / 2001, 1527254 / 10001, bytes_small / 101]})


def _targets(**kw):
    ratio = ratios(cheapest(_work_precision()))
    return evaluate_targets(kw.get("accel", _accel()), ratio, kw.get("qr20", _qr20()),
                            kw.get("scaling", _scaling()), kw.get("memory", _memory()))


def test_targets_met_from_synthetic_tables():
    t = _targets()
    assert list(t.columns) == ["target", "threshold", "measured", "unit", "met", "how_measured", "repeats", "note"]
    verdicts = t.met.astype(str).tolist()
    assert len(t) == 9 and verdicts.count("True") == 7
    assert verdicts.count("reported") == 2 and "not measured" not in verdicts  # ratio 3' (two mechanisms)
    accel = t[t.target.str.startswith("1:")].iloc[0]
    assert accel.measured == pytest.approx(0.83) and accel.threshold == THRESHOLDS["accel"][0]
    qr = t[t.target.str.startswith("2:")]
    assert list(qr.measured) == pytest.approx([0.143, 0.143])  # cheapest with error + reference error <= 1e-8
    ratio = t[t.target.str.startswith("3:")]
    assert list(ratio.measured) == pytest.approx([0.0123 / 22.25] * 2)  # DOP853 1e-9 / Exudyn h = 2e-5
    assert "(quick_return)" in ratio.target.iloc[0] and "(slider_crank)" in ratio.target.iloc[1]
    assert "Exudyn tuned" in ratio.target.iloc[0] and "Exudyn tuned" in ratio.how_measured.iloc[0]
    python = t[t.target.str.startswith("3':")]   # reference path 1e-8 setting (5e-5 rad) misses 1e-6: NaN
    assert python.measured.isna().all() and (python.met == "reported").all()


def test_targets_missed_from_synthetic_tables():
    t = _targets(accel=_accel(us_loop=6.0), qr20=_qr20(best_error=2e-8), scaling=_scaling(cpu_100=0.9),
                 memory=_memory(bytes_small=60000))
    met = dict(zip(t.target.str.split(":").str[0], t.met))
    assert met["1"] is False and met["4a"] is False and met["4b"] is False
    qr = t[t.target.str.startswith("2:")]
    assert not qr.met.any() and qr.measured.isna().all()  # not reached: no CPU, the best error in the note
    assert "no setting reaches 1e-08" in qr.note.iloc[0] and "1e-08" in qr.note.iloc[0]
    # the reference's error counts against a setting: rtol 1e-14 has 9.5e-9 rad
    t2 = _targets(qr20=_qr20(best_error=1.9e-8, uncertainty=4e-10))
    assert t2[t2.target.str.startswith("2:")].measured.tolist() == pytest.approx([0.21, 0.21])
    t2 = _targets(qr20=_qr20(best_error=1.9e-8, uncertainty=1e-9))  # 9.5e-9 + 1e-9 > 1e-8
    assert not t2[t2.target.str.startswith("2:")].met.any()


def test_exudyn_not_reaching_a_level_is_recorded():
    ratio = ratios(cheapest(_work_precision()))
    assert set(ratio.comparison) == {"compiled / Exudyn tuned", "reference / Exudyn (Python user functions)"}
    ratio = ratio[ratio.comparison == "compiled / Exudyn tuned"]
    at8 = ratio[np.isclose(ratio.level, 1e-8)]
    assert at8.ratio_inhouse_over_exudyn.isna().all()
    assert at8.exudyn_finest_h_tried.tolist() == pytest.approx([2e-5, 2e-5])
    assert "did not reach 1e-08" in at8.note.iloc[0]


def test_helpers():
    assert repeats_for(0.1) == 5 and repeats_for(8.0) == 1 and repeats_for(6.0) == 2
    h = order2_step(3.90625e-05, 8.8e-6, 1e-6, 0.01)
    assert h < 3.90625e-05 * np.sqrt(0.8 / 8.8) + 1e-15 and abs(0.01 / h - round(0.01 / h)) < 1e-6
    h = order2_step(1.25e-05, 7.6e-5, 1e-6, 1e-3)   # Andrews: its samples every 1e-3 s
    assert h < 1.25e-05 * np.sqrt(0.8 / 76) + 1e-15 and abs(1e-3 / h - round(1e-3 / h)) < 1e-6


def _write(folder, targets):
    folder.mkdir(parents=True)
    wp = _work_precision()
    per_level = cheapest(wp)
    targets.to_csv(folder / "targets.csv", index=False)
    wp.to_csv(folder / "work_precision.csv", index=False)
    per_level.to_csv(folder / "cpu_to_accuracy.csv", index=False)
    ratios(per_level).to_csv(folder / "ratio_inhouse_exudyn.csv", index=False)
    _qr20().to_csv(folder / "quick_return_20s.csv", index=False)
    pd.DataFrame([{"mechanism": "quick_return", "variant": "seed", "t_end": 20.0, "integrator": "DOP853 (compiled)",
                   "reference_rtol": 5e-15, "reference_atol": 5e-17, "check_rtol": 1e-14, "check_atol": 1e-16,
                   "max_abs_dq_check_vs_reference": 2.5e-10, "reference_steps": 7000, "check_steps": 6000}]
                 ).to_csv(folder / "references.csv", index=False)
    _accel().to_csv(folder / "acceleration_evaluation.csv", index=False)
    _scaling().to_csv(folder / "scaling_simulated_time.csv", index=False)
    pd.DataFrame({"t_end": [20.0], "output_step": [0.01], "samples": [2001], "cpu_s": [0.0698], "steps": [3376],
                  "nfev": [56714], "repeats": [5]}).to_csv(folder / "scaling_output_density.csv", index=False)
    _memory().to_csv(folder / "peak_memory.csv", index=False)
    pd.DataFrame({"cache": ["fresh cache (code generation + compilation)"], "mechanism": ["quick_return"],
                  "first_call_wall_s": [41.7]}).to_csv(folder / "compile_time.csv", index=False)
    (folder / "machine.json").write_text(json.dumps({"platform": "Linux-test", "cpu_count": 2, "python": "3.11.7",
                                                     "exudyn": "1.13.6", "numba": "0.68.1", "repeats": 5,
                                                     "benchmark_wall_s": 431.5, "long_run_s": 5.0}))
    for path in folder.glob("*.csv"):   # recorded as the one table writer records them
        record_written(path, "written by the test")


def test_section_renders_saved_numbers(tmp_path):
    targets = _targets(accel=_accel(us_loop=0.8261))
    _write(tmp_path / "benchmarks", targets)
    ctx = ReportContext(reports_dir=tmp_path, store=None, case_lists={})
    lines = benchmarks.section(ctx)
    text = "\n".join(lines)
    assert lines[0] == "## Performance: accuracy per CPU second"
    assert "| 0.826 | µs | **met** |" in text  # target 1 as saved
    ratio = pd.read_csv(tmp_path / "benchmarks" / "ratio_inhouse_exudyn.csv")
    for value in ratio.ratio_inhouse_over_exudyn.dropna():
        assert fmt_number(value) in text
    assert "Linux-test" in text and "432" in text and "exudyn 1.13.6" in text
    assert "41.7" in text and "2.5e-10" in text
    assert "All 7 target rows met." in text and "2 row(s) carry no verdict" in text
    assert (tmp_path / "figures" / "benchmark_work_precision.png").exists()
    read = {p.name for p in ctx.inputs}
    assert {"targets.csv", "work_precision.csv", "ratio_inhouse_exudyn.csv", "machine.json",
            "acceleration_evaluation.csv", "peak_memory.csv", "compile_time.csv", "references.csv"} <= read

    missed = _targets(accel=_accel(us_loop=7.5))
    missed.to_csv(tmp_path / "benchmarks" / "targets.csv", index=False)
    record_written(tmp_path / "benchmarks" / "targets.csv", "written by the test")
    text = "\n".join(benchmarks.section(ReportContext(reports_dir=tmp_path, store=None, case_lists={})))
    assert "| 7.5 | µs | **missed** |" in text and "1 of 7 target rows missed" in text
    assert "| reported |" in text


def test_section_without_benchmark(tmp_path):
    lines = benchmarks.section(ReportContext(reports_dir=tmp_path, store=None, case_lists={}))
    assert lines[0].startswith("## Performance") and "make bench" in "\n".join(lines)


def test_study_cases_compiled_over_reference_row():
    study_cpu = pd.DataFrame({"study": ["s", "s"], "case": ["s/a", "s/b"], "compiled_cpu_s": [0.03, 0.05],
                              "reference_cpu_s": [1.0, 1.0], "compiled_over_reference": [0.03, 0.05]})
    ratio = ratios(cheapest(_work_precision()))
    t = evaluate_targets(_accel(), ratio, _qr20(), _scaling(), _memory(), study_cpu=study_cpu)
    row = t[t.target.str.contains("study cases")].iloc[0]
    assert row.measured == pytest.approx(0.05) and row.met is False and "s/b" in row.how_measured


def test_a_mechanisms_run_replaces_only_its_own_rows(tmp_path):
    """``--mechanisms andrews`` keeps the other mechanisms' rows of a saved table and replaces Andrews' rows."""
    from study.bench.command import _merge

    old = pd.DataFrame({"mechanism": ["quick_return", "andrews", "four_bar"], "cpu_s": [1.0, 2.0, 3.0]})
    new = pd.DataFrame({"mechanism": ["andrews", "andrews"], "cpu_s": [5.0, 6.0]})
    merged = _merge(new, old, ["andrews"])
    assert sorted(zip(merged.mechanism, merged.cpu_s)) == [("andrews", 5.0), ("andrews", 6.0), ("four_bar", 3.0),
                                                          ("quick_return", 1.0)]
    assert _merge(new, None, ["andrews"]).equals(new)


def test_unknown_mechanism_is_refused_by_name(tmp_path):
    from study.bench.command import add_arguments, run
    import argparse

    args = add_arguments(argparse.ArgumentParser()).parse_args(["--mechanisms", "andrew", "--out", str(tmp_path)])
    with pytest.raises(ValueError, match="--mechanisms andrew: no such mechanism.*valid: quick_return"):
        run(args)
