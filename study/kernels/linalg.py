"""Small dense linear algebra for the compiled path: LU with partial pivoting, in place.

The systems are the (m + r)-square saddle-point matrices of the acceleration problem (5 x 5 for
the quick-return) and the contacts' small friction systems: a hand-written elimination avoids the
call and allocation cost of LAPACK at this size. Partial pivoting is what LAPACK's getrf does too.
"""

from __future__ import annotations

from study.kernels.cache import internal


@internal()
def lu_factor(A, piv):
    """Factor the square A in place (L unit lower, U upper); returns False if A is singular."""
    n = A.shape[0]
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big, p = abs(A[i, k]), i
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            A[i, k] *= inv
            f = A[i, k]
            if f != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    return True


@internal()
def lu_solve(LU, piv, b):
    """Solve with a factor from :func:`lu_factor`; b is overwritten with the solution."""
    n = LU.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= LU[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * b[j]
        b[i] = s / LU[i, i]
