"""The consistent-initial-conditions table: printed values, their constraint residuals, and ours."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from study.mechanisms import initial_state, load
from study.params import available_mechanisms
from study.model.initial_state import constraint_residuals


def initial_conditions_table() -> pd.DataFrame:
    """One row per mechanism and coordinate: printed q, qd; consistent q, qd; residuals."""
    rows = []
    for name in available_mechanisms():
        ps, eom = load(name, "seed")
        state = initial_state(ps, eom)
        phi_p, vel_p = constraint_residuals(eom, ps.initial.printed_q, ps.initial.printed_qd)
        for i, coord in enumerate(eom.coordinate_names):
            rows.append({
                "mechanism": name,
                "coordinate": coord,
                "independent": i in ps.initial.independent,
                "q_printed": ps.initial.printed_q[i],
                "q_consistent": state.q[i],
                "qd_printed": ps.initial.printed_qd[i],
                "qd_consistent": state.qd[i],
                "max_abs_phi_printed": float(np.max(np.abs(phi_p))),
                "max_abs_phidot_printed": float(np.max(np.abs(vel_p))),
                "max_abs_phi_consistent": state.phi_residual,
                "max_abs_phidot_consistent": state.velocity_residual,
                "newton_iterations": state.iterations,
                "branch": ps.initial.branch,
            })
    return pd.DataFrame(rows)


def write_initial_conditions(out_dir: Path) -> Path:
    """Write ``initial_conditions.csv`` into ``out_dir`` (a report's ``tables/``), recorded beside it."""
    from study.pipeline.tables import write_table

    text = initial_conditions_table().to_csv(index=False, float_format="%.10g", lineterminator="\n")
    out_dir = Path(out_dir)
    return write_table(out_dir / "initial_conditions.csv", text, f"python -m study initial --out {out_dir.parent}")
