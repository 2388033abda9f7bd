"""From the sweeps' runs to CPU at each accuracy level (part b) and the in-house / Exudyn ratios (part c).

Pure functions of the work-precision table (``work_precision.csv``): the cheapest run reaching each
level, and the two ratios of :data:`~study.bench.settings.COMPARISONS` at each level.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from study.bench.settings import COMPARISONS, LEVELS


def cheapest(wp: pd.DataFrame, levels=LEVELS) -> pd.DataFrame:
    """Per mechanism, engine, method and level: the cheapest run with error <= level.

    Parameters
    ----------
    wp : DataFrame
        Work-precision runs (columns mechanism, variant, t_end, engine, method, setting, error,
        cpu_s, repeats).

    Returns
    -------
    DataFrame
        Columns mechanism, variant, t_end, engine, method, level, reached, cpu_s, setting, error,
        repeats, finest_setting_tried, best_error (NaN CPU/setting where not reached) and
        failed_settings (settings whose run failed, '; '-separated).
    """
    rows = []
    for (mech, engine, method), g in wp.groupby(["mechanism", "engine", "method"], sort=True):
        fine = g[g.error.notna()]
        for level in levels:
            ok = fine[fine.error <= level]
            row = {"mechanism": mech, "variant": g.variant.iloc[0], "t_end": g.t_end.iloc[0], "engine": engine,
                   "method": method, "level": level, "reached": not ok.empty, "cpu_s": np.nan, "setting": np.nan,
                   "error": np.nan, "repeats": 0,
                   "finest_setting_tried": float(fine.setting.min()) if len(fine) else np.nan,
                   "best_error": float(fine.error.min()) if len(fine) else np.nan,
                   "failed_settings": "; ".join(f"{x:.4g}" for x in sorted(g[g.error.isna()].setting.unique()))}
            if not ok.empty:
                best = ok.loc[ok.cpu_s.idxmin()]
                row.update(cpu_s=float(best.cpu_s), setting=float(best.setting), error=float(best.error),
                           repeats=int(best.repeats))
            rows.append(row)
    return pd.DataFrame(rows)


def ratios(per_level: pd.DataFrame) -> pd.DataFrame:
    """In-house (best method) / Exudyn (best solver) CPU at each level and mechanism, for each of
    :data:`COMPARISONS` (column ``comparison``).

    ``exudyn_cpu_order2_at_level`` scales Exudyn's CPU to the step that would give exactly the level
    (cost ∝ 1/h, error ∝ h²: cpu * sqrt(error / level)), a fairer Exudyn figure than the run that
    overshoots it; ``ratio_order2`` uses it.
    """
    rows = []
    for (mech, level), g in per_level.groupby(["mechanism", "level"], sort=True):
        for comparison, (ours_engine, exu_engine) in COMPARISONS.items():
            row = _ratio_row(g, mech, level, ours_engine, exu_engine)
            if row is not None:
                rows.append({"comparison": comparison, **row})
    return pd.DataFrame(rows)


def _ratio_row(g: pd.DataFrame, mech: str, level: float, ours_engine: str, exu_engine: str) -> dict | None:
    """One row of :func:`ratios` (None if neither engine ran)."""
    if not ((g.engine == ours_engine).any() and (g.engine == exu_engine).any()):
        return None
    ours = g[(g.engine == ours_engine) & g.reached]
    exu = g[(g.engine == exu_engine) & g.reached]
    exu_all = g[g.engine == exu_engine]
    row = {"mechanism": mech, "variant": g.variant.iloc[0], "t_end": g.t_end.iloc[0], "level": level,
           "inhouse_engine": ours_engine, "exudyn_engine": exu_engine}
    for prefix, sel in (("inhouse", ours), ("exudyn", exu)):
        if sel.empty:
            row.update({f"{prefix}_method": "", f"{prefix}_setting": np.nan, f"{prefix}_error": np.nan,
                        f"{prefix}_cpu_s": np.nan, f"{prefix}_repeats": 0})
        else:
            b = sel.loc[sel.cpu_s.idxmin()]
            row.update({f"{prefix}_method": b.method, f"{prefix}_setting": b.setting, f"{prefix}_error": b.error,
                        f"{prefix}_cpu_s": b.cpu_s, f"{prefix}_repeats": int(b.repeats)})
    row["exudyn_cpu_order2_at_level"] = (row["exudyn_cpu_s"] * math.sqrt(row["exudyn_error"] / level)
                                         if not exu.empty and row["exudyn_error"] > 0 else np.nan)
    row["ratio_inhouse_over_exudyn"] = row["inhouse_cpu_s"] / row["exudyn_cpu_s"] if not exu.empty else np.nan
    row["ratio_order2"] = row["inhouse_cpu_s"] / row["exudyn_cpu_order2_at_level"] if not exu.empty else np.nan
    row["exudyn_finest_h_tried"] = float(exu_all.finest_setting_tried.min()) if len(exu_all) else np.nan
    row["exudyn_best_error"] = float(exu_all.best_error.min()) if len(exu_all) else np.nan
    if exu.empty:
        row["note"] = (f"Exudyn did not reach {level:g}: best max|dq| {row['exudyn_best_error']:.3g} rad at the "
                       f"finest step tried, h = {row['exudyn_finest_h_tried']:.4g} s")
    else:
        row["note"] = ""
    failed = [f"{m} at h = {f}" for m, f in zip(exu_all.method, exu_all.failed_settings) if isinstance(f, str) and f]
    if failed:
        row["note"] = "; ".join(x for x in [row["note"], "Exudyn failed (solver terminated): " + ", ".join(failed)] if x)
    return row
