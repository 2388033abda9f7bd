"""Exudyn's frictionless runs that test_against_inhouse.py and test_reactions.py both compare (the quick-return
through its first cut at the same steps with both solvers), and whose index-2 drift test_exudyn_models.py checks:
each run is made once per test process.

The two files compare them on different grids: test_against_inhouse.py every FINE_STEP, test_reactions.py every
0.01 s, the sampling of its reference. A shared run is sampled every FINE_STEP, and the comparison on common samples
(study.compare.common_samples) reads every second one: the same numbers as a run sampled every 0.01 s, since
Exudyn's output step does not change its steps. The scheduler (tests/scheduling.py) runs the three files on one worker,
so the cache is shared.
"""

from __future__ import annotations

from functools import lru_cache

from study.exudyn_models import run as exudyn_run
from study.params import load_parameters

FINE_STEP = 0.005  # [s] a multiple of the quick-return's steps (cut_steps), a divisor of 0.01 s


@lru_cache(maxsize=None)
def frictionless_run(mechanism: str, variant: str, t_end: float, h: float, solver: str, output_step: float):
    """Exudyn's run without any contact's or pin's friction (friction='none'), sampled every output_step."""
    return exudyn_run(load_parameters(mechanism, variant), t_end, h, solver=solver, output_step=output_step,
                      friction="none")
