"""The report of ``study validate``: figures from the saved runs and tables, and ``report.md`` from the tables."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from study.model import Mechanism  # noqa: E402
from study.pipeline.tables import read_table  # noqa: E402
from study.reference_data import tolerance  # noqa: E402
from study.report.render import fmt_number, frame_table  # noqa: E402
from study.results import SimulationResult  # noqa: E402
from study.spatial.elements import Prismatic  # noqa: E402


MAX_PANELS = 8   # coordinates drawn, one panel each
FIGURES = ("trajectories", "constraint_violation", "exudyn_convergence")   # figures/<stem>.png, each drawn once


def _figures(out: Path, convergence: pd.DataFrame, coordinates: list[str]) -> list[str]:
    """Trajectories, constraint violation and Exudyn's convergence; returns the figure files (relative to out)."""
    runs, folder = out / "runs", out / "figures"
    folder.mkdir(exist_ok=True)
    names = []
    ref = SimulationResult.load(runs / "inhouse_reference")
    exudyn = sorted(runs.glob("exudyn_index3_h*.csv"), key=lambda p: float(p.stem.split("_h")[1]))
    shown = coordinates[:MAX_PANELS]
    fig, axes = plt.subplots(len(shown), 1, figsize=(8, 1.2 + 1.8 * len(shown)), sharex=True, squeeze=False)
    ex = SimulationResult.load(exudyn[0].with_suffix("")) if exudyn else None
    for i, (name, ax) in enumerate(zip(shown, axes[:, 0])):
        ax.plot(ref.t, ref.q[:, i], lw=1.8, label="in-house reference")
        if ex is not None:
            ax.plot(ex.t, ex.q[:, i], "--", lw=1.2, label=f"Exudyn index 3, h = {ex.meta['h']:g} s")
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    axes[0, 0].set_title("Coordinates" + (f" (the first {MAX_PANELS} of {len(coordinates)})"
                                          if len(coordinates) > MAX_PANELS else ""))
    axes[-1, 0].set_xlabel("t [s]")
    names.append(_save(fig, folder, "trajectories"))

    if ref.phi.shape[1] == 0:   # no constraint rows (free bodies held by loads): no violation to draw
        return names + _convergence_figure(folder, convergence)
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for path in sorted(runs.glob("inhouse_method_*.csv")):
        r = SimulationResult.load(path.with_suffix(""))
        if r.phi.size:
            ax.semilogy(r.t, np.maximum(np.abs(r.phi).max(axis=1), 1e-18), label=path.stem[len("inhouse_method_"):])
    _finish(ax, "t [s]", "max |Φ| (floored at 1e-18)", "Constraint violation of every stabilization method "
            "(DOP853, rtol 1e-8)")
    names.append(_save(fig, folder, "constraint_violation"))
    return names + _convergence_figure(folder, convergence)


def _convergence_figure(folder: Path, convergence: pd.DataFrame) -> list[str]:
    ok = convergence[convergence["error"].isna()]   # read with na_values [""]: a run without error
    names = []
    if len(ok):
        fig, ax = plt.subplots(figsize=(6, 4.5))
        for solver, g in ok.groupby("solver", sort=False):
            ax.loglog(g["h"], g["max_abs_dq"], "o-", label=f"{solver}: max|q − q_ref|")
            ax.loglog(g["h"], g["max_abs_dqd"], "s--", label=f"{solver}: max|q̇ − q̇_ref|")
        h = np.sort(ok["h"].unique())
        ax.loglog(h, ok["max_abs_dq"].max() * (h / h[-1]) ** 2, "k:", label="slope 2")
        _finish(ax, "h [s]", "deviation from the in-house reference", "Exudyn against the in-house reference")
        names.append(_save(fig, folder, "exudyn_convergence"))
    return names


def _finish(ax, xlabel: str, ylabel: str, title: str) -> None:
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")


def _save(fig, folder: Path, stem: str) -> str:
    fig.tight_layout()
    fig.savefig(folder / f"{stem}.png", dpi=120)
    plt.close(fig)
    return f"figures/{stem}.png"


def _table(df: pd.DataFrame) -> str:
    """The table with its numbers to 3 significant digits."""
    return frame_table(df.map(lambda v: fmt_number(v) if isinstance(v, (float, np.floating)) else str(v)), df)


def _width_unit(mech: Mechanism) -> str:
    """The unit of the regularized friction's width for the mechanism's friction entries ('' without friction): m/s
    for a planar slider's contact and a spatial prismatic joint (a sliding rate), rad/s for a pin and a spatial
    revolute joint (a turning rate)."""
    if mech.kind == "spatial":
        d = mech.description
        kinds = {type(j) for j in d.joints if j.name in d.frictions}
        units = [*(["m/s"] if Prismatic in kinds else []), *(["rad/s"] if kinds - {Prismatic} else [])]
    else:
        eom = mech.equations()
        units = [*(["m/s"] if eom.contacts else []), *(["rad/s"] if eom.pin_frictions else [])]
    return " or ".join(units)


def order_lines(orders: pd.DataFrame, mech: Mechanism, friction_eps: float) -> list[str]:
    """One line per solver and quantity: its observed orders and the verdict, with the likely cause of an order
    below ``min_order``: with regularized friction, the law's width unresolved by the steps near sticking or a
    reversal."""
    min_order = tolerance("min_order", table="cross_validation")
    unit = _width_unit(mech)
    lines = []
    for _, r in orders.iterrows():
        if not r["above_error_floor"]:
            verdict = ("not judged: the smallest error is below the floor where the reference's and Newton's own "
                       "errors enter (`reference/cross_validation.toml` order_error_floor)")
        elif r["meets_min_order"]:
            verdict = f"second order, as both solvers are (every order ≥ {min_order:g})"
        elif unit:
            verdict = (f"**below {min_order:g}**: probably the regularized friction's width (friction_eps = "
                       f"{friction_eps:g} {unit}) is not resolved by Exudyn's steps near sticking or a reversal: the law "
                       f"turns from -mu N to +mu N over |v| < friction_eps, which a step of h crosses at once. Remedy: a larger "
                       f"friction_eps (--friction-eps), or finer steps (a smaller --h, or more --levels)")
        else:
            verdict = f"**below {min_order:g}**: a finding (an unresolved load ramp, a switch, or a mapping error)"
        lines.append(f"- {r['solver']}, {r['quantity']}: observed orders {r['orders']}; {verdict}.")
    return lines


def write_report(mech: Mechanism, settings, out: Path) -> Path:
    """``out/report.md`` from ``out/tables`` and the figures drawn from ``out/runs``."""
    t = {name: read_table(out / "tables" / f"{name}.csv", keep_default_na=False, na_values=[""])
         for name in ("initial_state", "in_house", "exudyn_convergence", "exudyn_orders", "reactions")}
    eom = mech.equations()
    figures = _figures(out, t["exudyn_convergence"], list(eom.coordinate_names))
    lines = [f"# Validation of {mech.name}", "",
             f"{eom.n_coordinates} coordinates ({', '.join(eom.coordinate_names)}), {eom.n_constraints} constraint "
             f"rows, {len(eom.contacts)} contacts and {len(eom.pin_frictions)} joints with friction; parameters `{mech.parameters.path.name}` (variant "
             f"`{mech.parameters.variant}`); horizon {settings.t_end:g} s, samples every {settings.output_step:g} s.",
             "", "## Consistent initial state", "", _table(t["initial_state"]), ""]
    methods = t["in_house"]
    ref = methods[methods["run"] == "reference"].iloc[0]
    lines += ["## In-house methods", "",
              f"The reference is DOP853 at rtol {fmt_number(ref['rtol'])} with post-step projection "
              f"(max|Φ| {fmt_number(ref['max_abs_phi'])}, energy balance error {fmt_number(ref['energy_balance_error_J'])}"
              f" J). Every other run is compared with it (where a run's friction treatment differs from the reference's, "
              "the difference includes the laws' own); the energy balance error is the largest change of kinetic + "
              "potential energy − work of the loads and of friction over the run.", "",
              _table(methods), ""]
    lines += ["## Exudyn", "",
              "Exudyn's model is generated from the same description (`study.exudyn_models`), not from the in-house "
              "equations, and starts from the same consistent state." + (
                  f" Friction is the regularized law on both sides (width {settings.friction_eps:g} "
                  f"{_width_unit(mech)})." if _width_unit(mech) else ""), "", _table(t["exudyn_convergence"]), ""]
    lines += order_lines(t["exudyn_orders"], mech, settings.friction_eps) + [""]
    if len(t["reactions"]):
        lines += ["## Joint reactions", "", "In-house (reference run, absolute-coordinate multipliers) against "
                  "Exudyn's joint forces (finest index-3 run):", "", _table(t["reactions"]), ""]
    lines += ["## Figures", ""] + [f"![{Path(f).stem}]({f})" for f in figures] + [""]
    path = out / "report.md"
    path.write_text("\n".join(lines))
    return path
