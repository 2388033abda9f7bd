"""Errata: the papers' printed formulas checked against the equations derived from the mechanisms.

``reference/printed_formulas.toml`` holds every checked formula of papers 000 (slider-crank) and
001 (quick-return) as printed, in sympy syntax. Each one names the derived quantity it claims to be
(its ``target``), which is built here from the mechanism's body-level description
(:func:`study.mechanisms.slider_crank.describe`, :func:`study.mechanisms.quick_return.describe`)
through :func:`study.model.derive.derive`, i.e.

    M qdd + C qd + dV/dq + Phi_q^T lambda = Q_applied.

Verdicts
--------
``exact``
    symbolically identical after simplification (an equation may differ by a constant factor).
``equivalent on the constraint manifold``
    not identical, but the same wherever it matters: equal at random points with Phi = 0,
    Phi_q qd = 0 (and Phi_q qdd = gamma); for generalized forces it is enough that the difference
    lies in the range of Phi_q^T (it moves load into the constraint reactions: the motion is
    unchanged, only the multipliers change; the note gives the shift mu).
``wrong``
    differs on the manifold; ``derived`` holds the corrected form.

Printed numbers (initial conditions) are ``exact`` when Newton-Raphson from the printed independent
values reproduces every printed number to its printed digits, else ``wrong``.

The numeric checks use parameter values spread randomly around the seed set (so that coincidences
of the seed such as a1 = 0 or c2 = l2/2 cannot hide a misprint) and configurations along a whole
turn of the crank, reached by continuation with :func:`study.solver.initial.consistent_initial_conditions`.
"""

from __future__ import annotations

import argparse
import re
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import pandas as pd
import sympy as sp

from study import mechanisms
from study.mechanisms import quick_return, slider_crank
from study.model.builder import MechanismBuilder
from study.model.derive import SymbolicEquations, derive
from study.params import REFERENCE_DIR, ParameterSet, load_parameters
from study.report.render import md_escape, md_math, md_table
from study.solver.initial import consistent_initial_conditions

FORMULAS_PATH = REFERENCE_DIR / "printed_formulas.toml"
DEFAULT_OUT_DIR = Path(__file__).resolve().parent.parent / "reports" / "tables"

EXACT = "exact"
EQUIVALENT = "equivalent on the constraint manifold"
WRONG = "wrong"
VERDICTS = (EXACT, EQUIVALENT, WRONG)
COLUMNS = ("formula", "paper", "equation", "verdict", "printed", "derived", "derived_latex", "difference_latex",
           "note")
# Colour of the derived terms (entries) that the printed formula lacks, in ``derived_latex``. A
# scoped ``{\color{...} ...}`` renders the same in MathJax (code hosts) and in latex2mathml (report).
DIFFERENCE_COLOR = "crimson"
KINDS = ("expression", "generalized_force", "potential", "equation", "sparse", "initial_conditions")

# Number of random configurations on the constraint manifold per mechanism; each one is a full
# (q, qd, qdd) state, spread over a whole crank turn. A misprint would have to vanish at all of
# them by accident.
SAMPLES = 8
RNG_SEED = 20240611
# Relative spread of the randomized parameters around the seed values. Small enough that both
# mechanisms still assemble over a whole crank turn (001 needs |h2 - l2 sin q2| < l3 and h1 > l1),
# large enough to break the seed's coincidences. Seed values of exactly zero (001's a1) are
# replaced by a value drawn from ZERO_PARAMETER_RANGE.
PARAMETER_SPREAD = 0.03
ZERO_PARAMETER_RANGE = (0.1, 0.5)
# Largest step of the independent coordinate in the continuation between samples [rad].
CONTINUATION_STEP = 0.1
# Two expressions agree numerically when |a - b| <= MANIFOLD_RTOL * (sum of the magnitudes of
# their terms). Newton leaves |Phi| <= 1e-13 on lengths of O(1..10) m, a relative violation of
# ~1e-14; differences that vanish on the manifold are proportional to it, rounding in sums of
# up to ~10 terms adds ~1e-15. 1e-8 leaves a margin of 1e5 and is still 1e7 below any misprint.
MANIFOLD_RTOL = 1e-8
# Printed numbers without decimals (such as pi/6) must agree to round-off.
EXACT_NUMBER_RTOL = 1e-12


@dataclass(frozen=True)
class PaperSpec:
    """How a paper's printed symbols map onto a mechanism description.

    ``extras``: printed symbols that are not parameters (load magnitudes), with their meaning.
    ``loads``: load or contact name -> printed symbol of its magnitude.
    ``inputs``: the paper's input vector u, as (load name, force direction or None for a torque).
    """

    paper: str
    mechanism: str
    module: ModuleType
    extras: Mapping[str, str]
    loads: Mapping[str, str]
    inputs: tuple[tuple[str, tuple[int, int] | None], ...] = ()


PAPERS: dict[str, PaperSpec] = {
    "000": PaperSpec(
        "000", "slider_crank", slider_crank,
        extras={"M": "drive torque on the crank", "F_ms": "signed friction force on the slider along +x"},
        loads={"drive": "M", "guide": "F_ms"},
    ),
    "001": PaperSpec(
        "001", "quick_return", quick_return,
        extras={"M": "drive torque on the crank", "F": "cutting force on the ram along +x"},
        loads={"drive": "M", "cutting": "F"},
        inputs=(("drive", None), ("cutting", (1, 0))),
    ),
}

# Targets on the left-hand side of M qdd + C qd + dV/dq + Phi_q^T lambda = Q: a printed term that
# exceeds the derived one by Phi_q^T mu lowers the multipliers by mu (on the right-hand side it
# raises them).
_LEFT_HAND_SIDE = {"velocity_terms", "potential_gradient", "gravity_potential"}


# --------------------------------------------------------------------------------------------
# Printed formulas
# --------------------------------------------------------------------------------------------
def load_printed(path: Path | None = None) -> list[dict[str, Any]]:
    """The ``[[formula]]`` entries of ``reference/printed_formulas.toml``, in file order.

    Raises
    ------
    ValueError
        Listing every entry with a missing key, an unknown kind or paper, or a duplicate id.
    """
    path = path or FORMULAS_PATH
    with open(path, "rb") as fh:
        entries = tomllib.load(fh).get("formula", [])
    problems, seen = [], set()
    required = ("id", "paper", "equation", "quantity", "printed", "expr", "kind", "target", "note")
    for n, e in enumerate(entries):
        name = e.get("id", f"entry {n}")
        missing = [k for k in required if k not in e]
        if missing:
            problems.append(f"{name}: missing {missing}")
        if e.get("kind") not in KINDS:
            problems.append(f"{name}: kind {e.get('kind')!r} not one of {KINDS}")
        if e.get("paper") not in PAPERS:
            problems.append(f"{name}: paper {e.get('paper')!r} not one of {tuple(PAPERS)}")
        if name in seen:
            problems.append(f"{name}: duplicate id")
        seen.add(name)
    if problems:
        raise ValueError(f"{path}: " + "; ".join(problems))
    return entries


# --------------------------------------------------------------------------------------------
# Derived side
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Kinematics:
    """The part of an EquationsOfMotion that consistent_initial_conditions uses."""

    name: str
    n_coordinates: int
    n_constraints: int
    phi: Callable[[np.ndarray], np.ndarray]
    phi_q: Callable[[np.ndarray], np.ndarray]


class _Context:
    """One paper's mechanism: description, derived equations, symbol maps, manifold samples."""

    def __init__(self, spec: PaperSpec):
        self.spec = spec
        self.ps: ParameterSet = load_parameters(spec.mechanism, "seed")
        self.b: MechanismBuilder = mechanisms.builder(self.ps)
        self.eqs: SymbolicEquations = derive(self.b)
        b = self.b
        self.q, self.qd = b.q, b.qd
        self.qdd = sp.Matrix(sp.symbols([f"qdd_{c}" for c in b.coordinate_names], real=True))
        self.names: dict[str, sp.Symbol] = {}
        for i, c in enumerate(b.coordinate_names):
            if not re.fullmatch(r"q\d+", c):
                raise ValueError(f"{b.name}: coordinate name {c!r} is not of the form q<n>")
            k = c[1:]
            self.names[f"q{k}"], self.names[f"qd{k}"], self.names[f"qdd{k}"] = b.q[i], b.qd[i], self.qdd[i]
        self.parameters = {k: getattr(b.p, k) for k in b.values}
        self.names.update(self.parameters)
        # a printed load magnitude that is also a parameter (the drive torque M) is that parameter
        self.extras = {k: sp.Symbol(f"x_{k}", real=True) for k in spec.extras if k not in self.parameters}
        self.names.update(self.extras)
        self.display = {sym: sp.Symbol(name) for name, sym in self.names.items()}
        self.tex_names = {sym: _tex_symbol(name) for name, sym in self.names.items()}
        self._targets: dict[str, sp.Matrix] = {}
        self._samples = None

    # --- parsing and printing ----------------------------------------------------------------
    def parse(self, text: Any) -> sp.Expr:
        """A printed formula (string or number) in the mechanism's symbols."""
        local = dict(self.names)
        local.update({f: getattr(sp, f) for f in ("sin", "cos", "tan", "sqrt", "sign", "Abs", "pi")})
        expr = sp.parse_expr(str(text), local_dict=local)
        stray = expr.free_symbols - set(self.names.values())
        if stray:
            raise ValueError(f"paper {self.spec.paper}: unknown symbols {sorted(map(str, stray))} in {text!r}")
        return expr

    def show(self, expr: sp.Expr, simplify: bool = True) -> str:
        """An expression in the printed symbol names, simplified for display unless told not to."""
        return str((_simplify(expr) if simplify else sp.sympify(expr)).xreplace(self.display))

    def tex(self, expr: sp.Expr) -> str:
        """LaTeX of an expression in the printed symbols (q_1, \\dot{q}_1, l_1, ...), as it stands."""
        return sp.latex(sp.sympify(expr), symbol_names=self.tex_names)

    # --- targets -------------------------------------------------------------------------------
    def target(self, name: str) -> sp.Matrix:
        """The derived quantity called ``name`` (terms joined by ' + ' are summed)."""
        parts = [p.strip() for p in name.split(" + ")]
        if len(parts) > 1:
            total = self.target(parts[0])
            for p in parts[1:]:
                total = total + self.target(p)
            return total
        if name not in self._targets:
            self._targets[name] = sp.Matrix(self._build(name))
        return self._targets[name]

    def _build(self, name: str) -> sp.Matrix:
        b, e, q, qd, qdd = self.b, self.eqs, self.q, self.qd, self.qdd
        m = len(q)
        match = re.fullmatch(r"(\w+)\[([\w, ]+)\]", name)
        base, args = (match.group(1), [a.strip() for a in match.group(2).split(",")]) if match else (name, [])
        springs = sum((expr for _, expr in b.potentials), sp.Integer(0))
        if base == "mass":
            return e.mass
        if match is None and name.startswith("dmass/dq"):
            return e.mass.diff(self.names[name[len("dmass/d"):]])
        if base == "kinetic_gradient":  # dT/dq
            return sp.Matrix([(qd.T * e.mass.diff(qi) * qd)[0] / 2 for qi in q])
        if base == "mass_rate_times_qd":  # (dM/dt) qd
            return sum((e.mass.diff(qk) * dk for qk, dk in zip(q, qd)), sp.zeros(m, m)) * qd
        if base == "velocity_terms":
            return e.velocity_terms
        if base == "inertia_forces":  # 000's Q^qt = -C qd
            return -e.velocity_terms
        if base == "potential_gradient":
            return e.potential_gradient
        if base == "gravity_potential":
            return sp.Matrix([e.potential - springs])
        if base == "spring_forces":
            return -sp.Matrix([springs]).jacobian(q).T
        if base == "phi":
            return e.phi
        if base == "phi_q":
            return e.phi_q
        if base == "phi_dot":
            return e.phi_q * qd
        if base == "phi_ddot":
            return e.phi_q * qdd - e.gamma
        if base == "dphi_q/dq" or name == "dphi_q/dq":
            return sp.Matrix.hstack(*[e.phi_q.diff(qk) for qk in q])
        if base == "null_space_D":
            return self._null_space_rows()
        if base in ("position", "velocity", "acceleration", "relative_position"):
            r, jac = self._location(args[0])
            if base == "position":
                return r
            if base == "relative_position":
                return r - self._location(args[1])[0]
            if base == "velocity":
                return jac * qd
            return jac * qdd + (jac * qd).jacobian(q) * qd
        if base == "torque":
            (load,) = [t for t in b.torque_loads if t.name == args[0]]
            return self.names[self.spec.loads[load.name]] * e.angle_jacobians[load.body.name].T
        if base in ("friction", "resistance"):
            (c,) = [c for c in b.contacts if c.name == args[0]]
            tangent = sp.Matrix(c.tangent)
            dir_q = e.point_jacobians[c.point.name].T * tangent  # generalized direction of +t
            if base == "friction":
                return self.names[self.spec.loads[c.name]] * dir_q
            v_t = (tangent.T * e.point_jacobians[c.point.name] * qd)[0]
            return -c.resistance * sp.sign(v_t) * dir_q
        if base == "input_matrix":
            cols = []
            for load_name, direction in self.spec.inputs:
                torques = [t for t in b.torque_loads if t.name == load_name]
                if direction is None:
                    cols.append(e.angle_jacobians[torques[0].body.name].T)
                else:
                    (load,) = [f for f in b.point_loads if f.name == load_name]
                    cols.append(e.point_jacobians[load.point.name].T * sp.Matrix(direction))
            return sp.Matrix.hstack(*cols)
        raise KeyError(f"paper {self.spec.paper}: unknown target {name!r}")

    def _location(self, name: str) -> tuple[sp.Matrix, sp.Matrix]:
        for pt in self.b.points:  # a printed point name is the first body point of that name
            if pt.name == name or pt.name.endswith(f".{name}"):
                return self.eqs.point_positions[pt.name], self.eqs.point_jacobians[pt.name]
        for body in self.b.bodies:
            if body.name == name:
                r = sp.Matrix([body.x, body.y])
                return r, r.jacobian(self.q)
        raise KeyError(f"paper {self.spec.paper}: no point or body {name!r}")

    def _null_space_rows(self) -> sp.Matrix:
        """D = R^T with R = [E; -Phi_v^-1 Phi_u] (001 eq. 8), the seed's independent coordinates."""
        m = len(self.q)
        ind = list(self.ps.initial.independent)
        dep = [i for i in range(m) if i not in ind]
        phi_q = self.eqs.phi_q
        block = -phi_q.extract(list(range(phi_q.rows)), dep).inv() * phi_q.extract(list(range(phi_q.rows)), ind)
        r = sp.zeros(m, len(ind))
        for k, i in enumerate(ind):
            r[i, k] = 1
        for k, i in enumerate(dep):
            r[i, :] = block[k, :]
        return r.T

    # --- numbers -------------------------------------------------------------------------------
    def kinematics(self, values: Mapping[sp.Symbol, float]) -> _Kinematics:
        phi = sp.lambdify([list(self.q)], self.eqs.phi.xreplace(dict(values)), "numpy")
        phi_q = sp.lambdify([list(self.q)], self.eqs.phi_q.xreplace(dict(values)), "numpy")
        return _Kinematics(
            name=f"errata {self.b.name}",
            n_coordinates=len(self.q),
            n_constraints=self.eqs.phi.rows,
            phi=lambda x: np.asarray(phi(x), dtype=float).reshape(-1),
            phi_q=lambda x: np.asarray(phi_q(x), dtype=float).reshape(self.eqs.phi.rows, len(self.q)),
        )

    def seed_values(self) -> dict[sp.Symbol, float]:
        return {sym: float(self.b.values[k]) for k, sym in self.parameters.items()}

    def samples(self) -> "_Samples":
        if self._samples is None:
            self._samples = _Samples.draw(self)
        return self._samples


@dataclass(frozen=True)
class _Samples:
    """Random states on the constraint manifold, with the randomized parameter values."""

    values: dict[sp.Symbol, float]
    q: np.ndarray    # (S, m)
    qd: np.ndarray   # (S, m)
    qdd: np.ndarray  # (S, m), Phi_q qdd = gamma
    null: np.ndarray  # (S, m, n) orthonormal null-space bases of Phi_q

    @staticmethod
    def draw(ctx: _Context) -> "_Samples":
        rng = np.random.default_rng(RNG_SEED)
        values = {}
        for k, sym in ctx.parameters.items():
            v = float(ctx.b.values[k])
            values[sym] = v * rng.uniform(1 - PARAMETER_SPREAD, 1 + PARAMETER_SPREAD) if v else rng.uniform(*ZERO_PARAMETER_RANGE)
        for k in sorted(ctx.extras):
            values[ctx.extras[k]] = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 2.0))
        kin = ctx.kinematics(values)
        ic = ctx.ps.initial
        ind = list(ic.independent)
        guess = np.array(ic.printed_q, dtype=float)
        guess[ind] = ic.q_independent
        start = consistent_initial_conditions(kin, guess, ind, rng.normal(size=len(ind))).q
        gamma = sp.lambdify([list(ctx.q), list(ctx.qd)], ctx.eqs.gamma.xreplace(values), "numpy")
        offsets = np.linspace(0.0, 2 * np.pi, SAMPLES, endpoint=False) + rng.uniform(0.05, 0.6)
        qs, qds, qdds, nulls = [], [], [], []
        current = start.copy()
        for off in offsets:
            target = start[ind] + off
            steps = max(1, int(np.ceil(np.max(np.abs(target - current[ind])) / CONTINUATION_STEP)))
            begin = current[ind].copy()
            for s in range(1, steps + 1):
                guess = current.copy()
                guess[ind] = begin + (target - begin) * s / steps
                current = consistent_initial_conditions(kin, guess, ind, np.zeros(len(ind))).q
            state = consistent_initial_conditions(kin, current, ind, rng.normal(size=len(ind)))
            jac = kin.phi_q(state.q)
            g = np.asarray(gamma(state.q, state.qd), dtype=float).reshape(-1)
            _, _, vt = np.linalg.svd(jac)
            null = vt[jac.shape[0]:].T
            qdd = np.linalg.lstsq(jac, g, rcond=None)[0] + null @ rng.normal(size=null.shape[1])
            qs.append(state.q), qds.append(state.qd), qdds.append(qdd), nulls.append(null)
        return _Samples(values, np.array(qs), np.array(qds), np.array(qdds), np.array(nulls))

    def evaluate(self, ctx: _Context, exprs: Sequence[sp.Expr]) -> np.ndarray:
        """Values (S, len(exprs)) of expressions at the samples."""
        fn = sp.lambdify([list(ctx.q), list(ctx.qd), list(ctx.qdd)],
                         [sp.sympify(x).xreplace(self.values) for x in exprs], "numpy")
        return np.array([np.broadcast_to(np.asarray(fn(q, qd, qdd), dtype=float), (len(exprs),))
                         for q, qd, qdd in zip(self.q, self.qd, self.qdd)])

    def magnitude(self, ctx: _Context, exprs: Sequence[sp.Expr]) -> np.ndarray:
        """Sum of the absolute values of the terms of each expanded expression, at the samples."""
        return self.evaluate(ctx, [sum((sp.Abs(t) for t in sp.Add.make_args(sp.expand(x))), sp.Integer(0))
                                   for x in exprs])


# --------------------------------------------------------------------------------------------
# Comparison
# --------------------------------------------------------------------------------------------
def _without_signs(expr: sp.Expr) -> tuple[sp.Expr, dict]:
    """expr with every sign(...) replaced by a dummy symbol, and the map back."""
    dummies = {s: sp.Dummy(f"sign{k}") for k, s in enumerate(sorted(expr.atoms(sp.sign), key=sp.default_sort_key))}
    return expr.xreplace(dummies), {d: s for s, d in dummies.items()}


def _trig_canonical(expr: sp.Expr) -> sp.Expr:
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


def _is_zero(expr: sp.Expr) -> bool:
    """Is expr identically zero? (sign(...) factors are treated as independent unknowns.)"""
    expr = sp.sympify(expr)
    if expr == 0:
        return True
    expr, _ = _without_signs(expr)
    numerator, _ = sp.fraction(sp.together(expr))
    return _trig_canonical(numerator) == 0


def _simplify(expr: sp.Expr) -> sp.Expr:
    """A compact form for display: factor, then trigsimp (sign(...) arguments separately)."""
    expr = sp.sympify(expr)
    if expr.is_number:
        return expr
    expr, back = _without_signs(expr)
    out = sp.factor(sp.expand(expr))
    trig = sp.trigsimp(out)
    if not trig.has(sp.pi):  # trigsimp may trade sin/cos sums for sqrt(2) sin(x + pi/4): keep those factored
        out = trig
    return out.xreplace({d: sp.sign(_simplify(s.args[0])) for d, s in back.items()})


def _matrix(ctx: _Context, expr: Any) -> sp.Matrix:
    """A printed scalar, vector (column) or matrix (list of rows) as a sympy Matrix."""
    if isinstance(expr, list) and expr and isinstance(expr[0], list):
        return sp.Matrix([[ctx.parse(x) for x in row] for row in expr])
    if isinstance(expr, list):
        return sp.Matrix([ctx.parse(x) for x in expr])
    return sp.Matrix([ctx.parse(expr)])


def _select(target: sp.Matrix, index: Any) -> sp.Matrix:
    """Entries of target at 1-based index [i], [i, j] or a list of such (as a column)."""
    if index is None:
        return target
    if isinstance(index[0], list):
        return sp.Matrix([_select(target, i)[0] for i in index])
    if len(index) == 1:
        flat = target if target.cols == 1 else target.T
        return sp.Matrix([flat[index[0] - 1]])
    return sp.Matrix([target[index[0] - 1, index[1] - 1]])


def _show_matrix(ctx: _Context, mat: sp.Matrix, simplify: bool = True) -> str:
    def show(x):
        return ctx.show(x, simplify)

    if mat.shape == (1, 1):
        return show(mat[0])
    if mat.cols == 1:
        return "[" + ", ".join(show(x) for x in mat) + "]"
    return "[" + ", ".join("[" + ", ".join(show(x) for x in mat.row(i)) + "]" for i in range(mat.rows)) + "]"


def _tex_symbol(name: str) -> str:
    """LaTeX of a printed symbol name: q1 -> q_{1}, qd1 -> \\dot{q}_{1}, qdd1 -> \\ddot{q}_{1}, l1 -> l_{1}."""
    match = re.fullmatch(r"q(d{0,2})(\d+)", name)
    if match:
        return {"": "q", "d": r"\dot{q}", "dd": r"\ddot{q}"}[match.group(1)] + f"_{{{match.group(2)}}}"
    return sp.latex(sp.Symbol(name))


def _tex_marked(tex: str) -> str:
    return rf"{{\color{{{DIFFERENCE_COLOR}}}{tex}}}"


def _terms(expr: sp.Expr) -> set[sp.Expr]:
    """The terms of expr in the canonical trigonometric basis (see _trig_canonical)."""
    return set(sp.Add.make_args(_trig_canonical(expr)))


def _tex_against(ctx: _Context, derived: sp.Expr, printed: sp.Expr | None) -> str:
    """LaTeX of derived in its display form; where printed differs, the derived terms that printed
    lacks (compared term by term after expansion) are marked in DIFFERENCE_COLOR.
    A derived entry that is one term (a product) is marked whole."""
    shown = _simplify(derived)
    if printed is None or _is_zero(printed - derived):
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
            body = _tex_marked(body)
        parts.append(("- " if negative else ("+ " if k else "")) + body)
    return " ".join(parts)


def _tex_matrix(mat: sp.Matrix, entry: Callable[[int], str]) -> str:
    """A scalar as its entry, a vector or matrix as a bmatrix of the entries (k in row-major order)."""
    if mat.shape == (1, 1):
        return entry(0)
    rows = [" & ".join(entry(i * mat.cols + j) for j in range(mat.cols)) for i in range(mat.rows)]
    return r"\begin{bmatrix}" + r" \\ ".join(rows) + r"\end{bmatrix}"


def _tex_difference(ctx: _Context, printed: sp.Matrix, derived: sp.Matrix) -> str:
    """LaTeX of printed - derived, simplified, entry by entry."""
    delta = printed - derived
    return _tex_matrix(delta, lambda k: ctx.tex(_simplify(delta[k])))


def _label(mat: sp.Matrix, k: int) -> str:
    i, j = divmod(k, mat.cols)
    return f"[{i + 1}]" if mat.cols == 1 else f"[{i + 1},{j + 1}]"


def _agree_numerically(ctx: _Context, printed: Sequence[sp.Expr], derived: Sequence[sp.Expr]) -> list[bool]:
    """Per element: do printed and derived agree at every manifold sample?"""
    smp = ctx.samples()
    diff = smp.evaluate(ctx, [p - d for p, d in zip(printed, derived)])
    scale = smp.magnitude(ctx, list(printed)) + smp.magnitude(ctx, list(derived))
    return list(np.all(np.abs(diff) <= MANIFOLD_RTOL * scale + 1e-300, axis=0))


def _differences(ctx: _Context, printed: sp.Matrix, derived: sp.Matrix) -> list[int]:
    return [k for k in range(len(printed)) if not _is_zero(printed[k] - derived[k])]


def _difference_note(ctx: _Context, printed: sp.Matrix, derived: sp.Matrix, which: Sequence[int]) -> str:
    label = (lambda k: _label(printed, k) + " ") if len(printed) > 1 else (lambda k: "")
    return "; ".join(f"{label(k)}printed - derived = {ctx.show(printed[k] - derived[k])}" for k in which)


def _multiplier(ctx: _Context, delta: sp.Matrix) -> sp.Matrix | None:
    """mu with delta = Phi_q^T mu, if delta is a multiple of one constraint gradient."""
    phi_q = ctx.eqs.phi_q
    for k in range(phi_q.rows):
        row = phi_q.row(k).T
        pivots = [i for i in range(len(row)) if not _is_zero(row[i])]
        if not pivots:
            continue
        c = sp.cancel(_trig_canonical(delta[pivots[0]]) / _trig_canonical(row[pivots[0]]))
        if all(_is_zero(delta[i] - c * row[i]) for i in range(len(row))):
            mu = sp.zeros(phi_q.rows, 1)
            mu[k] = c
            return mu
    return None


def _in_range_of_phi_q_t(ctx: _Context, delta: sp.Matrix, scale_exprs: Sequence[sp.Expr]) -> bool:
    """Is R^T delta = 0 at every sample (R an orthonormal null-space basis of Phi_q)?"""
    smp = ctx.samples()
    values = smp.evaluate(ctx, list(delta))                    # (S, m)
    scale = smp.magnitude(ctx, list(scale_exprs)).max(axis=1)  # (S,)
    projected = np.einsum("smn,sm->sn", smp.null, values)
    return bool(np.all(np.abs(projected) <= MANIFOLD_RTOL * scale[:, None] + 1e-300))


def _range_note(ctx: _Context, delta: sp.Matrix, target: str) -> str:
    mu = _multiplier(ctx, delta)
    sign = "-" if target.split(" + ")[0] in _LEFT_HAND_SIDE else "+"
    if mu is None:
        return ("printed - derived lies in the range of Phi_q^T at every sample: the motion is unchanged, "
                "only the multipliers change")
    return (f"printed - derived = Phi_q^T mu with mu = {_show_matrix(ctx, mu)}: the motion is unchanged, "
            f"the multipliers become lambda {sign} mu (M qdd + C qd + dV/dq + Phi_q^T lambda = Q)")


@dataclass(frozen=True)
class _Judgement:
    verdict: str
    derived: str
    finding: str
    derived_latex: str = ""
    difference_latex: str = ""


def _judge_expression(ctx: _Context, entry: Mapping[str, Any], expr: Any) -> _Judgement:
    printed = _matrix(ctx, expr)
    derived = _select(ctx.target(entry["target"]), entry.get("index"))
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
        return _Judgement(EXACT, _show_matrix(ctx, printed, simplify=False), "",
                          _tex_matrix(printed, lambda k: ctx.tex(printed[k])))
    shown = _show_matrix(ctx, derived)
    tex = (_tex_matrix(derived, lambda k: _tex_against(ctx, derived[k], printed[k])),
           _tex_difference(ctx, printed, derived))
    note = _difference_note(ctx, printed, derived, which)
    agree = _agree_numerically(ctx, [printed[k] for k in which], [derived[k] for k in which])
    if all(agree):
        return _Judgement(EQUIVALENT, shown, note + " (zero at every manifold sample)", *tex)
    if kind == "generalized_force":
        delta = printed - derived
        columns = [delta.col(j) for j in range(delta.cols)]
        if all(_in_range_of_phi_q_t(ctx, col, list(printed.col(j)) + list(derived.col(j)))
               for j, col in enumerate(columns)):
            notes = [_range_note(ctx, col, entry["target"]) for col in columns if any(not _is_zero(x) for x in col)]
            return _Judgement(EQUIVALENT, shown, note + ". " + "; ".join(notes), *tex)
    return _Judgement(WRONG, shown, note, *tex)


def _judge_equation(ctx: _Context, printed: sp.Matrix, derived: sp.Matrix) -> _Judgement:
    p, d = printed[0], derived[0]
    as_printed = ctx.tex(p) + " = 0"
    if _is_zero(p - d):
        return _Judgement(EXACT, ctx.show(p, simplify=False) + " = 0", "", as_printed)
    ratio = sp.cancel(_trig_canonical(p) / _trig_canonical(d))
    state = set(ctx.q) | set(ctx.qd) | set(ctx.qdd)
    if ratio != 0 and not (ratio.free_symbols & state) and _is_zero(p - ratio * d):
        return _Judgement(EXACT, ctx.show(p, simplify=False) + " = 0", f"the printed equation is the derived one times {ctx.show(ratio)}",
                          as_printed)
    shown = ctx.show(d) + " = 0"
    tex = (_tex_against(ctx, d, p) + " = 0", _tex_difference(ctx, printed, derived))
    smp = ctx.samples()
    value = smp.evaluate(ctx, [p])[:, 0]
    scale = smp.magnitude(ctx, [p])[:, 0]
    note = f"printed - derived = {ctx.show(p - d)}"
    if np.all(np.abs(value) <= MANIFOLD_RTOL * scale + 1e-300):
        return _Judgement(EQUIVALENT, shown, note + " (the printed equation holds wherever the derived one does)", *tex)
    return _Judgement(WRONG, shown, note + " (the printed equation fails where the derived one holds)", *tex)


def _judge_potential(ctx: _Context, printed: sp.Matrix, derived: sp.Matrix) -> _Judgement:
    """A potential matters only through its gradient: an additive constant is allowed."""
    p, d = printed[0], derived[0]
    diff = p - d
    grad = sp.Matrix([diff]).jacobian(ctx.q).T
    if all(_is_zero(x) for x in grad):
        extra = "" if _is_zero(diff) else f"the two differ by the constant {ctx.show(diff)}"
        return _Judgement(EXACT, ctx.show(p, simplify=False), extra, ctx.tex(p))
    shown = ctx.show(d)
    tex = (_tex_against(ctx, d, p), _tex_difference(ctx, printed, derived))
    note = f"printed - derived = {ctx.show(diff)}"
    smp = ctx.samples()
    values = smp.evaluate(ctx, [diff])[:, 0]
    scale = (smp.magnitude(ctx, [p]) + smp.magnitude(ctx, [d]))[:, 0]
    if np.ptp(values) > MANIFOLD_RTOL * scale.max():
        return _Judgement(WRONG, shown, note, *tex)
    return _Judgement(EQUIVALENT, shown, note + ", constant on the manifold; for the gradients, "
                      + _range_note(ctx, grad, "potential_gradient"), *tex)


def _judge_sparse(ctx: _Context, entry: Mapping[str, Any]) -> _Judgement:
    target = ctx.target(entry["target"])
    listed, bad, printed = set(), [], {}
    for i, j, text in entry["expr"]:
        p = printed[i, j] = ctx.parse(text)
        if _is_zero(p - target[i - 1, j - 1]):
            listed.add((i, j))
        else:
            bad.append(f"[{i},{j}] printed {ctx.show(p)}, derived {ctx.show(target[i - 1, j - 1])}")
    nonzero = [(i + 1, j + 1) for i in range(target.rows) for j in range(target.cols) if not _is_zero(target[i, j])]
    missing = [f"[{i},{j}] = {ctx.show(target[i - 1, j - 1])} not listed" for i, j in nonzero if (i, j) not in listed]
    shown = "; ".join(f"[{i},{j}] = {ctx.show(target[i - 1, j - 1])}" for i, j in nonzero)
    # an entry the paper does not list is marked whole (compared with 0)
    tex = r",\quad ".join(f"[{i},{j}] = {_tex_against(ctx, target[i - 1, j - 1], printed.get((i, j), sp.S.Zero))}"
                          for i, j in nonzero)
    verdict = EXACT if not bad and not missing else WRONG
    return _Judgement(verdict, shown, "; ".join(bad + missing), tex)


def _decimals(text: Any) -> int | None:
    match = re.fullmatch(r"\s*[-+]?\d*\.(\d+)\s*", str(text))
    if match:
        return len(match.group(1))
    return 0 if re.fullmatch(r"\s*[-+]?\d+\s*", str(text)) else None


def _judge_initial(ctx: _Context, entry: Mapping[str, Any]) -> _Judgement:
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
            tex[-1] = _tex_marked(tex[-1])
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
    ctx = _context(entry["paper"])
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
        note += f" Read as {_show_matrix(ctx, _matrix(ctx, entry['reading']))}: {alt.verdict}."
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
def _context(paper: str) -> _Context:
    return _Context(PAPERS[paper])


@lru_cache(maxsize=None)
def _rows() -> tuple[tuple[str, ...], ...]:
    rows = [check_formula(e) for e in load_printed()]
    return tuple(tuple(r[c] for c in COLUMNS) for r in rows)


# --------------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------------
def errata_table() -> pd.DataFrame:
    """Every printed formula of ``reference/printed_formulas.toml`` with its verdict.

    Returns
    -------
    pandas.DataFrame
        Columns formula, paper, equation, verdict, printed, derived (the derived, i.e. corrected,
        form in the printed symbol names), derived_latex and difference_latex (see
        :func:`check_formula`), note; one row per formula, in file order.
    """
    return pd.DataFrame(list(_rows()), columns=list(COLUMNS))


def _markdown(df: pd.DataFrame) -> str:
    """errata.md: per formula a row with the printed form and the note, a row with the derived form
    and, where they differ, a row with printed - derived, so the forms line up for comparison."""
    rows = []
    for row in df.itertuples(index=False):
        rows.append([row.formula, row.equation, row.verdict, "printed", md_math(row.printed), md_escape(row.note)])
        rows.append(["", "", "", "derived", md_math(row.derived_latex), ""])
        if row.difference_latex:
            rows.append(["", "", "", "printed\u00a0−\u00a0derived", md_math(row.difference_latex), ""])
    counts = df["verdict"].value_counts()
    lines = [
        "# Errata: printed formulas of papers 000 and 001 against the derived equations",
        "",
        "Generated by `study.errata` from `reference/printed_formulas.toml`; do not edit.",
        "",
        "Verdicts: " + ", ".join(f"{v}: {int(counts.get(v, 0))}" for v in VERDICTS) + ".",
        "For each formula: as printed (the paper's OCR text), as derived from the mechanism description (the "
        f"corrected form where the verdict is not exact; terms the printed formula lacks in {DIFFERENCE_COLOR}) "
        "and, where the two differ, printed − derived.",
        "",
        md_table(["formula", "equation", "verdict", "form", "expression", "note"], rows),
    ]
    return "\n".join(lines) + "\n"


def write_errata(out_dir: Path) -> Path:
    """Write ``errata.csv`` and ``errata.md`` into ``out_dir`` (created if needed).

    Returns
    -------
    pathlib.Path
        The path of ``errata.md``; ``errata.csv`` is next to it.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    df = errata_table()
    df.to_csv(out_dir / "errata.csv", index=False, lineterminator="\n")
    md = out_dir / "errata.md"
    md.write_text(_markdown(df), encoding="utf-8")
    return md


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: write the errata table and print one line per formula."""
    parser = argparse.ArgumentParser(prog="study errata", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT_DIR,
                        help=f"output folder for errata.csv and errata.md (default {DEFAULT_OUT_DIR})")
    args = parser.parse_args(argv)
    md = write_errata(args.out)
    for row in errata_table().itertuples(index=False):
        print(f"{row.formula:22s} {row.verdict}")
    print(f"wrote {md} and {md.with_suffix('.csv')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
