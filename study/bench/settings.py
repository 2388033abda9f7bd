"""The benchmark's settings: its runs' case list, accuracy levels, budgets, repeats and references.

The runs themselves (mechanisms, variants, horizons, the candidate settings of every sweep, the
references) are the case list ``reference/cases/bench.toml``; the numbers below that describe them
(:data:`CASES`, :data:`REF_RTOL`, the 20 s quick-return's grid) are read from it, the others plan how
the benchmark walks it. The targets the measurements are judged against are in
:mod:`study.bench.targets` (thresholds in ``reference/tolerances.toml``).
"""

from __future__ import annotations


from study.locations import CASES_DIR, REPORTS_DIR
from study.pipeline import Case, CaseList, load_case_list
from study.solver.friction import DEFAULT_EPS

OUT = REPORTS_DIR / "benchmarks"
#: The benchmark's runs (a standalone case list: only ``study bench`` runs it).
CASE_LIST: CaseList = load_case_list(CASES_DIR / "bench.toml")
#: The benchmark's own store of saved runs, a folder of the cache root: its runs are timed one at a time in
#: its process, the studies' runs with parallel workers, so the two never share a saved CPU time.
STORE_FOLDER = "bench_runs"


def group(name: str) -> list[Case]:
    """The cases of one group of the benchmark's case list, in list order (KeyError naming it if absent)."""
    cases = [c for c in CASE_LIST.cases if c.group == name]
    if not cases:
        raise KeyError(f"{CASE_LIST.path.name} has no group {name!r}")
    return cases


def _extra(case: Case) -> dict:
    """The friction options of a run (the in-house keyword arguments beyond method and tolerances)."""
    return {k: case.kwargs[k] for k in ("friction", "friction_eps") if k in case.kwargs}


REPEATS = 5
LONG_RUN = 5.0  # [s] runs at least this long are timed fewer than REPEATS times
LONG_RUN_TOTAL = 15.0  # [s] CPU allowed for the repeats of one long run
LEVELS = (1e-4, 1e-6, 1e-8)
EXUDYN_LEVELS = (1e-4, 1e-6)  # levels the Exudyn step is refined for (1e-8: out of reach)
OUTPUT_STEP = 0.01  # [s] sampling of the quick-return runs outside the sweeps (20 s runs, scaling)
EPS = DEFAULT_EPS  # the regularized friction's default width, the same on both engines
SWEEP_BUDGET = 6.0  # [s] stop halving a step / tightening a tolerance once one run costs more
EXUDYN_RUN_BUDGET = 150.0  # [s] largest predicted CPU of one order-2 refinement run of Exudyn (the
# slider-crank's index-2 run to 1e-6 is predicted at ~40-65 s here, depending on the machine's load)
MARGIN = 0.8  # aim the order-2 prediction at MARGIN * level
#: Exudyn's two configurations (study.exudyn_models.settings.CONFIGURATIONS), as work-precision engines:
#: 'tuned' is Exudyn as its documentation recommends for speed (symbolic user functions, plain constant
#: loads, no numerical load Jacobian unless a Python load needs it, one Jacobian per step); 'python'
#: evaluates every load law in a Python user function with full Newton (study.exudyn_models.run's default).
EXUDYN_ENGINES = {"Exudyn tuned": "tuned", "Exudyn (Python user functions)": "python"}
EXUDYN_REPEATS = 3  # every Exudyn run that enters a ratio is timed at least this often (median)
#: Mechanism -> (variant, horizon [s], friction options) of the work-precision sweeps: their reference runs.
CASES = {c.mechanism: (c.variant, c.t_end, _extra(c))
         for c in CASE_LIST.cases if c.group == f"{c.mechanism}: reference"}
#: Mechanism -> sampling step [s] of its runs (its reference group's output_step): every run of a mechanism is
#: compared on these samples, and its fixed steps divide it.
OUTPUT_STEPS = {c.mechanism: c.kwargs["output_step"] for c in CASE_LIST.cases if c.group == f"{c.mechanism}: reference"}
REF_RTOL = group(f"{next(iter(CASES))}: reference")[0].kwargs["rtol"]
REF_CHECK_RTOLS = tuple(c.kwargs["rtol"] for c in group(f"{next(iter(CASES))}: reference check"))
T2_LEVEL = 1e-8
T2_T_END = group("quick_return 20 s: DOP853")[0].t_end
T2_RTOLS = tuple(dict.fromkeys(c.kwargs["rtol"] for c in group("quick_return 20 s: DOP853")))  # a grid of decades
T2_REF_RTOL = group("quick_return 20 s: reference")[0].kwargs["rtol"]   # the independent reference: compiled RK45
T2_VARIANTS = tuple(c.variant for c in group("quick_return 20 s: reference"))
RATIO_LEVEL = 1e-6
#: Timings per point of the linearity fit (compiled runs of 4 ms ... 0.4 s): a median of 21 is stable to
#: ~1 % on a loaded machine where single timings of a few ms scatter by 20-50 %.
LINEAR_REPEATS = 21
#: Repeats of a timing in a ``--quick`` smoke run (instead of REPEATS).
QUICK_REPEATS = 2


def repeats(quick: bool) -> int:
    """Timings per measurement: :data:`REPEATS`, or :data:`QUICK_REPEATS` in a ``--quick`` run."""
    return QUICK_REPEATS if quick else REPEATS


#: The two ratios the benchmark reports, each like with like: the compiled in-house path against
#: tuned Exudyn, and the Python-bound in-house reference path against Exudyn with Python user functions.
COMPARISONS = {"compiled / Exudyn tuned": ("in-house compiled", "Exudyn tuned"),
               "reference / Exudyn (Python user functions)": ("in-house reference", "Exudyn (Python user functions)")}
