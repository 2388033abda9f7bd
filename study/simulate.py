"""``simulate``: one call from equations (or a built-in mechanism) to a SimulationResult, through
:func:`study.engines.run` with the :class:`study.engines.InHouse` specification of its keyword arguments."""

from __future__ import annotations

from typing import Callable

from study.engines.inhouse import InHouse
from study.engines.runner import resolve, run
from study.model.eom import EquationsOfMotion
from study.friction_default import default_friction, friction_entries
from study.results import SimulationResult
from study.run_arguments import (BACKENDS, DEFAULT_FRICTION, DEFAULT_OUTPUT_STEP, FIXED_STEP, INTEGRATOR_NAMES,
                                 check_arguments, check_run_size)
from study.solver.run import build_dynamics
from study.solver.stabilization import Stabilization

__all__ = ["BACKENDS", "DEFAULT_FRICTION", "DEFAULT_OUTPUT_STEP", "FIXED_STEP", "INTEGRATOR_NAMES", "build_dynamics",
           "check_run_size", "default_friction", "friction_entries", "resolve", "simulate", "simulate_methods"]


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
    """Simulate a constrained mechanism.

    Parameters
    ----------
    eom_or_mechanism : EquationsOfMotion, Mechanism or str
        A user's equations; a :class:`study.Mechanism` (a description with its parameter set: q0, qd0 default
        to its consistent initial state); or a study mechanism's name, e.g. 'slider_crank' (then ``variant``
        selects the parameter set, default 'seed', and q0, qd0 default to its consistent initial state).
    q0, qd0 : (m,) array_like
        Initial state; it should satisfy the constraints (see ``study.solver.initial``).
    t_end : float
        End time [s], > 0.
    method : str or Stabilization
        Stabilization: 'none', 'baumgarte', 'sliding_mode', 'projection'; options go in
        ``method_options`` (d, omega or alpha, beta; Lambda, K, k, sgn, width; weighting). Or a
        ``study.solver.stabilization.Stabilization`` object (e.g. ``Baumgarte(d=1, omega=10)``, or a
        user's subclass on the reference backend), whose fields are its options.
    integrator : str
        'RK45', 'DOP853', 'RK23', 'Radau', 'LSODA' (scipy, adaptive: ``rtol``, default 1e-8, and ``atol``,
        default 1e-10) or 'RK4' (fixed ``step``, no longer than ``t_end``): these integrate the
        accelerations of ``acceleration_solver`` stabilized by ``method``. Or 'ALI3P' (fixed ``step``): the
        index-3 augmented Lagrangian with mass-orthogonal projections of Bayo and Ledesma on the trapezoidal
        rule (``study.solver.index3``), which holds the position constraints itself and passes singular
        positions; it takes no ``method`` but 'none', no ``acceleration_solver``, no friction, no switching
        loads, and runs on the reference backend. An argument the chosen integrator would ignore (``step``
        for an adaptive one, ``rtol``/``atol`` for a fixed-step one) is refused.
    acceleration_solver : str, optional
        'multiplier' (the default), 'partitioned' (R/D matrix) or 'orthonormal' (these need a full-rank
        Phi_q: a run stops at a singular pose with a SingularConfigurationError naming the time, pose and
        rank), or 'augmented_lagrangian' (passes singular poses and redundant constraints; no singularity
        monitor).
    output_step : float
        Spacing of the saved samples [s].
    friction : {'default', 'none', 'exact', 'regularized', 'sign'}
        Coulomb friction at the sliding contacts and pins (``study.solver.friction``). 'default': the parameter
        set's treatment of every entry with friction (``study.friction_default``); 'none' (or None) leaves them
        out, named in ``meta['friction_left_out']``. 'exact': event-located stick/slip; 'regularized': sgn replaced
        by ``friction_sgn`` ('tanh', 'sat', 'arctan', 'sqrt'; default 'tanh') of width ``friction_eps``
        [m/s] (default 1e-3); 'sign': paper 000's plain sgn (use with integrator='RK4'). ``friction_eps``
        also sets the band |v_t| <= eps reported as apparent stick by 'regularized' and 'sign'. A
        width or sgn the chosen treatment does not use is refused. The result gains
        forces ``normal_<c>``, ``friction_<c>``, ``stick_<c>`` and energies ``work_friction_<c>``.
        Revolute joints with friction (``Description.revolute(..., friction=, radius=)``) follow the contacts in
        these outputs (``normal_<pin>`` = |R| [N], ``friction_<pin>`` = the torque on the joint's first body
        [N m], ``friction_eps`` read in rad/s), with every treatment on both backends.
    resistance_reading : {None, 'holds', 'sliding_only'}
        Whether a contact's constant resistance counts in the static limit of the 'exact' treatment
        (``study.solver.friction.RESISTANCE_READINGS``). None: the parameter set's
        ``resistance_reading`` if it has one, else 'holds' (``study.model.SlidingContact.resistance``).
    backend : {'reference', 'compiled'}
        'reference': the Python solver with scipy's integrators. 'compiled': generated numba code and a
        compiled integration loop (``study.fast``; multiplier solver, RK23/RK45/DOP853/RK4; Radau and
        LSODA take scipy's steps on the compiled evaluations); an unsupported combination raises a
        ValueError naming the option.
    check : bool
        Validate the equations and the initial state once before the run (``study.solver.checks``:
        symmetric positive-definite M(q0), phi_q and gamma against finite differences of phi and
        phi_q, q0 and qd0 on the constraints); False skips it. A singular pose is refused either way.
    max_evaluations : float, optional
        Bound on right-hand-side evaluations (default ``max_evaluations`` in reference/tolerances.toml).
        A fixed-step run that needs more is refused before it starts, with its estimate.
    min_step : float, optional
        Smallest step of an adaptive integrator [s] (default ``min_step_fraction`` * t_end).
    max_output_bytes : float, optional
        Bound on the estimated memory of the output (default ``max_output_bytes``).

    Raises
    ------
    ValueError
        A bad argument (named); ``study.errors.EquationsError`` for equations or a state that fail
        the checks; ``study.errors.RunTooLargeError`` for a run refused by its estimate.
    study.errors.SimulationError
        The run failed: non-finite values, a singular configuration, a bound reached (time, quantity
        and likely cause in the message).

    Returns
    -------
    SimulationResult
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
