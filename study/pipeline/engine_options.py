"""The options of a case list's case, checked when the list is read: those of its engine's run (an in-house
``study.simulate`` or ``study.exudyn_models.run``), of their types and ranges, and its cost within one run's bounds
(reference/tolerances.toml), so that a wrong case is refused before any case runs."""

from __future__ import annotations

from study import arguments
from study.reference_data import tolerance


def check_inhouse_options(options: dict, t_end: float) -> None:
    """An in-house case's options (consumed from ``options``): arguments of study.simulate of their types and ranges,
    its stabilization's own options, and its output and fixed-step cost within one run's bounds."""
    import inspect

    from study.run_arguments import FIXED_STEP, check_arguments, fixed_step_evaluations
    from study.simulate import simulate
    from study.solver.stabilization import make_stabilization

    arguments.choice("initial", options.pop("initial", "consistent"), ("consistent", "printed"))
    arguments.number("perturb_ulps", options.pop("perturb_ulps", 0), positive=False, whole=True)
    for key in ("q0", "qd0"):   # a user's state: its length is checked against the equations when the case runs
        if key in options:
            value = options.pop(key)
            if not isinstance(value, list):
                raise ValueError(f"{key} = {arguments.shown(value)} must be a list of numbers")
            arguments.state(key, value, len(value))
    run = {k: p.default for k, p in inspect.signature(simulate).parameters.items() if p.kind == p.KEYWORD_ONLY}
    checked = set(inspect.signature(check_arguments).parameters) - {"names"}
    given = {k: options.pop(k) for k in list(options) if k in run}
    run.update(given, t_end=t_end)
    given = check_arguments(**{k: v for k, v in run.items() if k in checked})
    make_stabilization(run["method"], **options)
    samples = given["t_end"] / given["output_step"]   # the time column alone: a lower bound of the output
    if samples * tolerance("output_bytes_per_value") > tolerance("max_output_bytes"):
        raise ValueError(f"t_end = {t_end:g} s at output_step = {given['output_step']:g} s asks for {samples:.3g} "
                         f"samples, more output than max_output_bytes = {tolerance('max_output_bytes'):g} bytes allows")
    if run["integrator"] in FIXED_STEP:   # its evaluations are known before it starts
        evaluations = fixed_step_evaluations(run["integrator"], given["t_end"], given["step"])
        bound = tolerance("max_evaluations") if given["max_evaluations"] is None else given["max_evaluations"]
        if evaluations > bound:
            raise ValueError(f"{run['integrator']} with step = {given['step']:g} s over t_end = {t_end:g} s takes "
                             f"{evaluations:.3g} evaluations, above max_evaluations = {bound:g} (one run's budget; "
                             f"the option max_evaluations confirms a larger run): use a larger step or a shorter t_end")


def check_exudyn_options(options: dict, t_end: float) -> None:
    """An Exudyn case's options: arguments of study.exudyn_models.run of their types, and its steps within one
    run's bound."""
    import inspect

    from study.exudyn_models import run
    from study.exudyn_models.settings import check_arguments

    declared = dict(list(inspect.signature(run).parameters.items())[2:])   # after ps and t_end
    unknown = sorted(set(options) - set(declared))
    if unknown:
        raise ValueError(f"{', '.join(unknown)}: not an option of an Exudyn case; valid options: {', '.join(declared)}")
    given = {k: p.default for k, p in declared.items() if p.default is not p.empty} | options
    arguments.number("h", given.get("h"))
    arguments.flag("ignore_singular", given["ignore_singular"])
    grid = check_arguments(t_end, given["h"], given["solver"], given["output_step"], given["friction"], given["eps"],
                           given["configuration"], given["linear_solver"], given["ignore_singular"],
                           given["newton_tolerance"])
    if grid.n_steps > tolerance("max_exudyn_steps"):
        raise ValueError(f"t_end = {t_end:g} s at h = {given['h']:g} s takes {grid.n_steps:.3g} steps, above "
                         f"max_exudyn_steps = {tolerance('max_exudyn_steps'):g} (one Exudyn run's budget, as an in-house "
                         f"run's max_evaluations: each step solves Newton's equations at least once): use a larger h "
                         f"or a shorter t_end")
