"""The derived side of the errata: one paper's mechanism, its derived equations and every target.

A target is a derived quantity a printed formula claims to be (``target = "mass"``,
``"position[B]"``, ``"friction[guide]"``, ...). Each base name is one small function of the
derived equations in :data:`TARGETS`; ``a + b`` sums targets.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np
import sympy as sp

from study import mechanisms
from study.errata.algebra import simplify
from study.errata.latex import tex_symbol
from study.errata.printed import PaperSpec
from study.model.builder import MechanismBuilder
from study.model.derive import SymbolicEquations, derive
from study.params import ParameterSet, load_parameters


@dataclass(frozen=True)
class Kinematics:
    """The part of an EquationsOfMotion that consistent_initial_conditions uses."""

    name: str
    n_coordinates: int
    n_constraints: int
    phi: Callable[[np.ndarray], np.ndarray]
    phi_q: Callable[[np.ndarray], np.ndarray]


class PaperContext:
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
        self.tex_names = {sym: tex_symbol(name) for name, sym in self.names.items()}
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

    def show(self, expr: sp.Expr, simplified: bool = True) -> str:
        """An expression in the printed symbol names, simplified for display unless told not to."""
        return str((simplify(expr) if simplified else sp.sympify(expr)).xreplace(self.display))

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
        if name.startswith("dmass/dq"):  # dM/dq<k>
            return self.eqs.mass.diff(self.names[name[len("dmass/d"):]])
        match = re.fullmatch(r"([\w/]+)\[([\w, ]+)\]", name)
        base, args = (match.group(1), [a.strip() for a in match.group(2).split(",")]) if match else (name, [])
        if base not in TARGETS:
            raise KeyError(f"paper {self.spec.paper}: unknown target {name!r}")
        return TARGETS[base](self, *args)

    def location(self, name: str) -> tuple[sp.Matrix, sp.Matrix]:
        """Position and its Jacobian of a printed point (the first body point of that name) or body."""
        for pt in self.b.points:
            if pt.name == name or pt.name.endswith(f".{name}"):
                return self.eqs.point_positions[pt.name], self.eqs.point_jacobians[pt.name]
        for body in self.b.bodies:
            if body.name == name:
                r = sp.Matrix([body.x, body.y])
                return r, r.jacobian(self.q)
        raise KeyError(f"paper {self.spec.paper}: no point or body {name!r}")

    def springs(self) -> sp.Expr:
        return sum((expr for _, expr in self.b.potentials), sp.Integer(0))

    # --- numbers -------------------------------------------------------------------------------
    def kinematics(self, values: Mapping[sp.Symbol, float]) -> Kinematics:
        phi = sp.lambdify([list(self.q)], self.eqs.phi.xreplace(dict(values)), "numpy")
        phi_q = sp.lambdify([list(self.q)], self.eqs.phi_q.xreplace(dict(values)), "numpy")
        return Kinematics(
            name=f"errata {self.b.name}",
            n_coordinates=len(self.q),
            n_constraints=self.eqs.phi.rows,
            phi=lambda x: np.asarray(phi(x), dtype=float).reshape(-1),
            phi_q=lambda x: np.asarray(phi_q(x), dtype=float).reshape(self.eqs.phi.rows, len(self.q)),
        )

    def seed_values(self) -> dict[sp.Symbol, float]:
        return {sym: float(self.b.values[k]) for k, sym in self.parameters.items()}

    def samples(self):
        """The manifold samples (:class:`study.errata.samples.Samples`), drawn once."""
        from study.errata.samples import Samples

        if self._samples is None:
            self._samples = Samples.draw(self)
        return self._samples


# --- the targets: base name -> function(ctx, *args) ---------------------------------------------
def _kinetic_gradient(ctx: PaperContext) -> sp.Matrix:  # dT/dq
    return sp.Matrix([(ctx.qd.T * ctx.eqs.mass.diff(qi) * ctx.qd)[0] / 2 for qi in ctx.q])


def _mass_rate_times_qd(ctx: PaperContext) -> sp.Matrix:  # (dM/dt) qd
    m = len(ctx.q)
    return sum((ctx.eqs.mass.diff(qk) * dk for qk, dk in zip(ctx.q, ctx.qd)), sp.zeros(m, m)) * ctx.qd


def _acceleration(ctx: PaperContext, where: str) -> sp.Matrix:
    _, jac = ctx.location(where)
    return jac * ctx.qdd + (jac * ctx.qd).jacobian(ctx.q) * ctx.qd


def _torque(ctx: PaperContext, name: str) -> sp.Matrix:
    (load,) = [t for t in ctx.b.torque_loads if t.name == name]
    return ctx.names[ctx.spec.loads[load.name]] * ctx.eqs.angle_jacobians[load.body.name].T


def _contact_direction(ctx: PaperContext, name: str):
    """(contact, generalized direction of its +tangent, tangent)."""
    (c,) = [c for c in ctx.b.contacts if c.name == name]
    tangent = sp.Matrix(c.tangent)
    return c, ctx.eqs.point_jacobians[c.point.name].T * tangent, tangent


def _friction(ctx: PaperContext, name: str) -> sp.Matrix:
    c, direction, _ = _contact_direction(ctx, name)
    return ctx.names[ctx.spec.loads[c.name]] * direction


def _resistance(ctx: PaperContext, name: str) -> sp.Matrix:
    c, direction, tangent = _contact_direction(ctx, name)
    v_t = (tangent.T * ctx.eqs.point_jacobians[c.point.name] * ctx.qd)[0]
    return -c.resistance * sp.sign(v_t) * direction


def _input_matrix(ctx: PaperContext) -> sp.Matrix:
    cols = []
    for load_name, direction in ctx.spec.inputs:
        if direction is None:
            (torque,) = [t for t in ctx.b.torque_loads if t.name == load_name]
            cols.append(ctx.eqs.angle_jacobians[torque.body.name].T)
        else:
            (load,) = [f for f in ctx.b.point_loads if f.name == load_name]
            cols.append(ctx.eqs.point_jacobians[load.point.name].T * sp.Matrix(direction))
    return sp.Matrix.hstack(*cols)


def _null_space_rows(ctx: PaperContext) -> sp.Matrix:
    """D = R^T with R = [E; -Phi_v^-1 Phi_u] (001 eq. 8), the seed's independent coordinates."""
    m = len(ctx.q)
    ind = list(ctx.ps.initial.independent)
    dep = [i for i in range(m) if i not in ind]
    phi_q = ctx.eqs.phi_q
    rows = list(range(phi_q.rows))
    block = -phi_q.extract(rows, dep).inv() * phi_q.extract(rows, ind)
    r = sp.zeros(m, len(ind))
    for k, i in enumerate(ind):
        r[i, k] = 1
    for k, i in enumerate(dep):
        r[i, :] = block[k, :]
    return r.T


TARGETS: dict[str, Callable[..., sp.Matrix]] = {
    "mass": lambda ctx: ctx.eqs.mass,
    "kinetic_gradient": _kinetic_gradient,
    "mass_rate_times_qd": _mass_rate_times_qd,
    "velocity_terms": lambda ctx: ctx.eqs.velocity_terms,
    "inertia_forces": lambda ctx: -ctx.eqs.velocity_terms,   # 000's Q^qt = -C qd
    "potential_gradient": lambda ctx: ctx.eqs.potential_gradient,
    "gravity_potential": lambda ctx: sp.Matrix([ctx.eqs.potential - ctx.springs()]),
    "spring_forces": lambda ctx: -sp.Matrix([ctx.springs()]).jacobian(ctx.q).T,
    "phi": lambda ctx: ctx.eqs.phi,
    "phi_q": lambda ctx: ctx.eqs.phi_q,
    "phi_dot": lambda ctx: ctx.eqs.phi_q * ctx.qd,
    "phi_ddot": lambda ctx: ctx.eqs.phi_q * ctx.qdd - ctx.eqs.gamma,
    "dphi_q/dq": lambda ctx: sp.Matrix.hstack(*[ctx.eqs.phi_q.diff(qk) for qk in ctx.q]),
    "null_space_D": _null_space_rows,
    "position": lambda ctx, where: ctx.location(where)[0],
    "relative_position": lambda ctx, a, b: ctx.location(a)[0] - ctx.location(b)[0],
    "velocity": lambda ctx, where: ctx.location(where)[1] * ctx.qd,
    "acceleration": _acceleration,
    "torque": _torque,
    "friction": _friction,
    "resistance": _resistance,
    "input_matrix": _input_matrix,
}
