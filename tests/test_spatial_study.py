"""The spatial study (reference/cases/spatial.toml, study.studies.spatial, study.report.sections.spatial): the
spatial registry by name, the equal-accuracy pairing, and the section on tiny tables typed here."""

from __future__ import annotations

import pandas as pd
import pytest

from study.mechanisms import named_mechanism
from study.params import ParameterError
from study.pipeline.tables import write_tables
from study.report.context import ReportContext
from study.report.sections import spatial as section
from study.studies.spatial import equal_accuracy


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


def test_the_section_says_when_the_study_has_not_run(tmp_path):
    text = "\n".join(section.section(ReportContext(reports_dir=tmp_path, store=None, case_lists={})))
    assert "the study `spatial` has not run" in text
