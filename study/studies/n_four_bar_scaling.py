"""Scaling of the N-four-bar (IFToMM A02) with the number of windows N: in-house and Exudyn.

For N = 2, 5, 10, 20, 40 (variants seed, n5, n10, n20, n40 of reference/n_four_bar.toml) measures, each
in a fresh process with an empty code cache (so nothing is reused between sizes):

* ``derive_s``: the sympy derivation (M, Q, Phi, Phi_q, gamma) in relative coordinates;
* ``derive_and_codegen_s``: derivation + code generation + binding, i.e. ``mechanisms.equations``;
* ``eval_s``: one right-hand-side evaluation (augmented Lagrangian accelerations), mean of 200;
* ``inhouse_cpu_per_s``: CPU per simulated second, augmented Lagrangian + projection, DOP853 rtol 1e-8,
  over ``t_sim`` seconds (which include the first singular position at ~0.7 s);
* ``exudyn_cpu_per_s``: the same for Exudyn index 3, h = 1e-3 s (or its error).

CPU times are process times on the machine that ran it, with one BLAS thread as ``simulate`` uses
(:func:`study.engines.runner.one_blas_thread`). The table is written to
``reports/tables/singular_four_bar_scaling.csv``. Run: ``python -m study.studies.n_four_bar_scaling``
(~10 min on 2 cores). Not a cached pipeline study: the quantities measured are the costs themselves.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import pandas as pd

from study.locations import REPORTS_DIR
from study.pipeline.tables import write_table
from study.engines.runner import one_blas_thread

VARIANTS = (("seed", 2.0), ("n5", 2.0), ("n10", 2.0), ("n20", 1.0), ("n40", 1.0))
OUT = REPORTS_DIR / "tables" / "singular_four_bar_scaling.csv"
SCALING_COMMAND = "python -m study.studies.n_four_bar_scaling"   # what rebuilds OUT (recorded beside it)


@one_blas_thread
def measure(variant: str, t_sim: float) -> dict:
    """The measurements of one size, in this process (call it in a fresh one with an empty cache)."""
    from study import mechanisms
    from study.exudyn_models import run as exudyn_run
    from study.model.derive import derive
    from study.params import load_parameters
    from study.simulate import simulate
    from study.solver.accelerations import make_acceleration_solver
    from study.solver.dynamics import Dynamics
    from study.solver.stabilization import make_stabilization

    ps = load_parameters("n_four_bar", variant)
    out = {"variant": variant, "N": int(ps.values.N), "t_sim": t_sim}
    t = time.process_time()
    derive(mechanisms.builder(ps))
    out["derive_s"] = time.process_time() - t
    t = time.process_time()
    eom = mechanisms.equations(ps)
    out["derive_and_codegen_s"] = time.process_time() - t
    st = mechanisms.initial_state(ps, eom)
    dyn = Dynamics(eom, make_acceleration_solver("augmented_lagrangian"), make_stabilization("none"))
    y = np.concatenate([st.q, st.qd])
    t = time.process_time()
    for _ in range(200):
        dyn.rhs(0.0, y)
    out["eval_s"] = (time.process_time() - t) / 200
    t = time.process_time()
    r = simulate(eom, st.q, st.qd, t_sim, method="projection", integrator="DOP853", rtol=1e-8, atol=1e-10,
                 acceleration_solver="augmented_lagrangian", output_step=0.01)
    out["inhouse_cpu_per_s"] = (time.process_time() - t) / t_sim
    E = r.energies["kinetic"] + r.energies["potential"]
    out["inhouse_drift"] = float(np.abs(E - E[0]).max())
    try:
        t = time.process_time()
        rx = exudyn_run(ps, t_sim, 1e-3, solver="index3", output_step=0.01, ignore_singular=True)
        out["exudyn_cpu_per_s"] = (time.process_time() - t) / t_sim
        E = rx.energies["kinetic"] + rx.energies["potential"]
        out["exudyn_drift"] = float(np.abs(E - E[0]).max())
        out["exudyn_error"] = ""
    except Exception as exc:  # noqa: BLE001 - recorded in the table: which engine failed and why
        out.update(exudyn_cpu_per_s=np.nan, exudyn_drift=np.nan, exudyn_error=f"{type(exc).__name__}: {exc}"[:120])
    return out


def main() -> int:
    rows = []
    for variant, t_sim in VARIANTS:
        print(f"n_four_bar scaling: {variant} ({t_sim:g} s) ...", file=sys.stderr, flush=True)
        env = {**os.environ, "STUDY_CACHE_DIR": tempfile.mkdtemp(prefix="nfb_scaling_")}
        code = ("import json, sys; from study.studies.n_four_bar_scaling import measure; "
                f"print(json.dumps(measure({variant!r}, {t_sim!r})))")
        done = subprocess.run([sys.executable, "-W", "ignore", "-c", code], env=env, capture_output=True, text=True,
                              check=True)
        rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
        print(f"  {rows[-1]}", file=sys.stderr, flush=True)
    write_table(OUT, pd.DataFrame(rows).to_csv(index=False, lineterminator="\n"), SCALING_COMMAND)
    print(f"wrote {OUT}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
