"""The verdict of one printed formula against its derived target (exact, equivalent on the manifold, wrong)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Mapping, Sequence

import numpy as np
import sympy as sp

from study import mechanisms
from study.errata.algebra import is_zero, trig_canonical
from study.errata.derived import PaperContext
from study.errata.latex import tex_against, tex_difference, tex_marked, tex_matrix
from study.errata.printed import PAPERS
from study.model.initial_state import consistent_initial_conditions

EXACT = "exact"
EQUIVALENT = "equivalent on the constraint manifold"
WRONG = "wrong"
VERDICTS = (EXACT, EQUIVALENT, WRONG)
# Two expressions agree numerically when |a - b| <= MANIFOLD_RTOL * (sum of the magnitudes of
# their terms). Newton leaves |Phi| <= 1e-13 on lengths of O(1..10) m, a relative violation of
# ~1e-14; differences that vanish on the manifold are proportional to it, rounding in sums of
# up to ~10 terms adds ~1e-15. 1e-8 leaves a margin of 1e5 and is still 1e7 below any misprint.
MANIFOLD_RTOL = 1e-8
# Printed numbers without decimals (such as pi/6) must agree to round-off.
EXACT_NUMBER_RTOL = 1e-12
# Targets on the left-hand side of M qdd + C qd + dV/dq + Phi_q^T lambda = Q: a printed term that
# exceeds the derived one by Phi_q^T mu lowers the multipliers by mu (on the right-hand side it
# raises them).
_LEFT_HAND_SIDE = {"velocity_terms", "potential_gradient", "gravity_potential"}


def printed_matrix(ctx: PaperContext, expr: Any) -> sp.Matrix:
    """A printed scalar, vector (column) or matrix (list of rows) as a sympy Matrix."""
    if isinstance(expr, list) and expr and isinstance(expr[0], list):
        return sp.Matrix([[ctx.parse(x) for x in row] for row in expr])
    if isinstance(expr, list):
        return sp.Matrix([ctx.parse(x) for x in expr])
    return sp.Matrix([ctx.parse(expr)])


def select(target: sp.Matrix, index: Any) -> sp.Matrix:
    """Entries of target at 1-based index [i], [i, j] or a list of such (as a column)."""
    if index is None:
        return target
    if isinstance(index[0], list):
        return sp.Matrix([select(target, i)[0] for i in index])
    if len(index) == 1:
        flat = target if target.cols == 1 else target.T
        return sp.Matrix([flat[index[0] - 1]])
    return sp.Matrix([target[index[0] - 1, index[1] - 1]])


def show_matrix(ctx: PaperContext, mat: sp.Matrix, simplified: bool = True) -> str:
    def show(x):
        return ctx.show(x, simplified)

    if mat.shape == (1, 1):
        return show(mat[0])
    if mat.cols == 1:
        return "[" + ", ".join(show(x) for x in mat) + "]"
    return "[" + ", ".join("[" + ", ".join(show(x) for x in mat.row(i)) + "]" for i in range(mat.rows)) + "]"


def _label(mat: sp.Matrix, k: int) -> str:
    i, j = divmod(k, mat.cols)
    return f"[{i + 1}]" if mat.cols == 1 else f"[{i + 1},{j + 1}]"


def _agree_numerically(ctx: PaperContext, printed: Sequence[sp.Expr], derived: Sequence[sp.Expr]) -> list[bool]:
    """Per element: do printed and derived agree at every manifold sample?"""
    smp = ctx.samples()
    diff = smp.evaluate(ctx, [p - d for p, d in zip(printed, derived)])
    scale = smp.magnitude(ctx, list(printed)) + smp.magnitude(ctx, list(derived))
    return list(np.all(np.abs(diff) <= MANIFOLD_RTOL * scale + 1e-300, axis=0))


def _differences(ctx: PaperContext, printed: sp.Matrix, derived: sp.Matrix) -> list[int]:
    return [k for k in range(len(printed)) if not is_zero(printed[k] - derived[k])]


def _difference_note(ctx: PaperContext, printed: sp.Matrix, derived: sp.Matrix, which: Sequence[int]) -> str:
    label = (lambda k: _label(printed, k) + " ") if len(printed) > 1 else (lambda k: "")
    return "; ".join(f"{label(k)}printed - derived = {ctx.show(printed[k] - derived[k])}" for k in which)


def _multiplier(ctx: PaperContext, delta: sp.Matrix) -> sp.Matrix | None:
    """mu with delta = Phi_q^T mu, if delta is a multiple of one constraint gradient."""
    phi_q = ctx.eqs.phi_q
    for k in range(phi_q.rows):
        row = phi_q.row(k).T
        pivots = [i for i in range(len(row)) if not is_zero(row[i])]
        if not pivots:
            continue
        c = sp.cancel(trig_canonical(delta[pivots[0]]) / trig_canonical(row[pivots[0]]))
        if all(is_zero(delta[i] - c * row[i]) for i in range(len(row))):
            mu = sp.zeros(phi_q.rows, 1)
            mu[k] = c
            return mu
    return None


def _in_range_of_phi_q_t(ctx: PaperContext, delta: sp.Matrix, scale_exprs: Sequence[sp.Expr]) -> bool:
    """Is R^T delta = 0 at every sample (R an orthonormal null-space basis of Phi_q)?"""
    smp = ctx.samples()
    values = smp.evaluate(ctx, list(delta))                    # (S, m)
    scale = smp.magnitude(ctx, list(scale_exprs)).max(axis=1)  # (S,)
    projected = np.einsum("smn,sm->sn", smp.null, values)
    return bool(np.all(np.abs(projected) <= MANIFOLD_RTOL * scale[:, None] + 1e-300))


def _range_note(ctx: PaperContext, delta: sp.Matrix, target: str) -> str:
    mu = _multiplier(ctx, delta)
    sign = "-" if target.split(" + ")[0] in _LEFT_HAND_SIDE else "+"
    if mu is None:
        return ("printed - derived lies in the range of Phi_q^T at every sample: the motion is unchanged, "
                "only the multipliers change")
    return (f"printed - derived = Phi_q^T mu with mu = {show_matrix(ctx, mu)}: the motion is unchanged, "
            f"the multipliers become lambda {sign} mu (M qdd + C qd + dV/dq + Phi_q^T lambda = Q)")


@dataclass(frozen=True)
class _Judgement:
    verdict: str
    derived: str
    finding: str
    derived_latex: str = ""
    difference_latex: str = ""


def _judge_expression(ctx: PaperContext, entry: Mapping[str, Any], expr: Any) -> _Judgement:
    printed = printed_matrix(ctx, expr)
    derived = select(ctx.target(entry["target"]), entry.get("index"))
    if printed.shape != derived.shape and printed.shape == derived.T.shape:
        derived = derived.T
    if printed.shape != derived.shape:
        raise ValueError(f"{entry['id']}: printed shape {printed.shape} != derived shape {derived.shape}")
    kind = entry["kind"]
    if kind == "equation":
        return _judge_equation(ctx, printed, derived)
    if kind == "potential":
        return _judge_potential(ctx, printed, derived)
    which = _differences(ctx, printed, derived)
    if not which:  # identical: the printed form is a form of the derived one
        return _Judgement(EXACT, show_matrix(ctx, printed, simplified=False), "",
                          tex_matrix(printed, lambda k: ctx.tex(printed[k])))
    shown = show_matrix(ctx, derived)
    tex = (tex_matrix(derived, lambda k: tex_against(ctx, derived[k], printed[k])),
           tex_difference(ctx, printed, derived))
    note = _difference_note(ctx, printed, derived, which)
    agree = _agree_numerically(ctx, [printed[k] for k in which], [derived[k] for k in which])
    if all(agree):
        return _Judgement(EQUIVALENT, shown, note + " (zero at every manifold sample)", *tex)
    if kind == "generalized_force":
        delta = printed - derived
        columns = [delta.col(j) for j in range(delta.cols)]
        if all(_in_range_of_phi_q_t(ctx, col, list(printed.col(j)) + list(derived.col(j)))
               for j, col in enumerate(columns)):
            notes = [_range_note(ctx, col, entry["target"]) for col in columns if any(not is_zero(x) for x in col)]
            return _Judgement(EQUIVALENT, shown, note + ". " + "; ".join(notes), *tex)
    return _Judgement(WRONG, shown, note, *tex)


def _judge_equation(ctx: PaperContext, printed: sp.Matrix, derived: sp.Matrix) -> _Judgement:
    p, d = printed[0], derived[0]
    as_printed = ctx.tex(p) + " = 0"
    if is_zero(p - d):
        return _Judgement(EXACT, ctx.show(p, simplified=False) + " = 0", "", as_printed)
    ratio = sp.cancel(trig_canonical(p) / trig_canonical(d))
    state = set(ctx.q) | set(ctx.qd) | set(ctx.qdd)
    if ratio != 0 and not (ratio.free_symbols & state) and is_zero(p - ratio * d):
        return _Judgement(EXACT, ctx.show(p, simplified=False) + " = 0", f"the printed equation is the derived one times {ctx.show(ratio)}",
                          as_printed)
    shown = ctx.show(d) + " = 0"
    tex = (tex_against(ctx, d, p) + " = 0", tex_difference(ctx, printed, derived))
    smp = ctx.samples()
    value = smp.evaluate(ctx, [p])[:, 0]
    scale = smp.magnitude(ctx, [p])[:, 0]
    note = f"printed - derived = {ctx.show(p - d)}"
    if np.all(np.abs(value) <= MANIFOLD_RTOL * scale + 1e-300):
        return _Judgement(EQUIVALENT, shown, note + " (the printed equation holds wherever the derived one does)", *tex)
    return _Judgement(WRONG, shown, note + " (the printed equation fails where the derived one holds)", *tex)


def _judge_potential(ctx: PaperContext, printed: sp.Matrix, derived: sp.Matrix) -> _Judgement:
    """A potential matters only through its gradient: an additive constant is allowed."""
    p, d = printed[0], derived[0]
    diff = p - d
    grad = sp.Matrix([diff]).jacobian(ctx.q).T
    if all(is_zero(x) for x in grad):
        extra = "" if is_zero(diff) else f"the two differ by the constant {ctx.show(diff)}"
        return _Judgement(EXACT, ctx.show(p, simplified=False), extra, ctx.tex(p))
    shown = ctx.show(d)
    tex = (tex_against(ctx, d, p), tex_difference(ctx, printed, derived))
    note = f"printed - derived = {ctx.show(diff)}"
    smp = ctx.samples()
    values = smp.evaluate(ctx, [diff])[:, 0]
    scale = (smp.magnitude(ctx, [p]) + smp.magnitude(ctx, [d]))[:, 0]
    if np.ptp(values) > MANIFOLD_RTOL * scale.max():
        return _Judgement(WRONG, shown, note, *tex)
    return _Judgement(EQUIVALENT, shown, note + ", constant on the manifold; for the gradients, "
                      + _range_note(ctx, grad, "potential_gradient"), *tex)


def _judge_sparse(ctx: PaperContext, entry: Mapping[str, Any]) -> _Judgement:
    target = ctx.target(entry["target"])
    listed, bad, printed = set(), [], {}
    for i, j, text in entry["expr"]:
        p = printed[i, j] = ctx.parse(text)
        if is_zero(p - target[i - 1, j - 1]):
            listed.add((i, j))
        else:
            bad.append(f"[{i},{j}] printed {ctx.show(p)}, derived {ctx.show(target[i - 1, j - 1])}")
    nonzero = [(i + 1, j + 1) for i in range(target.rows) for j in range(target.cols) if not is_zero(target[i, j])]
    missing = [f"[{i},{j}] = {ctx.show(target[i - 1, j - 1])} not listed" for i, j in nonzero if (i, j) not in listed]
    shown = "; ".join(f"[{i},{j}] = {ctx.show(target[i - 1, j - 1])}" for i, j in nonzero)
    # an entry the paper does not list is marked whole (compared with 0)
    tex = r",\quad ".join(f"[{i},{j}] = {tex_against(ctx, target[i - 1, j - 1], printed.get((i, j), sp.S.Zero))}"
                          for i, j in nonzero)
    verdict = EXACT if not bad and not missing else WRONG
    return _Judgement(verdict, shown, "; ".join(bad + missing), tex)


def _decimals(text: Any) -> int | None:
    match = re.fullmatch(r"\s*[-+]?\d*\.(\d+)\s*", str(text))
    if match:
        return len(match.group(1))
    return 0 if re.fullmatch(r"\s*[-+]?\d+\s*", str(text)) else None


def _judge_initial(ctx: PaperContext, entry: Mapping[str, Any]) -> _Judgement:
    ic = ctx.ps.initial
    ind = list(ic.independent)
    kin = ctx.kinematics(ctx.seed_values())
    rates = entry["target"] == "qd0"
    q_text = entry["q"] if rates else entry["expr"]
    q_printed = np.array([float(ctx.parse(x)) for x in q_text])
    printed = np.array([float(ctx.parse(x)) for x in entry["expr"]])
    qd_ind = printed[ind] if rates else np.zeros(len(ind))
    state = consistent_initial_conditions(kin, q_printed, ind, qd_ind)
    ours = state.qd if rates else state.q
    bad, shown, tex = [], [], []
    for k, text in enumerate(entry["expr"]):
        d = _decimals(text)
        tol = 0.5 * 10.0 ** -d if d is not None else EXACT_NUMBER_RTOL * max(1.0, abs(printed[k]))
        shown.append(f"{ours[k]:.{max(6, (d or 0) + 2)}f}")
        tex.append(shown[-1])
        if abs(ours[k] - printed[k]) > tol * (1 + 1e-9):
            bad.append(f"[{k + 1}] printed {text}, reproduced {ours[k]:.6g}")
            tex[-1] = tex_marked(tex[-1])
    name = "qd(0)" if rates else "q(0)"
    branch = "satisfies" if mechanisms.on_branch(ctx.ps, state.q) else "VIOLATES"
    if rates:
        residual = f"|Phi_q qd| of the printed qd(0) at the consistent q(0): {np.max(np.abs(kin.phi_q(state.q) @ printed)):.3g}"
    else:
        residual = f"|Phi| of the printed q(0): {np.max(np.abs(kin.phi(q_printed))):.3g}"
    finding = "; ".join(bad + [residual, f"the Newton solution {branch} the assembly-branch test ({ic.branch})"])
    symbol = r"\dot{q}(0)" if rates else "q(0)"
    return _Judgement(EXACT if not bad else WRONG, f"{name} = [{', '.join(shown)}]", finding,
                      symbol + r" = \begin{bmatrix}" + r" \\ ".join(tex) + r"\end{bmatrix}")


def check_formula(entry: Mapping[str, Any]) -> dict[str, str]:
    """Judge one printed formula (an entry of printed_formulas.toml); returns one table row.

    Parameters
    ----------
    entry : mapping
        Keys as documented in ``reference/printed_formulas.toml``.

    Returns
    -------
    dict
        formula, paper, equation, verdict, printed, derived, derived_latex (the derived form as
        LaTeX, with the terms the printed formula lacks in DIFFERENCE_COLOR), difference_latex
        (printed - derived as LaTeX, empty where they are identical), note.
    """
    ctx = paper_context(entry["paper"])
    kind = entry["kind"]
    if kind == "sparse":
        judged = _judge_sparse(ctx, entry)
    elif kind == "initial_conditions":
        judged = _judge_initial(ctx, entry)
    else:
        judged = _judge_expression(ctx, entry, entry["expr"])
    note = f"{entry['quantity']}. {entry['note']}"
    if judged.finding:
        note += f" Check: {judged.finding}."
    if "reading" in entry:
        alt = _judge_expression(ctx, entry, entry["reading"])
        note += f" Read as {show_matrix(ctx, printed_matrix(ctx, entry['reading']))}: {alt.verdict}."
    return {
        "formula": entry["id"],
        "paper": entry["paper"],
        "equation": entry["equation"],
        "verdict": judged.verdict,
        "printed": entry["printed"],
        "derived": judged.derived,
        "derived_latex": judged.derived_latex,
        "difference_latex": judged.difference_latex,
        "note": note,
    }


@lru_cache(maxsize=None)
def paper_context(paper: str) -> PaperContext:
    return PaperContext(PAPERS[paper])
