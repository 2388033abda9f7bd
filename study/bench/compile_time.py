"""The one-off compile time of the compiled path: first call in a fresh cache, then a warm one (subprocesses)."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

import pandas as pd

from study.bench.harness import log


def compile_time() -> pd.DataFrame:
    """First compiled call in a fresh cache (subprocess): sympy code generation + numba compilation."""
    code = ("import time; t0 = time.perf_counter(); from study.simulate import simulate\n"
            "for m, v in (('quick_return', 'smooth_cutting'), ('slider_crank', 'sustained_sliding')):\n"
            "    t = time.perf_counter(); simulate(m, variant=v, t_end=0.1, backend='compiled',"
            " friction='regularized' if m == 'slider_crank' else None); print(m, time.perf_counter() - t)\n")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env["STUDY_CACHE_DIR"] = tmp
        for label in ("fresh cache (code generation + compilation)", "warm cache (load from disk)"):
            out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            for line in out.stdout.split("\n"):
                if line.strip():
                    mech, sec = line.split()
                    rows.append({"cache": label, "mechanism": mech, "first_call_wall_s": float(sec)})
                    log(f"compile: {label} {mech}: {float(sec):.1f} s")
    return pd.DataFrame(rows)
