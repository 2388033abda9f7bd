"""The cost of one acceleration evaluation (benchmark part a), reference and compiled, in microseconds.

Lambda is included; for the slider-crank the coupled normal-force/friction solve. The compiled cost is
timed inside a compiled loop (the cost inside the integrator) and as one call from Python.
"""

from __future__ import annotations

import time

import pandas as pd

from study.bench.harness import log, median_cpu
from study.bench.settings import CASES, EPS


# --- (a) one acceleration evaluation ---------------------------------------------------------------
def accel_costs(repeats: int, n_calls: int, mechanisms=None) -> pd.DataFrame:
    """Microseconds per acceleration evaluation of each mechanism (default: every one of the benchmark):
    reference Python path, compiled (inside a compiled loop, i.e. the cost inside the integrator) and
    compiled called once from Python."""
    from study.fast import frontend
    from study.mechanisms import initial_state, load, mechanism

    rows = []
    for mech in mechanisms or CASES:
        variant, _, extra = CASES[mech]
        ps, eom = load(mech, variant)
        st = initial_state(ps, eom)
        s = frontend.setup(eom, mechanism(ps), st.q, st.qd, "none", extra.get("friction"), EPS, "tanh")
        fric = extra.get("friction") is not None
        ref = (lambda: s.dyn.contact_solution(0.1, st.q, st.qd)) if fric else (lambda: s.dyn.evaluate(0.1, st.q, st.qd))
        n_few = n_calls // 20

        def time_ref():
            t0 = time.process_time()
            for _ in range(n_few):
                ref()
            return (time.process_time() - t0) / n_few * 1e6, None

        def time_loop():  # n_calls evaluations inside one compiled call: the cost inside the integrator
            t0 = time.process_time()
            frontend.accelerations(s, 0.1, st.q, st.qd, (), repeat=n_calls)
            return (time.process_time() - t0) / n_calls * 1e6, None

        def time_call():  # one Python -> compiled call per evaluation
            t0 = time.process_time()
            for _ in range(n_few):
                frontend.accelerations(s, 0.1, st.q, st.qd, ())
            return (time.process_time() - t0) / n_few * 1e6, None

        for label, fn, n in (("reference (Python)", time_ref, n_few), ("compiled, in compiled loop", time_loop, n_calls),
                             ("compiled, one call from Python", time_call, n_few)):
            us, _ = median_cpu(fn, repeats)
            rows.append({"mechanism": mech, "variant": variant, "friction_solve": fric, "path": label,
                         "us_per_evaluation": us, "calls_per_timing": n, "repeats": repeats})
            log(f"(a) {mech} {label}: {us:.3f} us")
    return pd.DataFrame(rows)


def eval_cost_us(mech: str, variant: str, extra: dict, repeats: int, n_calls: int) -> float:
    """Median µs of one compiled acceleration evaluation inside a compiled loop (``n_calls`` per timing)
    at the initial state, in the mode the integration starts in: the cost unit of the loop overhead."""
    from study.fast import frontend
    from study.mechanisms import initial_state, load, mechanism

    ps, eom = load(mech, variant)
    st = initial_state(ps, eom)
    s = frontend.setup(eom, mechanism(ps), st.q, st.qd, "none", extra.get("friction"), EPS, "tanh")
    m = eom.n_coordinates
    mode = ()
    if s.n_load_modes:
        mode = tuple(frontend.initial_mode(lambda t, y: eom.indicators(t, y[:m], y[m:2 * m]), 0.0, s.y0, s.dyn.rhs))

    def fn():
        t0 = time.process_time()
        frontend.accelerations(s, 0.0, st.q, st.qd, mode, repeat=n_calls)
        return (time.process_time() - t0) / n_calls * 1e6, None
    return median_cpu(fn, repeats)[0]


def pace_us() -> float:
    """This host's pace: µs of one compiled quick-return acceleration evaluation (the benchmark's
    acceleration_evaluation row), timed now; what ``make reproduce`` prints to read its stages' times by."""
    return eval_cost_us("quick_return", "smooth_cutting", {}, 5, 20000)
