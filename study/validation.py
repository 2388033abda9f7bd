"""``study validate``: a user's mechanism through every in-house method and through Exudyn, with a report.

A user's mechanism is a Python file with ``describe(ps) -> study.Description`` beside its parameter file
``<same name>.toml`` (the format of ``reference/*.toml``); ``initial_guess(ps) -> (q, qd)`` is optional. Nothing in
the package names it. :func:`validate` runs, from the consistent initial state of the parameter file:

1. the in-house reference: DOP853 at the reference tolerances with post-step projection;
2. every stabilization method (none, Baumgarte, sliding mode, projection) at everyday settings (DOP853, rtol 1e-8),
   and, where a slider or a pin has friction, every friction treatment (exact, regularized, plain sgn with RK4);
3. Exudyn from the same description (:mod:`study.exudyn_models`), generalized-alpha index 3 and trapezoidal index 2,
   at three steps halving from ``h``; each against the in-house reference, with observed orders;
4. the joint reactions of both engines.

The runs are saved (``runs/``), the tables are written from them (``tables/``), the figures from the tables and the
saved runs (``figures/``), and ``report.md`` from the tables. Exudyn has regularized friction only, so where a
slider or pin has friction the comparison with Exudyn is at the regularized law (width ``friction_eps``) on both sides.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from study.compare import common_samples, max_deviation, observed_orders
from study.errors import SimulationError
from study.errors import ResultIntegrityError
from study.model import Mechanism
from study.output_folder import claim_output_folder
from study.pipeline.tables import forget_table, table_names, write_table
from study.reference_data import tolerance
from study.results import SimulationResult
from study.solver.friction import PainleveError

METHODS = ("none", "baumgarte", "sliding_mode", "projection")
EXUDYN_SOLVERS = ("index3", "index2")
EVERYDAY = {"integrator": "DOP853", "rtol": 1e-8, "atol": 1e-10}


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
    """Whether a slider's contact or a pin of the mechanism carries friction data."""
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


def _in_house_runs(mech: Mechanism, s: Settings, say: Callable[[str], None]) -> tuple[dict, dict[str, str]]:
    """The runs of :func:`_in_house_plan`, each with progress lines when long; a run that stops with a simulation
    error (other than the reference, which everything is compared with) is recorded with it."""
    from study.progress import ProgressPrinter
    from study.simulate import simulate

    plan = _in_house_plan(mech, s)
    runs, failed = {}, {}
    for k, (name, options) in enumerate(plan.items(), 1):
        say(f"[{k}/{len(plan)}] in-house {name}")
        try:
            runs[name] = simulate(mech, t_end=s.t_end, output_step=s.output_step, **options,
                                  progress=ProgressPrinter(s.t_end, say, label="    "))
        except (SimulationError, PainleveError) as exc:
            if name == "reference":
                raise
            failed[name] = f"{type(exc).__name__}: {exc}"
    return runs, failed


def _exudyn_runs(mech: Mechanism, s: Settings, say: Callable[[str], None]) -> tuple[dict, dict[tuple, str]]:
    """Exudyn at every solver and step; a run Exudyn refuses or that fails is recorded with its error."""
    from study.exudyn_models import ExudynModelError, ExudynSolverError, run

    friction = "regularized" if _friction(mech) else "none"
    runs, failed = {}, {}
    plan = [(solver, h) for solver in EXUDYN_SOLVERS for h in s.steps]
    for k, (solver, h) in enumerate(plan, 1):
        say(f"[{k}/{len(plan)}] Exudyn {solver} h = {h:g} s ({round(s.t_end / h)} steps)")
        try:
            runs[(solver, h)] = run(mech, s.t_end, h, solver=solver, output_step=s.output_step, friction=friction,
                                    eps=s.friction_eps, configuration="tuned")
        except (ExudynSolverError, ExudynModelError) as exc:   # a finding of the report, named with its error
            failed[(solver, h)] = f"{type(exc).__name__}: {exc}"
    return runs, failed


def tables(mech: Mechanism, s: Settings, inhouse: dict, exudyn: dict, failed: dict,
           inhouse_failed: dict) -> dict[str, pd.DataFrame]:
    """The report's tables from the runs."""
    ref = inhouse["reference"]
    eom = mech.equations()
    state = mech.initial_state()
    initial = pd.DataFrame({"coordinate": eom.coordinate_names, "q0": state.q, "qd0": state.qd,
                            "independent": [i in mech.parameters.initial.independent
                                            for i in range(eom.n_coordinates)]})
    rows = []
    for name, r in inhouse.items():
        summary = r.summary()
        rows.append({"run": name, "integrator": r.meta["integrator"], "rtol": r.meta.get("rtol"),
                     "step": r.meta.get("step"), "friction": r.meta.get("friction"),
                     "max_abs_dq_vs_reference": np.nan if name == "reference" else max_deviation(r, ref, "q"),
                     "max_abs_phi": summary["max_abs_phi"], "max_abs_phidot": summary["max_abs_phidot"],
                     "energy_balance_error_J": summary["energy_error"], "cpu_s": summary["cpu_seconds"],
                     "steps": r.stats.get("steps"), "events": r.stats.get("events"), "error": ""})
    rows += [{"run": name, "error": error} for name, error in inhouse_failed.items()]
    methods = pd.DataFrame(rows)
    rows = []
    for (solver, h), r in sorted(exudyn.items(), key=lambda item: (EXUDYN_SOLVERS.index(item[0][0]), -item[0][1])):
        rows.append({"solver": solver, "h": h, "max_abs_dq": max_deviation(r, ref, "q"),
                     "max_abs_dqd": max_deviation(r, ref, "qd"), "max_abs_phi": r.summary()["max_abs_phi"],
                     "energy_balance_error_J": r.summary()["energy_error"], "cpu_s": r.stats.get("cpu_seconds"),
                     "error": ""})
    rows += [{"solver": solver, "h": h, "error": error} for (solver, h), error in sorted(failed.items())]
    convergence = pd.DataFrame(rows, columns=["solver", "h", "max_abs_dq", "max_abs_dqd", "max_abs_phi",
                                              "energy_balance_error_J", "cpu_s", "error"])
    rows = []
    for solver, g in convergence[convergence["error"] == ""].groupby("solver", sort=False):
        g = g.sort_values("h", ascending=False)
        if len(g) < 2:
            continue
        for field in ("max_abs_dq", "max_abs_dqd"):
            orders = observed_orders(g["h"].to_numpy(), g[field].to_numpy())
            floor = tolerance("order_error_floor", table="cross_validation")
            rows.append({"solver": solver, "quantity": field[len("max_abs_d"):], "orders": ", ".join(f"{p:.3f}" for p in orders),
                         "min_order": float(orders.min()), "smallest_error": float(g[field].min()),
                         "above_error_floor": bool(g[field].min() > floor),
                         "meets_min_order": bool(orders.min() >= tolerance("min_order", table="cross_validation"))})
    orders = pd.DataFrame(rows, columns=["solver", "quantity", "orders", "min_order", "smallest_error",
                                         "above_error_floor", "meets_min_order"])
    reactions = _reactions(mech, ref, exudyn)
    return {"initial_state": initial, "in_house": methods, "exudyn_convergence": convergence, "exudyn_orders": orders,
            "reactions": reactions}


def _reactions(mech: Mechanism, ref: SimulationResult, exudyn: dict) -> pd.DataFrame:
    """Every joint's reaction, in-house (from the reference) against Exudyn's finest index-3 run."""
    from study.reactions import joint_reactions

    index3 = sorted((h, r) for (solver, h), r in exudyn.items() if solver == "index3")
    if not index3:
        return pd.DataFrame(columns=["reaction", "exudyn_h", "max_abs_in_house_N", "max_abs_difference_N",
                                     "difference_relative"])
    h, ex = index3[0]
    inhouse = joint_reactions(mech, ref)
    ia, ib = common_samples(ref, ex)
    rows = []
    for k, v in inhouse.items():
        if k in ex.forces:
            scale, diff = float(np.abs(v).max()), float(np.abs(v[ia] - ex.forces[k][ib]).max())
            rows.append({"reaction": k, "exudyn_h": h, "max_abs_in_house_N": scale, "max_abs_difference_N": diff,
                         "difference_relative": diff / scale if scale > 0 else np.nan})
    return pd.DataFrame(rows)


def validate(mech: Mechanism, settings: Settings, out: str | Path,
             say: Callable[[str], None] = print) -> dict[str, pd.DataFrame]:
    """Run a mechanism through every engine and write ``out/report.md`` with its tables, figures and saved runs
    (``runs/``, ``tables/``, ``figures/``). ``out`` must be new, empty or a folder study made (its marker): a user's
    folder is refused before any work. What an earlier validation wrote there is removed first, so nothing of it is
    read back; nothing else is touched. A failed run is a row of the tables with its error; the reference run must
    succeed."""
    from study.validation_plan import check_plan
    from study.validation_report import FIGURES, order_lines, write_report

    estimate = check_plan(mech, settings, _in_house_plan(mech, settings), len(EXUDYN_SOLVERS))
    out = claim_output_folder(Path(out))
    _remove_previous(out, FIGURES)
    (out / "runs").mkdir(exist_ok=True)
    t0 = time.perf_counter()
    say(f"validate {mech.name}: {mech.equations().n_coordinates} coordinates, "
        f"{mech.equations().n_constraints} constraint rows, t_end = {settings.t_end:g} s")
    say(estimate)
    inhouse, inhouse_failed = _in_house_runs(mech, settings, say)
    exudyn, failed = _exudyn_runs(mech, settings, say)
    for name, r in inhouse.items():
        r.save(out / "runs" / ("inhouse_" + name.replace(" ", "_").replace("(", "").replace(")", "")))
    for (solver, h), r in exudyn.items():
        r.save(out / "runs" / f"exudyn_{solver}_h{h:g}")
    result = tables(mech, settings, inhouse, exudyn, failed, inhouse_failed)
    command = (f"python -m study validate {mech.parameters.path.with_suffix('.py')} --out {out}"
               if mech.parameters.path.suffix == ".toml" else f"study.validate({mech.name}, ..., out='{out}') again")
    for name, table in result.items():
        write_table(out / "tables" / f"{name}.csv", table.to_csv(index=False), command)
    path = write_report(mech, settings, out)
    for line in order_lines(result["exudyn_orders"], mech.equations(), settings.friction_eps):
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
