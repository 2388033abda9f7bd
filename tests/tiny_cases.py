"""A tiny case list shared by the pipeline and report tests."""

import pytest

# A tiny sliding-mode study: a reference and 2 settings x 3 methods of the quick-return over 0.3 s
# (the on/off cutting law switches at 0.093 s, so events are located too). About 1 s of CPU.
TINY = """
[study]
description = "tiny"
summary = "study.studies.sliding_mode"
section = "sliding_mode"
section_order = 40

[[group]]
name = "reference"
mechanism = "quick_return"
t_end = 0.3
options = { integrator = "DOP853", rtol = 1e-10, atol = 1e-12, method = "projection", output_step = 0.05 }

[[group]]
name = "runs"
mechanism = "quick_return"
t_end = 0.3
options = { output_step = 0.05 }
sweep.setting = [
    { label = "RK45 rtol=1e-6", integrator = "RK45", rtol = 1e-6, atol = 1e-8 },
    { label = "RK4 h=1e-3", integrator = "RK4", step = 1e-3 },
]
sweep.method = [
    { label = "none", method = "none" },
    { label = "baumgarte", method = "baumgarte", d = 1.0, omega = 10.0 },
    { label = "sliding_mode/tanh", method = "sliding_mode", sgn = "tanh" },
]
"""


@pytest.fixture
def tiny(tmp_path):
    folder = tmp_path / "cases"
    folder.mkdir()
    (folder / "sliding_mode.toml").write_text(TINY)
    return folder


