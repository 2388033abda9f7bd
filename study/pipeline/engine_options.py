"""The options of a case list's case, checked when the list is read: a serialized run specification of its engine
(:class:`study.engines.InHouse`, the keyword arguments of ``study.simulate``, or :class:`study.engines.Exudyn`, those
of ``study.exudyn_models.run``), checked over the case's horizon, and its cost within one run's bounds
(reference/tolerances.toml), so that a wrong case is refused before any case runs."""

from __future__ import annotations

from study import arguments
from study.reference_data import tolerance


def check_inhouse_options(options: dict, t_end: float) -> None:
    """An in-house case's options (consumed from ``options``): its initial state, its run specification
    (:meth:`study.engines.InHouse.from_dict`, checked over ``t_end``), and its output and fixed-step cost within one
    run's bounds."""
    from study.engines.inhouse import InHouse
    from study.engines.integrators import FixedStep
    from study.run_arguments import fixed_step_evaluations

    arguments.choice("initial", options.pop("initial", "consistent"), ("consistent", "printed"))
    arguments.number("perturb_ulps", options.pop("perturb_ulps", 0), positive=False, whole=True)
    for key in ("q0", "qd0"):   # a user's state: its length is checked against the equations when the case runs
        if key in options:
            value = options.pop(key)
            if not isinstance(value, list):
                raise ValueError(f"{key} = {arguments.shown(value)} must be a list of numbers")
            arguments.state(key, value, len(value))
    spec = InHouse.from_dict(options)
    options.clear()
    given = spec.checked(t_end, names={})
    samples = given["t_end"] / given["output_step"]   # the time column alone: a lower bound of the output
    if samples * tolerance("output_bytes_per_value") > tolerance("max_output_bytes"):
        raise ValueError(f"t_end = {t_end:g} s at output_step = {given['output_step']:g} s asks for {samples:.3g} "
                         f"samples, more output than max_output_bytes = {tolerance('max_output_bytes'):g} bytes allows")
    name = spec.integrator.name
    if isinstance(spec.integrator, FixedStep):   # its evaluations are known before it starts
        evaluations = fixed_step_evaluations(name, given["t_end"], given["step"])
        bound = tolerance("max_evaluations") if given["max_evaluations"] is None else given["max_evaluations"]
        if evaluations > bound:
            raise ValueError(f"{name} with step = {given['step']:g} s over t_end = {t_end:g} s takes "
                             f"{evaluations:.3g} evaluations, above max_evaluations = {bound:g} (one run's budget; "
                             f"the option max_evaluations confirms a larger run): use a larger step or a shorter t_end")


def check_exudyn_options(options: dict, t_end: float) -> None:
    """An Exudyn case's options: its run specification (:meth:`study.engines.Exudyn.from_dict`, checked over
    ``t_end``), and its steps within one run's bound."""
    from study.engines.exudyn import Exudyn

    spec = Exudyn.from_dict(options)
    grid = spec.checked(t_end)
    if grid.n_steps > tolerance("max_exudyn_steps"):
        raise ValueError(f"t_end = {t_end:g} s at h = {spec.h:g} s takes {grid.n_steps:.3g} steps, above "
                         f"max_exudyn_steps = {tolerance('max_exudyn_steps'):g} (one Exudyn run's budget, as an in-house "
                         f"run's max_evaluations: each step solves Newton's equations at least once): use a larger h "
                         f"or a shorter t_end")
