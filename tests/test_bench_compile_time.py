"""The benchmark's time-to-first-result table (study.bench.compile_time): its rows and columns, on a tiny case.

Checks the table's shape and the pace scaling, never the seconds themselves (no test judges the host's speed)."""

from __future__ import annotations

import pytest

from study.bench.compile_time import MECHANISMS, commands, compile_time

COLUMNS = ["path", "cache", "mechanism", "repeat", "first_call_wall_s", "cpu_s", "pace_us", "cpu_s_at_pace_1us"]


def test_table_has_a_cold_and_a_warm_row_per_path_scaled_by_the_pace():
    table = compile_time(repeats=1, paths=("reference",), pace=2.0, t_end=0.01,   # the pace given: nothing compiled
                         mechanisms=("quick_return",))
    assert list(table.columns) == COLUMNS
    assert list(zip(table.path, table.cache, table.repeat)) == [("reference", "cold", 0), ("reference", "warm", 0)]
    assert (table.pace_us == 2.0).all()
    assert table.cpu_s_at_pace_1us.tolist() == pytest.approx((table.cpu_s / 2.0).tolist(), rel=0, abs=0)
    assert (table.cpu_s > 0).all() and (table.first_call_wall_s > 0).all()   # each child ran and was measured


def test_every_path_of_every_mechanism_runs_that_mechanism(tmp_path):
    """The spatial mechanisms are measured too, each path's child naming the mechanism it runs."""
    assert {"heavy_top", "spatial_slider_crank"} <= set(MECHANISMS)
    for mechanism in MECHANISMS:
        argv = commands(tmp_path, 0.5, mechanism)
        assert argv["reference"][3] == argv["compiled"][3] == mechanism and argv["compiled"][-1] == "compiled"
        assert f"study.run({mechanism!r}, study.Exudyn(h=1e-3), 0.5)" in argv["exudyn"][1]
