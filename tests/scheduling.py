"""The order in which the test files go to the xdist workers (`make test`: ``-n auto --dist loadfile``).

xdist's ``loadfile`` gives whole files to the workers, the files with most tests first. On a cold cache that
costs minutes: the files with few but long tests came last and one worker finished them alone, and the compiled
path's first compilation (study.fast, then under one lock for every compilation; now one per kernel,
study.kernels.cache.compile_lock) made the other worker wait
idle for it as soon as it reached a compiled test too. Here the files of LEAD go first, in its order: the compiled
path's own tests on one worker (it compiles), while the other runs files that need only the reference path, sympy
and Exudyn; then the other long files, longest first (by a cold run of the fast suite on two workers). The files
LEAD does not name follow in xdist's order; they are short. UNITS runs files that share runs through an in-process
cache (tests/cross_validation/frictionless_runs.py) on one worker, as one unit of work.

The order changes the wall time only: every file runs in one process from its first test to its last, as before.
tests/test_scheduling.py checks that every file named here exists.
"""

from __future__ import annotations

from collections import OrderedDict

from xdist.scheduler import LoadFileScheduling

CV = "tests/cross_validation/"
#: One unit of work per name: the files that share an in-process cache.
UNITS = {
    CV + "test_against_inhouse.py": CV + "frictionless_runs",
    CV + "test_reactions.py": CV + "frictionless_runs",
    CV + "test_exudyn_models.py": CV + "frictionless_runs",
}
#: The files (or units) that go first, in this order. The first compiles the compiled path; the next five use no
#: compiled code (sympy, the reference path, Exudyn) and keep the other worker busy meanwhile (more CPU on a cold
#: cache than the compilation and the first file). Then every other file that took over 5 s of CPU, longest first,
#: so that the short files left at the end even out the two workers: each file run alone on a cold cache
#: (``-n 0``, a fresh STUDY_CACHE_DIR, user + system seconds) at main 1c51fe9 with the round-3 cache tries and
#: slip_then_stick's index-3 Exudyn runs in the slow suite. The spatial friction, Bricard peer and heavy-top files
#: (13-31 s) were not named before and came last, after every named file.
LEAD = (
    "tests/test_fast.py",                               # 52
    "tests/test_spatial_exudyn.py",                     # 12
    CV + "frictionless_runs",                           # 18 + 18 + 18 alone, less together
    CV + "test_friction_variants.py",                   # 28
    "tests/test_errata.py",                             # 16
    "tests/test_coordinates.py",                        # 31
    "tests/test_backend_samples.py",                    # 55
    "tests/test_studies.py",                            # 50
    "tests/test_moving_friction_study.py",              # 45
    "tests/test_reliability_round3.py",                 # 40
    "tests/test_solver.py",                             # 37
    "tests/test_examples.py",                           # 37
    "tests/test_spatial_compiled.py",                   # 32
    "tests/test_moving_guide_friction.py",              # 32
    "tests/test_spatial_friction.py",                   # 31
    "tests/test_validation.py",                         # 29
    "tests/test_pipeline.py",                           # 25
    "tests/test_fast_pin_friction.py",                  # 24
    "tests/test_revolute_friction.py",                  # 22
    "tests/test_report.py",                             # 21
    "tests/test_exudyn_pin_friction.py",                # 20
    "tests/test_friction.py",                           # 19
    "tests/test_free_bodies.py",                        # 18
    "tests/test_spatial_slider_crank.py",               # 17
    "tests/test_reliability.py",                        # 17
    "tests/test_spatial_bricard.py",                    # 15
    "tests/test_spatial_friction_carriage.py",          # 13
    "tests/test_spatial_friction_exudyn.py",            # 13
    "tests/test_spatial_bricard_peer.py",               # 12
    "tests/test_spatial_heavy_top.py",                  # 12
    "tests/test_friction_defaults.py",                  # 10
    "tests/test_slider_crank_pins.py",                  # 10
    "tests/test_reliability_probe.py",                  # 9
    "tests/test_bench_compile_time.py",                 # 8
    "tests/test_codegen.py",                            # 7
    "tests/test_bench_report.py",                       # 7
    "tests/test_report_figure_cache.py",                # 7
    "tests/test_reliability_catalogue.py",              # 6
    "tests/test_spatial_joints.py",                     # 6
    "tests/test_andrews.py",                            # 6
    "tests/test_index3.py",                             # 5
    "tests/test_user_file.py",
    "tests/test_engines.py",
    "tests/test_bench_cases.py",
)


class LeadFirstScheduling(LoadFileScheduling):
    """``--dist loadfile`` with the files of LEAD first and the files of a UNITS entry as one unit."""

    def __init__(self, config, log=None) -> None:
        super().__init__(config, log)
        self._ordered = False

    def _split_scope(self, nodeid: str) -> str:
        path = super()._split_scope(nodeid)
        return UNITS.get(path, path)

    def _assign_work_unit(self, node) -> None:
        if not self._ordered:   # the queue is complete when the first unit is assigned
            rank = {scope: i for i, scope in enumerate(LEAD)}
            self.workqueue = OrderedDict(sorted(self.workqueue.items(), key=lambda kv: rank.get(kv[0], len(rank))))
            self._ordered = True
        super()._assign_work_unit(node)
