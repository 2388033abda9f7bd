"""Code generation, once for both paths: symbolic equations -> common subexpressions -> Python source.

A generated function is a *block*: the names it reads from its inputs and a list of outputs, each an
assignment target and a sympy expression. One common-subexpression elimination per block (``sp.cse``, temporaries
``x_0, x_1, ...``) and one printer (symbols as plain local names, ``math.`` functions) turn a block into lines
(:func:`block_lines`). Before the elimination every expression is prepared (:func:`prepared`: sympy's ``sub_pre``,
then, for a planar system, ``factor_terms``: exactly ``optimizations="basic"``, so the planar modules and tables do
not move; a spatial system skips ``factor_terms``, most of the generation's time: generation about 4x faster, the
code about 1 % longer). A prepared expression is memoized: the reference and the compiled module (and the compiled
module's kernels) repeat the mass, Phi, Phi_q and gamma entries, which are prepared once.

Two targets write blocks from the same :class:`SymbolicSystem`, the common interface of symbolic equations of
either kind (a planar description's, :func:`planar_system`; a spatial one's,
:func:`study.spatial.derive.spatial_system`); only their wrappers differ:

- :func:`reference_source`, the reference path's module (bound by :mod:`study.model.compile`): ``bind(p)``
  returns one plain-Python function per quantity (mass, velocity terms, Phi, Phi_q, gamma, each load, the
  switching functions, the system's kinematic functions: each point's and body's), its parameters bound in the
  closure, each returning a new array (zero entries left out) or a number;
- :func:`compiled_source`, the compiled path's module (loaded by :mod:`study.fast.codegen`): three numba
  kernels (``study.kernels.cache.kernel``) that take the parameter vector ``p`` and fill caller-owned arrays:

  - ``evaluate``: M, Q = applied loads - C(q, qd) qd - dV/dq, Phi, Phi_q, gamma, the contacts' tangent
    Jacobians and biases followed by those of the revolute joints with friction (their rate Jacobians P
    and biases Pdot qd: rows nc.. of Jt and bt), and the power of each applied load, in one block;
  - ``indicators``: switching functions of the discontinuous loads (signs = the load mode);
  - ``kinematics``: Phi, Phi_q and M (for the post-step projection).

Parameters stay symbols (``p_<name>``, in ``PARAMETERS`` order): every parameter variant reuses a module (a spatial
system has none: its numbers are in its expressions).
Both modules begin with :func:`header`, the docstring that marks generated code.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import sympy as sp
from sympy.core.exprtools import factor_terms
from sympy.printing.pycode import PythonCodePrinter
from sympy.simplify.cse_opts import sub_post, sub_pre

from study.model.builder import MechanismBuilder
from study.model.derive import SymbolicEquations

Target = tuple[str, sp.Expr]   # an assignment target in the generated code and its expression
Function = tuple[str, str, sp.Matrix, tuple]   # a reference function: name, arguments, expressions, shape


@dataclass(frozen=True)
class SymbolicSystem:
    """What the generator reads of a mechanism's symbolic equations, planar or spatial (symbols: ``q``, ``qd``,
    the time ``t``, the parameters ``p_<name>`` and the switching loads' ``modes``)."""

    name: str
    q: tuple[sp.Symbol, ...]
    qd: tuple[sp.Symbol, ...]
    parameters: tuple[str, ...]        # sorted parameter names (symbols p_<name>); () for a spatial system
    modes: tuple[sp.Symbol, ...]       # the switching loads' mode symbols (+-1), one per indicator
    mass: sp.Matrix                    # (m, m)
    velocity_terms: sp.Matrix          # (m, 1)  C(q, qd) qd
    potential: sp.Expr
    potential_gradient: sp.Matrix      # (m, 1)
    phi: sp.Matrix                     # (r, 1)
    phi_q: sp.Matrix                   # (r, m)
    gamma: sp.Matrix                   # (r, 1)
    loads: dict[str, sp.Matrix]        # (m, 1) generalized force of every applied load
    indicators: sp.Matrix              # (k, 1) switching functions of the loads
    rates: tuple[tuple[sp.Matrix, sp.Expr], ...]   # (1, m) Jacobian and bias of each friction rate (Jt, bt rows)
    kinematics: tuple[Function, ...]   # the reference module's kinematic functions (points, bodies, guides)
    factored: bool = False             # factor_terms before the CSE (planar: its modules stay as they were)


def planar_system(b: MechanismBuilder, eqs: SymbolicEquations) -> SymbolicSystem:
    """The generator's view of a planar description and its derived equations."""
    m = len(b.q)
    kinematics = []
    for c in b.contacts:
        if c.guide is not None:   # a moving guide's J_t and Jdot_t qd (a fixed guide's come from its point's)
            kinematics += [(f"contact_jac__{c.name}", "q", eqs.contact_jacobians[c.name], (m,)),
                           (f"contact_bias__{c.name}", "q, qd", sp.Matrix([eqs.contact_bias[c.name]]), ())]
    for body in b.bodies:
        kinematics += [(f"angle__{body.name}", "q", sp.Matrix([body.angle]), ()),
                       (f"angle_jac__{body.name}", "q", eqs.angle_jacobians[body.name], (m,)),
                       (f"angle_bias__{body.name}", "q, qd", sp.Matrix([eqs.angle_bias[body.name]]), ())]
    for pt in b.points:
        kinematics += [(f"pos__{pt.name}", "q", eqs.point_positions[pt.name], (2,)),
                       (f"jac__{pt.name}", "q", eqs.point_jacobians[pt.name], (2, m)),
                       (f"bias__{pt.name}", "q, qd", eqs.point_bias[pt.name], (2,))]
    rates = [(eqs.contact_jacobians[c.name], eqs.contact_bias[c.name]) for c in b.contacts]   # J_t, Jdot_t qd
    rates += [(eqs.pin_jacobians[pin.name], eqs.pin_bias[pin.name]) for pin in b.pin_frictions]   # P, Pdot qd
    return SymbolicSystem(
        name=b.name, q=tuple(b.q), qd=tuple(b.qd), parameters=tuple(sorted(vars(b.p))),
        modes=tuple(mode for _, _, mode in b.switches), mass=eqs.mass, velocity_terms=eqs.velocity_terms,
        potential=eqs.potential, potential_gradient=eqs.potential_gradient, phi=eqs.phi, phi_q=eqs.phi_q,
        gamma=eqs.gamma, loads=eqs.loads, indicators=eqs.indicators, rates=tuple(rates), kinematics=tuple(kinematics),
        factored=True)


class _Printer(PythonCodePrinter):
    def _print_Symbol(self, expr):  # symbols are plain local names in the generated code
        return expr.name


_PRINTER = _Printer({"fully_qualified_modules": True})


def header(s: SymbolicSystem, target: str) -> str:
    """The first line of a generated module (what tests/test_sizes.py recognizes as generated code)."""
    return f'"""Generated by study.model.codegen ({target}) for mechanism {s.name!r}. Do not edit."""'


@lru_cache(maxsize=1 << 14)
def prepared(e: sp.Expr, factored: bool) -> sp.Expr:
    """``e`` as ``sp.cse`` prepares it: ``sub_pre``, then ``factor_terms`` when ``factored`` (``"basic"``)."""
    e = sub_pre(e)
    return factor_terms(e) if factored else e


def block_lines(targets: list[Target], indent: str, skip_zeros: bool = False, factored: bool = True) -> list[str]:
    """The common subexpressions of ``targets`` assigned to ``x_0, x_1, ...``, then every target assigned its
    reduced expression (a target whose reduced expression is 0 left out when ``skip_zeros``); the expressions
    prepared by :func:`prepared`, undone by ``sub_post`` after the elimination (``factored``: as
    ``optimizations="basic"``)."""
    replacements, reduced = sp.cse([prepared(e, factored) for _, e in targets], symbols=sp.numbered_symbols("x_"),
                                   optimizations=[(None, sub_post)])
    lines = [f"{indent}{sym} = {_PRINTER.doprint(e)}" for sym, e in replacements]
    return lines + [f"{indent}{name} = {_PRINTER.doprint(e)}" for (name, _), e in zip(targets, reduced)
                    if not (skip_zeros and e == 0)]


def _unpack(s: SymbolicSystem, args: str, indent: str) -> list[str]:
    """Lines naming the entries of the arguments a block reads: q always, qd and mode when in ``args``."""
    names = args.split(", ")
    lines = [f"{indent}{x} = q[{i}]" for i, x in enumerate(s.q)]
    if "qd" in names:
        lines += [f"{indent}{x} = qd[{i}]" for i, x in enumerate(s.qd)]
    if "mode" in names:
        lines += [f"{indent}{m} = float(mode[{i}])" for i, m in enumerate(s.modes)]
    return lines


def _parameters(s: SymbolicSystem, indent: str) -> list[str]:
    return [f"{indent}p_{k} = p[{i}]" for i, k in enumerate(s.parameters)]


def function_name(name: str) -> str:
    """A valid Python identifier for a generated function named ``name`` (points are 'body.point')."""
    return re.sub(r"\W", "_", name)


def _reference_function(s: SymbolicSystem, name: str, args: str, exprs: sp.Matrix, shape: tuple) -> list[str]:
    """One function of the reference module: a new array of ``shape`` (zero entries left out), or a number."""
    flat = list(exprs)
    lines = [f"    def {function_name(name)}({args}):"] + _unpack(s, args, "        ")
    if shape == ():
        return lines + block_lines([("out", flat[0])], "        ", factored=s.factored) + ["        return out"]
    lines.append(f"        out = np.zeros({shape})")
    targets = [(f"out[{', '.join(map(str, idx))}]", e) for idx, e in zip(np.ndindex(*shape), flat)]
    return lines + block_lines(targets, "        ", skip_zeros=True, factored=s.factored) + ["        return out"]


def reference_functions(s: SymbolicSystem) -> list[Function]:
    """Name, arguments, expressions and shape of every function of the reference module."""
    m, r, k = len(s.q), s.phi.shape[0], len(s.modes)
    out = [("mass", "q", s.mass, (m, m)), ("velocity_terms", "q, qd", s.velocity_terms, (m,)),
           ("potential", "q", sp.Matrix([s.potential]), ()),
           ("potential_gradient", "q", s.potential_gradient, (m,)),
           ("phi", "q", s.phi, (r,)), ("phi_q", "q", s.phi_q, (r, m)), ("gamma", "q, qd", s.gamma, (r,))]
    out += [(f"load__{name}", "t, q, qd, mode", expr, (m,)) for name, expr in s.loads.items()]
    out.append(("indicators", "t, q, qd", s.indicators, (k,)))
    return out + list(s.kinematics)


def reference_source(s: SymbolicSystem) -> str:
    """The reference module: ``PARAMETERS`` and ``bind(p) -> dict[name, function]``."""
    functions = reference_functions(s)
    lines = [header(s, "reference"), "import math", "import numpy as np",
             f"PARAMETERS = {list(s.parameters)!r}", "", "def bind(p):"] + _parameters(s, "    ")
    for name, args, exprs, shape in functions:
        lines += _reference_function(s, name, args, exprs, shape)
    lines.append("    return {" + ", ".join(f"{name!r}: {function_name(name)}" for name, *_ in functions) + "}")
    return "\n".join(lines) + "\n"


def _kernel(s: SymbolicSystem, signature: str, args: str, targets: list[Target]) -> list[str]:
    """One kernel of the compiled module: ``targets`` assigned into the caller's arrays (zero entries too)."""
    lines = [f"@kernel({signature})", f"def {signature.lower()}({args}):"]
    if not targets:
        return lines + ["    return"]
    body = block_lines(targets, "    ", factored=s.factored)
    return lines + _unpack(s, args, "    ") + _parameters(s, "    ") + body


def _matrix(name: str, exprs: sp.Matrix) -> list[Target]:
    return [(f"{name}[{i}, {j}]", exprs[i, j]) for i in range(exprs.shape[0]) for j in range(exprs.shape[1])]


def _evaluate_targets(s: SymbolicSystem) -> list[Target]:
    m, r = len(s.q), s.phi.shape[0]
    targets = _matrix("M", s.mass)
    targets += [(f"Q[{i}]", -s.velocity_terms[i] - s.potential_gradient[i]
                 + sum((g[i] for g in s.loads.values()), sp.Integer(0))) for i in range(m)]
    for i in range(r):
        targets += [(f"phi[{i}]", s.phi[i])] + [(f"J[{i}, {j}]", s.phi_q[i, j]) for j in range(m)]
        targets.append((f"gamma[{i}]", s.gamma[i]))
    for k, (jac, bias) in enumerate(s.rates):
        targets += [(f"Jt[{k}, {j}]", jac[0, j]) for j in range(m)] + [(f"bt[{k}]", bias)]
    for k, g in enumerate(s.loads.values()):   # the power of each load, in the reference's work order
        targets.append((f"powers[{k}]", sum((g[j] * s.qd[j] for j in range(m)), sp.Integer(0))))
    return targets


def compiled_source(s: SymbolicSystem) -> str:
    """The compiled module: ``evaluate``, ``indicators`` and ``kinematics`` kernels and their sizes."""
    lines = [header(s, "compiled"), "import math", "from study.kernels.cache import kernel",
             "from study.kernels.signatures import EVALUATE, INDICATORS, KINEMATICS",
             f"PARAMETERS = {list(s.parameters)!r}", f"N_LOAD_INDICATORS = {len(s.modes)}",
             f"N_WORK = {len(s.loads)}", f"WORK_NAMES = {tuple(s.loads)!r}", ""]
    lines += _kernel(s, "EVALUATE", "t, q, qd, mode, p, lp, M, Q, phi, J, gamma, Jt, bt, powers",
                     _evaluate_targets(s)) + [""]
    lines += _kernel(s, "INDICATORS", "t, q, qd, p, lp, out",
                     [(f"out[{k}]", e) for k, e in enumerate(s.indicators)]) + [""]
    targets = [(f"phi[{i}]", e) for i, e in enumerate(s.phi)] + _matrix("J", s.phi_q) + _matrix("M", s.mass)
    return "\n".join(lines + _kernel(s, "KINEMATICS", "q, p, phi, J, M", targets)) + "\n"
