"""Exact zero tests and display simplification of the (trigonometric, sign-carrying) formulas."""

from __future__ import annotations

import sympy as sp


def without_signs(expr: sp.Expr) -> tuple[sp.Expr, dict]:
    """expr with every sign(...) replaced by a dummy symbol, and the map back."""
    dummies = {s: sp.Dummy(f"sign{k}") for k, s in enumerate(sorted(expr.atoms(sp.sign), key=sp.default_sort_key))}
    return expr.xreplace(dummies), {d: s for s, d in dummies.items()}


def trig_canonical(expr: sp.Expr) -> sp.Expr:
    """A polynomial in sin, cos of single angles, written in the basis sin^a cos^b with a in {0, 1}.

    Sums of angles are expanded and sin^2 is replaced by 1 - cos^2, so two such polynomials are
    equal exactly when their canonical forms are (no heuristic simplification involved).
    """
    expr = sp.expand(sp.expand_trig(expr))

    def reduce(power):
        angle, n = power.base.args[0], int(power.exp)
        return sp.sin(angle) ** (n % 2) * (1 - sp.cos(angle) ** 2) ** (n // 2)

    expr = expr.replace(lambda x: x.is_Pow and isinstance(x.base, sp.sin) and x.exp.is_Integer and x.exp > 1, reduce)
    return sp.expand(expr)


def is_zero(expr: sp.Expr) -> bool:
    """Is expr identically zero? (sign(...) factors are treated as independent unknowns.)"""
    expr = sp.sympify(expr)
    if expr == 0:
        return True
    expr, _ = without_signs(expr)
    numerator, _ = sp.fraction(sp.together(expr))
    return trig_canonical(numerator) == 0


def simplify(expr: sp.Expr) -> sp.Expr:
    """A compact form for display: factor, then trigsimp (sign(...) arguments separately)."""
    expr = sp.sympify(expr)
    if expr.is_number:
        return expr
    expr, back = without_signs(expr)
    out = sp.factor(sp.expand(expr))
    trig = sp.trigsimp(out)
    if not trig.has(sp.pi):  # trigsimp may trade sin/cos sums for sqrt(2) sin(x + pi/4): keep those factored
        out = trig
    return out.xreplace({d: sp.sign(simplify(s.args[0])) for d, s in back.items()})
