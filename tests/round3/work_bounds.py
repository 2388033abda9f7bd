"""Round three, group 'work bounds': see tests/round3/__init__.py.

Every amount of work is bounded before it starts: the levels of ``study validate``, its finest step, its horizon
against the run budget (evaluations and Exudyn steps), a case list's fixed-step and Exudyn cases, each refused
before any work with the counts named. A run stopped on its way is judged by what stopped it (the reason and its
counts; the probe's ``judge``), never by seconds. Long runs print progress lines within the run, at a count of
steps, so the same lines appear on any host.
"""

from __future__ import annotations

import contextlib
import io
import re
import textwrap
from pathlib import Path

from round3 import OK, add

import study
from study.cli import main
from study.errors import RunBoundError, RunTooLargeError

G = "work bounds"
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
CART = str(EXAMPLES / "cart_pendulum" / "cart_pendulum.py")    # rail friction: every treatment, RK4 sign too
YOKE = str(EXAMPLES / "scotch_yoke" / "scotch_yoke.py")        # no friction


def validate(*tail, file=CART, t_end="0.01", output_step="0.01"):
    """``validate`` argv with a short horizon (cheap even where the bound is missing) and --out in the try's folder."""
    return lambda tmp: ["validate", file, "--t-end", t_end, "--output-step", output_step, "--out", str(tmp / "v"),
                        *tail]


# --- study validate: levels, finest step, horizon ------------------------------------------------------------
add(G, "validate_levels_40", validate("--levels", "40"), 2, "levels = 40", "validate_max_levels", "3.64e-15")
add(G, "validate_levels_0", validate("--levels", "0"), 2, "levels = 0", "at least 2")
add(G, "validate_levels_fraction", lambda tmp: study.ValidationSettings(levels=2.5), ValueError, "levels = 2.5",
    "whole number")
add(G, "validate_levels_boolean", lambda tmp: study.ValidationSettings(levels=True), ValueError, "levels = True",
    "whole number")
add(G, "validate_finest_step_below_bound", validate("--h", "1e-6", "--levels", "5", t_end="0.001",
                                                    output_step="0.001"),
    2, "finest", "6.25e-08", "validate_min_step")
add(G, "validate_t_end_huge", validate(t_end="1000", output_step="1"), 2, "t_end = 1000", "8e+06 evaluations",
    "max_evaluations", "7e+06 Exudyn steps", "max_exudyn_steps")
add(G, "validate_t_end_huge_without_friction", validate(file=YOKE, t_end="1000", output_step="1"), 2,
    "t_end = 1000", "7e+06 Exudyn steps", "max_exudyn_steps")


def validate_library(tmp):
    study.validate(study.load_mechanism(CART), study.ValidationSettings(t_end=2000.0, output_step=1.0), tmp / "v",
                   say=lambda _: None)


add(G, "validate_t_end_huge_library", validate_library, RunTooLargeError, "t_end = 2000", "evaluations",
    "max_evaluations")
add(G, "validate_output_step_tiny", validate("--h", "1e-6", "--levels", "2", t_end="1", output_step="5e-7"), 2,
    "output_step = 5e-07", "max_output_bytes")


# --- case lists: fixed-step and Exudyn cases bounded when the list is read -----------------------------------
HEAD = '[study]\nsummary = "study.studies.sliding_mode"\n'


def run_list(text):
    def action(tmp):
        folder = tmp / "cases"
        folder.mkdir(exist_ok=True)
        (folder / "bounds.toml").write_text(HEAD + textwrap.dedent(text))
        return ["run", "--cases", str(folder), "--out", str(tmp / "r")]
    return action


add(G, "case_list_rk4_step_tiny", run_list("""
    [[group]]
    name = "fine"
    mechanism = "quick_return"
    t_end = 1.0
    options = { integrator = "RK4", step = 1e-9, output_step = 0.5 }
    """), 2, "bounds.toml", "step = 1e-09", "evaluations", "max_evaluations")
add(G, "case_list_step_sweep_explodes", run_list("""
    [[group]]
    name = "steps"
    mechanism = "quick_return"
    t_end = 2.0
    options = { integrator = "RK4", output_step = 0.5 }
    sweep.step = [1e-3, 1e-4, 1e-5, 1e-8]
    """), 2, "bounds.toml", "step = 1e-08", "8e+08 evaluations", "max_evaluations")


def exudyn_list(name, t_end, options):
    return run_list(f"""
    [[group]]
    name = "{name}"
    mechanism = "slider_crank"
    t_end = {t_end}
    engine = "exudyn"
    options = {options}
    """)


add(G, "case_list_exudyn_t_end_huge", exudyn_list("long", "1e5", "{ h = 1e-3, output_step = 100.0 }"), 2,
    "bounds.toml", "t_end = 100000", "1e+08 steps", "max_exudyn_steps")
add(G, "case_list_exudyn_every_step_saved", exudyn_list("dense", "1e3", "{ h = 1e-5 }"), 2, "bounds.toml",
    "1e+08 steps", "max_exudyn_steps")


# --- runs stopped on their way: by what stopped them and its counts ------------------------------------------
add(G, "budget_stop_names_reason_and_counts",
    lambda tmp: study.simulate("slider_crank", variant="slip_then_stick", t_end=6.0, friction="sign",
                               max_evaluations=200_000),
    RunBoundError, "chatter", "after", "evaluations", "max_evaluations = 200000")
add(G, "simulate_t_end_huge_stops_with_estimate",
    lambda tmp: ["simulate", "quick_return", "--t-end", "1e5", "--output-step", "100", "--max-evaluations", "2e5",
                 "--out", str(tmp / "x")], 1, "estimate", "after", "evaluations", "max_evaluations = 200000")


# --- progress within a run, at a count of steps ------------------------------------------------------------
def captured(argv, name):
    """Run the command line with stderr kept in ``tmp/name`` (the grader keeps its own copy of stderr)."""
    def action(tmp):
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            code = main(argv(tmp))
        (tmp / name).write_text(err.getvalue())
        assert code == 0, err.getvalue()[-300:]
    return action


PROGRESS = re.compile(r"t = (\S+) of (\S+) s \((\S+) %\), (\d+) steps; ~(\S+) steps to t_end at the pace of the last")


def progress_lines(text, at_least=2):
    """The progress lines of one run's output: at least ``at_least``, t and the steps increasing."""
    lines = [m for m in map(PROGRESS.search, text.splitlines()) if m]
    assert len(lines) >= at_least, f"fewer than {at_least} progress lines: {text[-400:]!r}"
    t = [float(m.group(1)) for m in lines]
    steps = [int(m.group(4)) for m in lines]
    assert t == sorted(t) and steps == sorted(steps) and len(set(steps)) == len(steps), lines
    assert all(float(m.group(5)) >= 0 for m in lines)
    return lines


add(G, "simulate_long_run_prints_progress",
    captured(lambda tmp: ["simulate", "quick_return", "--t-end", "30", "--output-step", "0.5",
                          "--out", str(tmp / "x")], "stderr.txt"), OK,
    then=lambda tmp: progress_lines((tmp / "stderr.txt").read_text()))


def short_run_silent(tmp):
    assert (tmp / "stderr.txt").read_text() == "", (tmp / "stderr.txt").read_text()


add(G, "simulate_short_run_is_silent",
    captured(lambda tmp: ["simulate", "quick_return", "--t-end", "0.5", "--out", str(tmp / "x")], "stderr.txt"), OK,
    then=short_run_silent)


def validate_progress(tmp):
    text = (tmp / "stderr.txt").read_text()
    reference = text.partition("in-house reference\n")[2].partition("[2/7]")[0]
    progress_lines(reference, at_least=1)   # within the reference run (regularized: ~1500 steps per second)
    assert re.search(r"Exudyn index3 h = \S+ s \(\d+ steps\)", text), text[-400:]
    assert re.search(r"plan: 7 in-house runs .* 4 Exudyn runs with \d+ steps in all", text), text[:600]


add(G, "validate_long_run_prints_progress_and_plan",
    captured(lambda tmp: ["validate", CART, "--t-end", "2", "--output-step", "0.02", "--h", "0.002", "--levels", "2",
                          "--out", str(tmp / "v")], "stderr.txt"), OK, then=validate_progress, slow=True)
