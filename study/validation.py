"""``study validate``: a user's mechanism through every in-house method and through Exudyn, with a report.

A user's mechanism is a Python file with ``describe(ps) -> study.Description`` beside its parameter file
``<same name>.toml`` (the format of ``reference/*.toml``); ``initial_guess(ps) -> (q, qd)`` is optional. Nothing in
the package names it. :func:`validate` runs, from the consistent initial state of the parameter file:

1. the in-house reference: DOP853 at the reference tolerances with post-step projection;
2. every stabilization method (none, Baumgarte, sliding mode, projection) at everyday settings (DOP853, rtol 1e-8),
   and, where a slider or a joint has friction, every friction treatment (exact, regularized, plain sgn with RK4);
3. Exudyn from the same description (:mod:`study.exudyn_models`), generalized-alpha index 3 and trapezoidal index 2,
   at three steps halving from ``h``; each against the in-house reference, with observed orders;
4. the joint reactions of both engines.

The runs are a generated case list (:func:`validation_cases`: cases of the pipeline, :mod:`study.pipeline.cases`,
whose mechanism is the Mechanism given) run by the pipeline's runner in this process and saved in its store
(``<cache>/runs``, :mod:`study.cache_folder`), so a second validation of the same mechanism at the same settings
reads its runs back instead of running them again. Their differences from the reference and Exudyn's observed orders
are computed by the cross-validation study's functions (:mod:`study.studies.cross_validation`). A copy of each run is
saved in the report folder (``runs/``), the tables are written from the runs (``tables/``), the figures from the
tables and the saved runs (``figures/``), and ``report.md`` from the tables. Exudyn has regularized friction only,
so where a slider or a joint (a planar pin, a spatial revolute or prismatic joint) has friction the comparison with
Exudyn is at the regularized law (width ``friction_eps``, m/s for a sliding rate, rad/s for a turning one) on both
sides.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from study.cache_folder import cache_dir
from study.errors import ResultIntegrityError, SimulationError
from study.model import Mechanism
from study.output_folder import claim_output_folder
from study.pipeline import Case, Store
from study.pipeline.tables import forget_table, table_names, write_table
from study.reference_data import tolerance
from study.results import SimulationResult
from study.compare import common_samples
from study.studies.cross_validation import joint_force_deviations, state_deviations, with_orders

METHODS = ("none", "baumgarte", "sliding_mode", "projection")
EXUDYN_SOLVERS = ("index3", "index2")
EVERYDAY = {"integrator": "DOP853", "rtol": 1e-8, "atol": 1e-10}
FIELDS = ("max_abs_dq", "max_abs_dqd")   # Exudyn against the in-house reference: these differences and their orders
STUDY = "validate"   # the study name of the validation's cases


@dataclass(frozen=True)
class Settings:
    """What :func:`validate` runs. ``h``: Exudyn's largest step [s] (then h/2, h/4); ``output_step`` [s] divides
    t_end and is a whole multiple of every Exudyn step."""

    t_end: float = 1.0
    output_step: float = 0.01
    h: float = 2e-3
    levels: int = 3
    friction_eps: float = 1e-3

    def __post_init__(self) -> None:
        for name in ("t_end", "output_step", "h", "friction_eps"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                raise ValueError(f"validate: {name} = {value!r} must be a finite number > 0")
        if isinstance(self.levels, bool) or not isinstance(self.levels, (int, np.integer)):
            raise ValueError(f"validate: levels = {self.levels!r} must be a whole number (of Exudyn steps, "
                             f"halving from h)")
        if self.levels < 2:
            raise ValueError(f"validate: levels = {self.levels!r}: an observed order needs at least 2 steps")
        top = int(tolerance("validate_max_levels"))
        if self.levels > top:
            raise ValueError(f"validate: levels = {self.levels} is above validate_max_levels = {top} "
                             f"(reference/tolerances.toml): {2 * self.levels} Exudyn runs with steps halving from "
                             f"{self.h:g} s to {math.ldexp(self.h, 1 - self.levels):.3g} s, whose second-order "
                             f"errors would fall below what an observed order can measure; use at most {top} levels")
        finest, smallest = self.steps[-1], tolerance("validate_min_step")
        if finest < smallest:
            raise ValueError(f"validate: the finest Exudyn step h/2^(levels-1) = {self.h:g}/2^{self.levels - 1} = "
                             f"{finest:.3g} s is below validate_min_step = {smallest:g} s (reference/tolerances.toml: "
                             f"below it Newton's tolerance, not the step, decides Exudyn's error, so an observed order "
                             f"no longer measures the method): use a larger h (--h) or fewer levels (--levels)")
        for label, num, den in (("t_end", self.t_end, self.output_step),
                                ("output_step", self.output_step, self.h / 2 ** (self.levels - 1))):
            ratio = num / den
            if abs(ratio - round(ratio)) > 1e-9 * ratio or round(ratio) < 1:
                raise ValueError(f"validate: {label} = {num:g} s is not a whole multiple of {den:g} s (the output "
                                 f"step, and the finest Exudyn step h/2^(levels-1))")

    @property
    def steps(self) -> list[float]:
        return [self.h / 2 ** k for k in range(self.levels)]


def _friction(mech: Mechanism) -> bool:
    """Whether a slider's contact or a joint of the mechanism (a planar pin, a spatial revolute or prismatic joint)
    carries friction data."""
    eom = mech.equations()
    return bool(eom.contacts or eom.pin_frictions)


def _in_house_plan(mech: Mechanism, s: Settings) -> dict[str, dict]:
    """The in-house runs by name with their options: the reference, every method at everyday settings, and (with
    friction) every treatment."""
    law = {"friction": "regularized", "friction_eps": s.friction_eps} if _friction(mech) else {}
    reference = {"integrator": "DOP853", "rtol": tolerance("reference_rtol"), "atol": tolerance("reference_atol")}
    plan = {"reference": {**reference, "method": "projection", **law}}
    plan.update({f"method {m}": {**EVERYDAY, "method": m, **law} for m in METHODS})
    if law:
        plan["friction exact"] = {**EVERYDAY, "method": "projection", "friction": "exact"}
        plan["friction sign (RK4)"] = {"integrator": "RK4", "step": s.h / 2 ** (s.levels - 1), "method": "projection",
                                       "friction": "sign", "friction_eps": s.friction_eps}
    return plan


def validation_cases(mech: Mechanism, s: Settings) -> tuple[Case, ...]:
    """The validation's case list, the cases the pipeline runs (:mod:`study.pipeline.cases`): the in-house runs of
    :func:`_in_house_plan` (group = the run's name), then Exudyn at every solver (group ``Exudyn <solver>``) and step
    (label ``h``); each case's options are its engine's run specification (:func:`study.engines.spec_from_dict`,
    which refuses a wrong one by name here, before any run), its mechanism is ``mech`` itself."""
    from study.engines import spec_from_dict

    plan = [(name, "inhouse", options, ()) for name, options in _in_house_plan(mech, s).items()]
    friction = "regularized" if _friction(mech) else "none"
    plan += [(f"Exudyn {solver}", "exudyn", {"solver": solver, "h": h, "friction": friction, "eps": s.friction_eps,
                                            "configuration": "tuned"}, (("h", f"{h:g}"),))
             for solver in EXUDYN_SOLVERS for h in s.steps]
    cases = []
    for group, engine, options, labels in plan:
        options = {**options, "output_step": s.output_step}
        spec_from_dict({"engine": engine, **options})
        cases.append(Case(STUDY, group, engine, mech, mech.parameters.variant, s.t_end, tuple(sorted(options.items())),
                          labels))
    return tuple(cases)


def _announcer(cases: tuple[Case, ...], s: Settings, say: Callable[[str], None]):
    """What the pipeline calls just before a case runs: its line, and for an in-house run the progress printer."""
    from study.progress import ProgressPrinter

    inhouse = [c for c in cases if c.engine == "inhouse"]
    exudyn = [c for c in cases if c.engine == "exudyn"]

    def announce(case: Case):
        if case.engine == "inhouse":
            say(f"[{inhouse.index(case) + 1}/{len(inhouse)}] in-house {case.group}")
            return ProgressPrinter(s.t_end, say, label="    ")
        h = case.kwargs["h"]
        say(f"[{exudyn.index(case) + 1}/{len(exudyn)}] Exudyn {case.kwargs['solver']} h = {h:g} s "
            f"({round(s.t_end / h)} steps)")
        return None
    return announce


class _Lines:
    """A text stream whose lines go to ``say``: the pipeline's progress line among the validation's own."""

    def __init__(self, say: Callable[[str], None]):
        self.say, self.pending = say, ""

    def write(self, text: str) -> int:
        *lines, self.pending = (self.pending + text).split("\n")
        for line in lines:
            self.say(line.lstrip("\r"))
        return len(text)

    def flush(self) -> None:
        pass


def _run(cases: tuple[Case, ...], store: Store, s: Settings,
         say: Callable[[str], None]) -> tuple[dict[Case, SimulationResult], dict[Case, str]]:
    """Every case not saved in ``store`` yet run by the pipeline, in this process and in list order (cached: a case
    saved earlier from the same inputs is read back); returns the results and the failed cases' errors. The reference,
    which everything is compared with, must succeed."""
    from study.pipeline import InlineExecutor, run_cases

    done = run_cases(cases, store, InlineExecutor(), title=f"validate {cases[0].mechanism.name}",
                     stream=_Lines(say), announce=_announcer(cases, s, say))
    if done.cached:
        say(f"{done.cached} of {len(cases)} runs re-used from {store.root} (saved earlier from the same inputs)")
    results = {c: store.load(c) for c in cases if store.has(c)}
    errors = {c: store.failure(c)["error"] for c in cases if c not in results}
    reference = cases[0]
    if reference in errors:
        raise SimulationError(f"validate: the in-house reference run failed, and every other run is compared with "
                              f"it: {errors[reference]}")
    return results, errors


def _run_file(case: Case) -> str:
    """A run's file name in ``out/runs`` (without suffix)."""
    if case.engine == "exudyn":
        return f"exudyn_{case.kwargs['solver']}_h{case.kwargs['h']:g}"
    return "inhouse_" + case.group.replace(" ", "_").replace("(", "").replace(")", "")


def tables(mech: Mechanism, results: dict[Case, SimulationResult], errors: dict[Case, str]) -> dict[str, pd.DataFrame]:
    """The report's tables from the runs (case -> result) and the failed runs' errors; the differences and orders are
    the cross-validation study's (:mod:`study.studies.cross_validation`)."""
    ref = next(r for c, r in results.items() if c.group == "reference")
    eom = mech.equations()
    state = mech.initial_state()
    initial = pd.DataFrame({"coordinate": eom.coordinate_names, "q0": state.q, "qd0": state.qd,
                            "independent": [i in mech.parameters.initial.independent
                                            for i in range(eom.n_coordinates)]})
    convergence = _convergence(results, errors, ref)
    exudyn = {c.kwargs["h"]: r for c, r in results.items() if c.engine == "exudyn" and c.kwargs["solver"] == "index3"}
    return {"initial_state": initial, "in_house": _in_house(results, errors, ref), "exudyn_convergence": convergence,
            "exudyn_orders": _orders(convergence), "reactions": _reactions(mech, ref, exudyn)}


def _in_house(results: dict[Case, SimulationResult], errors: dict[Case, str], ref: SimulationResult) -> pd.DataFrame:
    """One row per in-house run: its settings, its distance from the reference, its constraint and energy errors."""
    rows = []
    for case, r in results.items():
        if case.engine != "inhouse":
            continue
        summary = r.summary()
        rows.append({"run": case.group, "integrator": r.meta["integrator"], "rtol": r.meta.get("rtol"),
                     "step": r.meta.get("step"), "friction": r.meta.get("friction"),
                     "max_abs_dq_vs_reference": np.nan if case.group == "reference"
                     else state_deviations(r, ref, ("q",))["max_abs_dq"],
                     "max_abs_phi": summary["max_abs_phi"], "max_abs_phidot": summary["max_abs_phidot"],
                     "energy_balance_error_J": summary["energy_error"], "cpu_s": summary["cpu_seconds"],
                     "steps": r.stats.get("steps"), "events": r.stats.get("events"), "error": ""})
    rows += [{"run": case.group, "error": error} for case, error in errors.items() if case.engine == "inhouse"]
    return pd.DataFrame(rows)


def _convergence(results: dict[Case, SimulationResult], errors: dict[Case, str], ref: SimulationResult) -> pd.DataFrame:
    """One row per Exudyn run (solver by solver, h decreasing; the failed ones last): its distance from the reference
    in q and qd, its constraint and energy errors."""
    rows = []
    for case, r in results.items():
        if case.engine == "exudyn":
            summary = r.summary()
            rows.append({"solver": case.kwargs["solver"], "h": case.kwargs["h"], **state_deviations(r, ref, ("q", "qd")),
                         "max_abs_phi": summary["max_abs_phi"], "energy_balance_error_J": summary["energy_error"],
                         "cpu_s": r.stats.get("cpu_seconds"), "error": ""})
    failed = sorted((c.kwargs["solver"], c.kwargs["h"], error) for c, error in errors.items() if c.engine == "exudyn")
    rows += [{"solver": solver, "h": h, "error": error} for solver, h, error in failed]
    return pd.DataFrame(rows, columns=["solver", "h", "max_abs_dq", "max_abs_dqd", "max_abs_phi",
                                       "energy_balance_error_J", "cpu_s", "error"])


def _orders(convergence: pd.DataFrame) -> pd.DataFrame:
    """Each solver's observed orders in q and qd over its successive steps, judged against ``min_order`` where the
    smallest error is above ``order_error_floor`` (reference/cross_validation.toml)."""
    ok = with_orders(convergence[convergence["error"] == ""], FIELDS, by=("solver",))
    floor = tolerance("order_error_floor", table="cross_validation")
    min_order = tolerance("min_order", table="cross_validation")
    rows = []
    for solver, g in ok.groupby("solver", sort=False):
        g = g.sort_values("h", ascending=False)
        if len(g) < 2:
            continue
        for field in FIELDS:
            quantity = field[len("max_abs_d"):]
            orders = g[f"order_d{quantity}"].to_numpy(float)[1:]
            rows.append({"solver": solver, "quantity": quantity, "orders": ", ".join(f"{p:.3f}" for p in orders),
                         "min_order": float(orders.min()), "smallest_error": float(g[field].min()),
                         "above_error_floor": bool(g[field].min() > floor),
                         "meets_min_order": bool(orders.min() >= min_order)})
    return pd.DataFrame(rows, columns=["solver", "quantity", "orders", "min_order", "smallest_error",
                                       "above_error_floor", "meets_min_order"])


def _reactions(mech: Mechanism, ref: SimulationResult, index3: dict[float, SimulationResult]) -> pd.DataFrame:
    """Every joint's reaction, in-house (from the reference) against Exudyn's finest index-3 run (by step h), by the
    mechanism's kind (REACTIONS)."""
    rows = []
    if index3:
        h = min(index3)
        rows = [{"reaction": k, "exudyn_h": h, "max_abs_in_house_N": scale, "max_abs_difference_N": diff,
                 "difference_relative": diff / scale if scale > 0 else np.nan}
                for k, (diff, scale) in REACTIONS[mech.kind](mech, ref, index3[h]).items()]
    return pd.DataFrame(rows, columns=["reaction", "exudyn_h", "max_abs_in_house_N", "max_abs_difference_N",
                                       "difference_relative"])


def _planar_reactions(mech: Mechanism, ref: SimulationResult, ex: SimulationResult) -> dict[str, tuple[float, float]]:
    """The joints' force components (:func:`study.reactions.joint_reactions`) that Exudyn's run outputs."""
    from study.reactions import joint_reactions

    inhouse = {k: v for k, v in joint_reactions(mech, ref).items() if k in ex.forces}
    return joint_force_deviations(ex, ref, inhouse)


def _multiplier_reactions(mech: Mechanism, ref: SimulationResult,
                          ex: SimulationResult) -> dict[str, tuple[float, float]]:
    """A spatial mechanism's joint rows' multipliers (a translation row's a force [N], a rotation row's a moment
    [N m]), both results in the rows of ``mech.equations()`` (study.exudyn_models.spatial maps Exudyn's); the
    Euler-parameter norm rows carry no reaction and are left out."""
    ia, ib = common_samples(ex, ref)
    norms = {f"{body}_norm" for body in mech.description.bodies}
    return {name: (float(np.abs(ex.lam[ia, k] - ref.lam[ib, k]).max()), float(np.abs(ref.lam[ib, k]).max()))
            for k, name in enumerate(mech.equations().constraint_names) if name not in norms}


#: a mechanism's kind -> (mechanism, in-house reference, Exudyn run) -> reaction name -> (max |difference|, max |in-house|)
REACTIONS = {"planar": _planar_reactions, "spatial": _multiplier_reactions}


def validate(mech: Mechanism, settings: Settings, out: str | Path,
             say: Callable[[str], None] = print) -> dict[str, pd.DataFrame]:
    """Run a mechanism through every engine and write ``out/report.md`` with its tables, figures and saved runs
    (``runs/``, ``tables/``, ``figures/``). ``out`` must be new, empty or a folder study made (its marker): a user's
    folder is refused before any work. What an earlier validation wrote there is removed first, so nothing of it is
    read back; nothing else is touched. The runs come from the pipeline's store (:func:`_run`: computed, or read back
    when an earlier validation saved them). A failed run is a row of the tables with its error; the reference run
    must succeed (a SimulationError naming its error otherwise)."""
    from study.validation_plan import check_plan
    from study.validation_report import FIGURES, order_lines, write_report

    estimate = check_plan(mech, settings, _in_house_plan(mech, settings), len(EXUDYN_SOLVERS))
    cases = validation_cases(mech, settings)
    store = Store(cache_dir() / "runs")   # the pipeline's saved runs: a case saved before is not run again
    out = claim_output_folder(Path(out))
    _remove_previous(out, FIGURES)
    (out / "runs").mkdir(exist_ok=True)
    t0 = time.perf_counter()
    say(f"validate {mech.name}: {mech.equations().n_coordinates} coordinates, "
        f"{mech.equations().n_constraints} constraint rows, t_end = {settings.t_end:g} s")
    say(estimate)
    results, errors = _run(cases, store, settings, say)
    for case, r in results.items():
        r.save(out / "runs" / _run_file(case))
    result = tables(mech, results, errors)
    command = (f"python -m study validate {mech.parameters.path.with_suffix('.py')} --out {out}"
               if mech.parameters.path.suffix == ".toml" else f"study.validate({mech.name}, ..., out='{out}') again")
    for name, table in result.items():
        write_table(out / "tables" / f"{name}.csv", table.to_csv(index=False), command)
    path = write_report(mech, settings, out)
    for line in order_lines(result["exudyn_orders"], mech, settings.friction_eps):
        say(line)
    say(f"wrote {path} ({time.perf_counter() - t0:.0f} s)")
    return result


def _remove_previous(out: Path, figures: tuple[str, ...]) -> None:
    """Remove what an earlier validation wrote into ``out``: its saved runs (result pairs that pass their check),
    the tables its record lists, and its figures (by name). A user's files there are left alone."""
    for side in sorted((out / "runs").glob("*.json")):
        base = side.with_suffix("")
        try:
            SimulationResult.verify(base)
        except (ResultIntegrityError, OSError):
            continue
        side.with_suffix(".csv").unlink(missing_ok=True)
        side.unlink()
    for name in table_names(out / "tables"):
        forget_table(out / "tables" / name)
    for stem in figures:
        (out / "figures" / f"{stem}.png").unlink(missing_ok=True)
