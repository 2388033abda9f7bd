"""The benchmark's settings: its mechanisms and horizons, accuracy levels, budgets, repeats and references.

Every number the benchmark's measurements are planned with; the targets they are judged against are in
:mod:`study.bench.targets` (thresholds in ``reference/tolerances.toml``).
"""

from __future__ import annotations

from pathlib import Path

from study.solver.friction import DEFAULT_EPS

OUT = Path(__file__).resolve().parents[2] / "reports" / "benchmarks"
REPEATS = 5
LONG_RUN = 5.0  # [s] runs at least this long are timed fewer than REPEATS times
LONG_RUN_TOTAL = 15.0  # [s] CPU allowed for the repeats of one long run
LEVELS = (1e-4, 1e-6, 1e-8)
EXUDYN_LEVELS = (1e-4, 1e-6)  # levels the Exudyn step is refined for (1e-8: out of reach)
OUTPUT_STEP = 0.01
EPS = DEFAULT_EPS  # the regularized friction's default width, the same on both engines
SWEEP_BUDGET = 6.0  # [s] stop halving a step / tightening a tolerance once one run costs more
EXUDYN_RUN_BUDGET = 150.0  # [s] largest predicted CPU of one order-2 refinement run of Exudyn (the
# slider-crank's index-2 run to 1e-6 is predicted at ~40-65 s here, depending on the machine's load)
MARGIN = 0.8  # aim the order-2 prediction at MARGIN * level
REF_RTOL = 5e-15
REF_CHECK_RTOLS = (1e-14, 2e-15)
#: Exudyn's two configurations (study.exudyn_models.settings.CONFIGURATIONS), as work-precision engines:
#: 'tuned' is Exudyn as its documentation recommends for speed (symbolic user functions, plain constant
#: loads, no numerical load Jacobian unless a Python load needs it, one Jacobian per step); 'python'
#: evaluates every load law in a Python user function with full Newton (the study's earlier setting).
EXUDYN_ENGINES = {"Exudyn tuned": "tuned", "Exudyn (Python user functions)": "python"}
EXUDYN_REPEATS = 3  # every Exudyn run that enters a ratio is timed at least this often (median)
T2_T_END = 20.0
T2_LEVEL = 1e-8
T2_RTOLS = (1e-10, 1e-11, 1e-12, 1e-13, 1e-14)   # a grid of decades (issue 15)
T2_REF_RTOL = 1e-14   # the independent reference: compiled RK45 (see independent_reference)
T2_VARIANTS = ("smooth_cutting", "seed")
CASES = {"quick_return": ("smooth_cutting", 5.0, {}),
         "slider_crank": ("sustained_sliding", 20.0, {"friction": "regularized", "friction_eps": EPS}),
         "four_bar": ("seed", 5.0, {})}
#: Mechanisms of the issue's table the benchmark has no case for yet: a row says so.
ABSENT = ("andrews",)
RATIO_LEVEL = 1e-6
#: Timings per point of the linearity fit (compiled runs of 4 ms ... 0.4 s): a median of 21 is stable to
#: ~1 % on a loaded machine where single timings of a few ms scatter by 20-50 %.
LINEAR_REPEATS = 21
#: Repeats of a timing in a ``--quick`` smoke run (instead of REPEATS).
QUICK_REPEATS = 2


def repeats(quick: bool) -> int:
    """Timings per measurement: :data:`REPEATS`, or :data:`QUICK_REPEATS` in a ``--quick`` run."""
    return QUICK_REPEATS if quick else REPEATS


#: The two ratios the benchmark reports (issue 15): like with like, the compiled in-house path against
#: tuned Exudyn, and the Python-bound in-house reference path against Exudyn with Python user functions.
COMPARISONS = {"compiled / Exudyn tuned": ("in-house compiled", "Exudyn tuned"),
               "reference / Exudyn (Python user functions)": ("in-house reference", "Exudyn (Python user functions)")}
