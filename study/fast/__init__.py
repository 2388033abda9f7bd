"""Compiled fast path: numba kernels on code generated from the same sympy CSE output as the reference.

``simulate(..., backend='compiled')`` runs here. Modules, one concern each:

cache
    Where compiled code lives: numba's on-disk cache under ``cache_dir()/numba/<source hash>``.
signatures
    The numba function types shared by the generated code and the kernels.
codegen
    sympy -> CSE -> a numba module per mechanism description (``evaluate``, ``indicators``, ``kinematics``);
    the load laws are the description's expressions, compiled with the rest.
linalg
    Small dense LU with partial pivoting.
dynamics
    Stabilization bias, multiplier solve, the coupled normal-force/friction solve, the right-hand side.
steppers
    RK23/RK45/DOP853 (scipy's tableaus and error control) and RK4 steps with their dense output.
loop
    The compiled integration loop: step control, located switches, projection, sampling.
frontend
    Python side: option checks (ValueError for what is not compiled), packing, events; the run's setup
    and result assembly are the reference's (``study.solver.run``, ``study.solver.assemble``).
"""

from study.fast import cache as _cache  # noqa: F401  (sets numba's cache folder before any kernel is defined)
from study.fast.frontend import CompiledModel, compiled_model, simulate_compiled

__all__ = ["CompiledModel", "compiled_model", "simulate_compiled"]
