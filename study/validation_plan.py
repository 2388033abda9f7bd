"""The work of one ``study validate``, counted and bounded before any run starts.

:func:`check_plan` counts what a validation will do (its in-house runs, the fixed-step run's evaluations, Exudyn's
steps at every level, the output of each run) and refuses, with one :class:`study.errors.RunTooLargeError` naming
every value, its bound and the reason, a validation that exceeds a bound of reference/tolerances.toml. It returns
the plan's line, the estimate a user sees before the first run. The bounds on the settings alone (levels, the
finest step) are checked by ``study.validation.Settings``.
"""

from __future__ import annotations

from study.errors import RunTooLargeError
from study.reference_data import tolerance

REMEDY = "use a shorter t_end (--t-end), a larger h (--h) or fewer levels (--levels)"


def exudyn_steps(s, solvers: int) -> tuple[list[int], int]:
    """Exudyn's steps per run at each level (h, h/2, ...) and their total over ``solvers`` solvers."""
    per_level = [int(round(s.t_end / h)) for h in s.steps]
    return per_level, solvers * sum(per_level)


def check_plan(mech, s, inhouse: dict[str, dict], solvers: int) -> str:
    """Refuse a validation whose work exceeds a bound, before any run; return the plan's one-line estimate."""
    from study.run_arguments import FIXED_STEP, fixed_step_evaluations, format_bytes, output_size

    eom, state = mech.equations(), mech.initial_state()
    problems = []
    samples, columns, nbytes = output_size(eom, state.q, state.qd, s.t_end, s.output_step, "regularized")
    if not nbytes <= tolerance("max_output_bytes"):
        problems.append(f"t_end = {s.t_end:g} s at output_step = {s.output_step:g} s asks for {samples:.3g} samples "
                        f"of {columns} values per run, about {format_bytes(nbytes)}, above max_output_bytes = "
                        f"{format_bytes(tolerance('max_output_bytes'))} (the memory one run may take): use a larger "
                        f"output_step (--output-step) or a shorter t_end")
    fixed, adaptive = {}, []
    for name, options in inhouse.items():
        if options["integrator"] in FIXED_STEP:
            fixed[name] = fixed_step_evaluations(options["integrator"], s.t_end, options["step"])
        else:
            adaptive.append(name)
    budget = tolerance("max_evaluations")
    for name, evaluations in fixed.items():
        if evaluations > budget:
            problems.append(f"the in-house run '{name}' at the finest Exudyn step {inhouse[name]['step']:.3g} s over "
                            f"t_end = {s.t_end:g} s takes {evaluations:.3g} evaluations, above max_evaluations = "
                            f"{budget:g} (one run's budget): {REMEDY}")
    per_level, total = exudyn_steps(s, solvers)
    bound = tolerance("max_exudyn_steps")
    if total > bound:
        problems.append(f"t_end = {s.t_end:g} s takes {total:.3g} Exudyn steps ({solvers} solvers x "
                        f"{sum(per_level):.3g} steps at h = {s.h:g} s halving to {s.steps[-1]:.3g} s in {s.levels} "
                        f"levels), above max_exudyn_steps = {bound:g} (each step solves Newton's equations at least "
                        f"once, so one validation's Exudyn steps are held to one in-house run's max_evaluations): "
                        f"{REMEDY}")
    if problems:
        raise RunTooLargeError("validate: refused before any run: " + "; ".join(problems))
    fixed_text = "".join(f"; '{name}' {evaluations:.3g} evaluations" for name, evaluations in fixed.items())
    return (f"plan: {len(inhouse)} in-house runs ({len(adaptive)} adaptive, each within max_evaluations = "
            f"{budget:g} and stopped early when its pace cannot reach t_end{fixed_text}), {solvers * s.levels} "
            f"Exudyn runs with {total} steps in all (max_exudyn_steps = {bound:g}), {samples:.0f} samples of "
            f"{columns} values per run (~{format_bytes(nbytes)})")
