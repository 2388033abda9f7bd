"""numba types of the generated functions, which the kernels receive as first-class functions.

Passing them as ``FunctionType`` (not as dispatcher objects) keeps the kernels' cache key stable
across processes, so a kernel is compiled once per machine, not once per run.
"""

from numba import types

f8 = types.float64
i8 = types.int64
V1 = types.Array(f8, 1, "C")
V2 = types.Array(f8, 2, "C")
I1 = types.Array(i8, 1, "C")
B1 = types.Array(types.boolean, 1, "C")

#: evaluate(t, q, qd, mode, p, lp, M, Q, phi, J, gamma, Jt, bt, powers)
EVALUATE = types.void(f8, V1, V1, I1, V1, V1, V2, V1, V1, V2, V1, V2, V1, V1)
#: indicators(t, q, qd, p, lp, out): switching functions of discontinuous loads
INDICATORS = types.void(f8, V1, V1, V1, V1, V1)
#: kinematics(q, p, phi, J, M): constraints, their Jacobian and the mass matrix (projection)
KINEMATICS = types.void(V1, V1, V1, V2, V2)

#: bias(phi, phidot, cf, offset, out): a stabilization's b(Phi, Phidot), its parameters at cf[offset:]
BIAS = types.void(V1, V1, V1, i8, V1)
#: phases(mode, n_load_modes, v_t, cf, offset, stick, s): a friction treatment's stick flags and slip factors of
#: the contacts, its parameters at cf[offset:]
PHASES = types.void(I1, i8, V1, V1, i8, B1, V1)
#: sgn(s, width): an approximation of sgn (study.kernels.signs)
SIGN = f8(f8, f8)

EVALUATE_T = types.FunctionType(EVALUATE)
BIAS_T = types.FunctionType(BIAS)
PHASES_T = types.FunctionType(PHASES)
INDICATORS_T = types.FunctionType(INDICATORS)
KINEMATICS_T = types.FunctionType(KINEMATICS)
