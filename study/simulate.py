"""``simulate``: one call from equations (or a built-in mechanism) to a SimulationResult, through
:func:`study.engines.run` with the :class:`study.engines.InHouse` specification of its keyword arguments."""

from __future__ import annotations

from typing import Callable

from study.engines.inhouse import InHouse
from study.engines.runner import resolve, run
from study.model.eom import EquationsOfMotion
from study.results import SimulationResult
from study.run_arguments import DEFAULT_FRICTION, DEFAULT_OUTPUT_STEP, check_arguments
from study.solver.stabilization import Stabilization

__all__ = ["simulate", "simulate_methods"]


def simulate(
    eom_or_mechanism,
    q0=None,
    qd0=None,
    t_end: float = 1.0,
    *,
    method: str | Stabilization = "none",
    integrator: str = "RK45",
    rtol: float | None = None,
    atol: float | None = None,
    step: float | None = None,
    output_step: float = DEFAULT_OUTPUT_STEP,
    acceleration_solver: str | None = None,
    variant: str | None = None,
    progress: Callable[[float], None] | None = None,
    friction: str | None = DEFAULT_FRICTION,
    friction_eps: float | None = None,
    friction_sgn: str | None = None,
    resistance_reading: str | None = None,
    backend: str = "reference",
    check: bool = True,
    max_evaluations: float | None = None,
    min_step: float | None = None,
    max_output_bytes: float | None = None,
    **method_options,
) -> SimulationResult:
    """Simulate a constrained mechanism: :func:`study.engines.run` of the :class:`study.engines.InHouse`
    specification of these keyword arguments (each option is documented there and in ``study.engines``).

    Parameters
    ----------
    eom_or_mechanism : EquationsOfMotion, Mechanism or str
        A user's equations (then ``q0``, ``qd0`` are required); a :class:`study.Mechanism`; or a study mechanism's
        name, e.g. 'slider_crank', with ``variant`` (default 'seed'). q0, qd0 default to the consistent state.
    q0, qd0 : (m,) array_like
        Initial state; it should satisfy the constraints (see ``study.model.initial_state``).
    t_end : float
        End time [s], > 0.
    method : str or Stabilization
        'none', 'baumgarte', 'sliding_mode', 'projection' with its options in ``method_options`` (d, omega or
        alpha, beta; Lambda, K, k, sgn, width; weighting), or a ``study.solver.stabilization.Stabilization`` object.
    integrator : str
        'RK45', 'DOP853', 'RK23', 'Radau', 'LSODA' (``rtol``, default 1e-8; ``atol``, default 1e-10; ``min_step``,
        default ``min_step_fraction`` * t_end), 'RK4' or 'ALI3P' (``step``; ALI3P, the index-3 augmented Lagrangian,
        takes no method, acceleration solver, friction or switching loads). An argument the integrator would
        ignore is refused.
    acceleration_solver : str, optional
        'multiplier' (default), 'partitioned', 'orthonormal' (full-rank Phi_q) or 'augmented_lagrangian'.
    friction, friction_eps, friction_sgn, resistance_reading
        'default' (the parameter set's treatment, ``study.friction_default``), 'none' (or None), 'exact',
        'regularized' (``friction_sgn`` of width ``friction_eps``) or 'sign' (stick band ``friction_eps``);
        ``resistance_reading`` (None: the parameter set's, else 'holds') for 'exact'. See ``study.engines.friction``.
    backend : {'reference', 'compiled'}
        scipy's loop on Python evaluations, or the compiled loop (``study.fast``; Radau and LSODA take scipy's steps
        on compiled evaluations); an unsupported combination is refused by name.
    output_step, check, max_evaluations, max_output_bytes, progress
        Sample spacing [s]; validate the equations and q0, qd0 first (``study.solver.checks``); the bounds of the
        run (defaults in reference/tolerances.toml; a fixed-step run over them is refused before it starts); a
        callback with the time reached.

    Raises
    ------
    ValueError
        A bad argument (named); ``study.errors.EquationsError``, ``study.errors.RunTooLargeError``.
    study.errors.SimulationError
        The run failed (time, quantity and likely cause in the message).
    """
    flat = dict(method=method, integrator=integrator, rtol=rtol, atol=atol, step=step, output_step=output_step,
                acceleration_solver=acceleration_solver, friction=friction, friction_eps=friction_eps,
                friction_sgn=friction_sgn, resistance_reading=resistance_reading, backend=backend, check=check,
                max_evaluations=max_evaluations, min_step=min_step, max_output_bytes=max_output_bytes)
    check_arguments(**flat, t_end=t_end, variant=variant, progress=progress)
    spec = InHouse.from_dict({**flat, **method_options})
    eom, mech = resolve(eom_or_mechanism, variant)
    return run(eom if mech is None else mech, spec, t_end, q0=q0, qd0=qd0, progress=progress)


def simulate_methods(eom_or_mechanism: EquationsOfMotion | str, q0=None, qd0=None, t_end: float = 1.0, *,
                     methods=("none", "baumgarte", "sliding_mode", "projection"), **options) -> dict[str, SimulationResult]:
    """:func:`simulate` with each stabilization method in turn (default options), the other arguments the same."""
    return {method: simulate(eom_or_mechanism, q0, qd0, t_end, method=method, **options) for method in methods}
