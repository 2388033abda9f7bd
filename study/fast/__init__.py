"""Compiled fast path: numba kernels on code generated from the same sympy CSE output as the reference.

``simulate(..., backend='compiled')`` runs here; the compiling machinery (cache, signatures, sgn kernels, LU) is
``study.kernels``. Modules, one concern each:

codegen
    The numba module of a mechanism description (``evaluate``, ``indicators``, ``kinematics``), written by
    study.model.codegen (the one generator, shared with the reference) and loaded here; the load laws are the
    description's expressions, compiled with the rest.
user
    A user's EquationsOfMotion compiled from its callables.
dynamics
    Constraint right-hand side (each stabilization's own compiled bias), multiplier solve, the coupled
    normal-force/friction solve (each friction treatment's own compiled phases), the right-hand side.
steppers
    RK23/RK45/DOP853 (scipy's tableaus and error control) and RK4 steps with their dense output.
loop
    The compiled integration loop: step control, located switches, projection, sampling.
frontend
    Python side: option checks (ValueError for what is not compiled), packing, events; the run's setup
    and result assembly are the reference's (``study.solver.run``, ``study.solver.assemble``).
"""

from study.kernels import cache as _cache

__all__ = ["CompiledModel", "compiled_model", "compiled_rhs", "simulate_compiled"]


def __getattr__(name: str):
    """The frontend's names, imported when first asked for: the cache folder is checked before the entry kernels
    compile or load, and ``import study`` does not load the compiled path until a run needs it."""
    if name in __all__:
        _cache.check()   # a cache folder that cannot be used is refused before the entry kernels compile or load
        from study.fast import frontend

        return getattr(frontend, name)
    raise AttributeError(f"module 'study.fast' has no attribute {name!r}")
