"""Compiled-kernel machinery shared by every layer above it: no mechanism, no law of motion, only how code is compiled.

cache
    Where compiled code lives: numba's on-disk cache under ``cache_dir()/numba/<source hash>``, checked before
    use, with entries that heal (``kernel``, numba's ``njit`` with that cache; ``internal`` for inlined helpers).
linking
    Helpers compiled for linking only: optimized and turned into machine code once, in the kernel that calls them.
signatures
    The numba function types shared by the generated code, the stabilization methods, the friction
    treatments and the kernels.
signs
    The sgn approximations by name, one numba function each for both backends (sliding-mode bias,
    friction laws, the Exudyn guards).
linalg
    Small dense LU with partial pivoting.
"""
