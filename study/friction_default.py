"""The friction a run takes unless told otherwise: the parameter set's treatment of every friction entry.

A description's friction entries are its sliding contacts and its pins (revolute joints with friction). An entry
whose coefficients, resistance or constant torque are all zero makes no force; the others are the physics the
parameter set states, and ``simulate(..., friction='default')`` (its default, and the command line's without
``--friction``) runs them with the parameter set's ``friction_treatment`` if it names one, else with the exact
stick/slip treatment. Asked to run without friction (``friction='none'``), a run records the entries it left out.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from study.run_arguments import DEFAULT_FRICTION, check_arguments

if TYPE_CHECKING:
    from study.model.eom import EquationsOfMotion



def friction_entries(eom: EquationsOfMotion) -> list[str]:
    """The friction entries of ``eom`` whose data make a force: the sliding contacts with a nonzero coefficient or
    resistance and the pins with a nonzero coefficient or constant torque (the order of ``work_friction_<entry>``)."""
    return ([c.name for c in eom.contacts if c.mu_static or c.mu_kinetic or c.resistance]
            + [p.name for p in eom.pin_frictions if p.mu_static or p.mu_kinetic or p.torque])


def default_friction(eom: EquationsOfMotion, ps=None) -> str | None:
    """The treatment ``friction='default'`` gives: None where no entry of ``eom`` has friction (:func:`friction_entries`);
    else the parameter set's ``friction_treatment`` if it states one, else 'exact' (event-located stick/slip)."""
    if not friction_entries(eom):
        return None
    return getattr(ps.values, "friction_treatment", "exact") if ps is not None else "exact"


def treatment(eom: EquationsOfMotion, ps, friction: str | None, given: dict, **run) -> str | None:
    """The friction treatment a run takes: ``friction`` as given ('none' -> None), or the parameter set's default
    (:func:`default_friction`), whose combinations with the other arguments (``given``: the numbers checked by
    :func:`study.run_arguments.check_arguments`; ``run``: integrator, friction_eps, friction_sgn, backend) are
    checked here, where it is known."""
    if friction != DEFAULT_FRICTION:
        return None if friction == "none" else friction
    chosen = default_friction(eom, ps)
    stated = "" if ps is None or not hasattr(ps.values, "friction_treatment") else \
        f" ({ps.path.name} states the treatment)"
    try:
        check_arguments(t_end=given["t_end"], method="none", rtol=None, atol=None, step=given["step"],
                        output_step=given["output_step"], acceleration_solver=None, variant=None, progress=None,
                        friction=chosen, resistance_reading=None, check=True, max_evaluations=None, min_step=None,
                        max_output_bytes=None, **run)
    except ValueError as exc:
        entries = ", ".join(friction_entries(eom))
        raise ValueError(f"{exc} (friction {chosen!r} is the default for the friction of {eom.name}'s {entries}"
                         f"{stated}; pass friction='none' to run without it)") from None
    return chosen
