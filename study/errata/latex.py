"""The errata's typeset forms: printed symbols as LaTeX, and derived forms with the terms the printed one lacks marked."""

from __future__ import annotations

import re
from typing import Callable

import sympy as sp

from study.errata.algebra import is_zero, simplify, trig_canonical

# Colour of the derived terms (entries) that the printed formula lacks, in ``derived_latex``. A
# scoped ``{\color{...} ...}`` renders the same in MathJax (code hosts) and in latex2mathml (report).
DIFFERENCE_COLOR = "crimson"


def tex_symbol(name: str) -> str:
    """LaTeX of a printed symbol name: q1 -> q_{1}, qd1 -> \\dot{q}_{1}, qdd1 -> \\ddot{q}_{1}, l1 -> l_{1}."""
    match = re.fullmatch(r"q(d{0,2})(\d+)", name)
    if match:
        return {"": "q", "d": r"\dot{q}", "dd": r"\ddot{q}"}[match.group(1)] + f"_{{{match.group(2)}}}"
    return sp.latex(sp.Symbol(name))


def tex_marked(tex: str) -> str:
    return rf"{{\color{{{DIFFERENCE_COLOR}}}{tex}}}"


def _terms(expr: sp.Expr) -> set[sp.Expr]:
    """The terms of expr in the canonical trigonometric basis (see trig_canonical)."""
    return set(sp.Add.make_args(trig_canonical(expr)))


def tex_against(ctx, derived: sp.Expr, printed: sp.Expr | None) -> str:
    """LaTeX of derived in its display form; where printed differs, the derived terms that printed
    lacks (compared term by term after expansion) are marked in DIFFERENCE_COLOR.
    A derived entry that is one term (a product) is marked whole."""
    shown = simplify(derived)
    if printed is None or is_zero(printed - derived):
        return ctx.tex(shown)
    have = _terms(printed)
    terms = shown.as_ordered_terms() if isinstance(shown, sp.Add) else [shown]
    parts = []
    for k, term in enumerate(terms):
        negative = term.could_extract_minus_sign()
        body = ctx.tex(-term if negative else term)
        if isinstance(-term if negative else term, sp.Add):
            body = rf"\left({body}\right)"
        if not _terms(term) <= have:
            body = tex_marked(body)
        parts.append(("- " if negative else ("+ " if k else "")) + body)
    return " ".join(parts)


def tex_matrix(mat: sp.Matrix, entry: Callable[[int], str]) -> str:
    """A scalar as its entry, a vector or matrix as a bmatrix of the entries (k in row-major order)."""
    if mat.shape == (1, 1):
        return entry(0)
    rows = [" & ".join(entry(i * mat.cols + j) for j in range(mat.cols)) for i in range(mat.rows)]
    return r"\begin{bmatrix}" + r" \\ ".join(rows) + r"\end{bmatrix}"


def tex_difference(ctx, printed: sp.Matrix, derived: sp.Matrix) -> str:
    """LaTeX of printed - derived, simplified, entry by entry."""
    delta = printed - derived
    return tex_matrix(delta, lambda k: ctx.tex(simplify(delta[k])))
