"""The order in which the test files go to the xdist workers (`make test`: ``-n auto --dist loadfile``).

xdist's ``loadfile`` gives whole files to the workers, the files with most tests first. On a cold cache that
costs minutes: the files with few but long tests came last and one worker finished them alone, and the compiled
path's first compilation (study.fast, under its lock, study.kernels.cache.compile_lock) made the other worker wait
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
#: cache than the compilation and the first file). Then the rest of the files that took over 5 s in a cold run of
#: the fast suite (tests' seconds, both workers busy; the spatial files as measured cold after the spatial CSE
#: without factor_terms and the spatial slider-crank's compiled run moved to the slow suite), longest first, so
#: that the short files left at the end even out the two workers.
LEAD = (
    "tests/test_fast.py",
    "tests/test_spatial_exudyn.py",
    CV + "frictionless_runs",
    CV + "test_friction_variants.py",
    "tests/test_errata.py",
    "tests/test_coordinates.py",
    "tests/test_reliability_round3.py",
    "tests/test_moving_friction_study.py",
    "tests/test_backend_samples.py",
    "tests/test_spatial_joints.py",
    "tests/test_free_bodies.py",
    "tests/test_spatial_bricard.py",
    "tests/test_pipeline.py",
    "tests/test_bench_compile_time.py",
    "tests/test_spatial_compiled.py",
    "tests/test_studies.py",
    "tests/test_solver.py",
    "tests/test_exudyn_pin_friction.py",
    "tests/test_revolute_friction.py",
    "tests/test_spatial_slider_crank.py",
    "tests/test_reliability_catalogue.py",
    "tests/test_codegen.py",
    "tests/test_validation.py",
    "tests/test_bench_report.py",
    "tests/test_report_figure_cache.py",
    "tests/test_reliability.py",
    "tests/test_report.py",
    "tests/test_moving_guide_friction.py",
    "tests/test_index3.py",
    "tests/test_slider_crank_pins.py",
    "tests/test_reliability_probe.py",
    "tests/test_examples.py",
    "tests/test_friction_defaults.py",
    "tests/test_andrews.py",
    "tests/test_friction.py",
    "tests/test_user_file.py",
    "tests/test_engines.py",
    "tests/test_fast_pin_friction.py",
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
