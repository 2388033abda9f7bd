"""CPU against simulated time and output density (benchmark part d); peak memory against output size (e).

The simulated-time runs are the cases of ``"scaling: simulated time"`` (through the pipeline's store);
the output-density and memory runs call the compiled loop directly (no post-processing: what they
measure is the loop's own cost and allocation), timed here and never saved.
"""

from __future__ import annotations

import time
import tracemalloc

import pandas as pd

from study.bench.harness import bench_store, log, median_cpu, repeat_of, timed
from study.bench.summary import summarize
from study.bench.settings import EPS, LINEAR_REPEATS, OUTPUT_STEP, group, repeats
from study.simulate import simulate


def scaling(quick: bool) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """CPU against simulated time and output density; tracemalloc peak against output size."""
    from study.fast import frontend
    from study.mechanisms import initial_state, load, mechanism

    few = repeats(quick)
    executed = []
    for case in group("scaling: simulated time"):   # the compiled path, then the reference path up to 5 s
        backend, t_end = case.kwargs["backend"], case.t_end
        if quick and t_end > 5:
            continue
        n = LINEAR_REPEATS if backend == "compiled" else few
        log(f"(d) {backend} t_end {t_end}: {timed(case, n)[0]:.4f} s")
        executed += [repeat_of(case, k) for k in range(n)]
    time_df = summarize(executed, bench_store().load)["scaling_simulated_time"]

    ps, eom = load("quick_return", "smooth_cutting")
    st = initial_state(ps, eom)
    s = frontend.setup(eom, mechanism(ps), st.q, st.qd, "none", None, EPS, "tanh")
    rows, mem = [], []
    t_end = 5.0 if quick else 20.0
    for dt in (1.0, 0.1, 0.01, 0.001, 0.0001):
        t_out = frontend.output_times(t_end, dt)

        def fn():
            t0 = time.process_time()
            out = frontend.run(s, t_end, t_out, "DOP853", 1e-10, 1e-12, None)
            return time.process_time() - t0, out
        cpu, out = median_cpu(fn, few)
        rows.append({"t_end": t_end, "output_step": dt, "samples": len(t_out), "cpu_s": cpu,
                     "steps": out[3]["steps"], "nfev": out[3]["nfev"], "repeats": few})
        log(f"(d) output step {dt}: {cpu:.4f} s, {out[3]['nfev']} evaluations")
    for t_end_m, dt in ((20.0, 0.01), (100.0, 0.01), (100.0, 0.1), (100.0, 1.0)):
        if quick and t_end_m > 20:
            continue
        t_out = frontend.output_times(t_end_m, dt)
        tracemalloc.start()
        out = frontend.run(s, t_end_m, t_out, "DOP853", 1e-10, 1e-12, None)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        mem.append({"backend": "compiled", "t_end": t_end_m, "output_step": dt, "samples": len(t_out),
                    "steps": out[3]["steps"], "peak_traced_bytes": peak,
                    "bytes_per_sample": peak / len(t_out)})
        log(f"(e) compiled t_end {t_end_m} dt {dt}: peak {peak / 1e6:.3f} MB, {out[3]['steps']} steps")
    tracemalloc.start()
    r = simulate("quick_return", variant="smooth_cutting", t_end=5.0, integrator="DOP853", rtol=1e-10, atol=1e-12)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    mem.append({"backend": "reference (simulate, incl. post-processing)", "t_end": 5.0, "output_step": OUTPUT_STEP,
                "samples": len(r.t), "steps": r.stats["steps"], "peak_traced_bytes": peak,
                "bytes_per_sample": peak / len(r.t)})
    return time_df, pd.DataFrame(rows), pd.DataFrame(mem)
