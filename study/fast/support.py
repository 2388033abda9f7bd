"""What the compiled backend supports, checked before anything is compiled.

A compiled run compiles the kernels it needs on a cold cache (most of a minute), so a run that the compiled backend
cannot do is refused from here, by ``study.simulate`` as soon as its arguments are checked.
"""

from __future__ import annotations

#: The compiled loop's integrators and their ids in the kernels (study.fast.steppers).
METHOD_IDS = {"RK23": 0, "RK45": 1, "DOP853": 2, "RK4": 3}
SUPPORTED_INTEGRATORS = tuple(METHOD_IDS)
SUPPORTED_ACCELERATION_SOLVERS = ("multiplier",)
#: Integrators whose steps only scipy takes: on backend 'compiled' scipy's loop runs on compiled evaluations.
SCIPY_STEPS_ONLY = ("Radau", "LSODA")


def check_supported(integrator: str, acceleration_solver: str, progress=None) -> None:
    """ValueError naming every option the compiled backend does not support.

    The integrators of the compiled loop (``SUPPORTED_INTEGRATORS``) and, with scipy's loop on compiled
    evaluations (``SCIPY_STEPS_ONLY``), Radau and LSODA; ``progress`` only on scipy's loop."""
    problems = []
    if integrator not in (*SUPPORTED_INTEGRATORS, *SCIPY_STEPS_ONLY):
        problems.append(f"integrator={integrator!r} (compiled: {', '.join((*SUPPORTED_INTEGRATORS, *SCIPY_STEPS_ONLY))})")
    if acceleration_solver not in SUPPORTED_ACCELERATION_SOLVERS:
        problems.append(f"acceleration_solver={acceleration_solver!r} (compiled: "
                        f"{', '.join(SUPPORTED_ACCELERATION_SOLVERS)})")
    if progress is not None and integrator not in SCIPY_STEPS_ONLY:
        problems.append("progress= (the compiled loop does not call back into Python)")
    if problems:
        raise ValueError("backend='compiled' does not support " + "; ".join(problems) + "; use backend='reference'")
