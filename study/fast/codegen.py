"""Generate a numba module for one mechanism description from the same sympy CSE output as the reference.

The reference generator (``study.model.compile``) writes one plain-Python function per quantity with
the parameters bound in a closure. Here the quantities one right-hand-side evaluation needs are put
through one common-subexpression elimination and written as ``@njit(cache=True)`` functions that
take the parameter vector ``p`` (same order as ``PARAMETERS``) and fill caller-owned arrays:

- ``evaluate``: M, Q = applied loads - C(q, qd) qd - dV/dq, Phi, Phi_q, gamma, the contacts' tangent
  Jacobians and biases, and the power of each applied load;
- ``indicators``: switching functions of the discontinuous loads (signs = the load mode);
- ``kinematics``: Phi, Phi_q and M (for the post-step projection).

The module is stored in ``generated_dir()`` under a key of the description and the compiled load
kinds (numeric load values are an argument, ``lp``), written atomically, and imported by name so
numba's cache can find it again in the next process.
"""

from __future__ import annotations

import hashlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from study.fast.cache import SOURCE_HASH, generated_dir
from study.fast.loads import PointSpec, TorqueSpec
from study.integrity import ensure_generated
from study.model.builder import MechanismBuilder
from study.model.compile import description_key
from study.model.derive import SymbolicEquations, derive


class _Printer(PythonCodePrinter):
    def _print_Symbol(self, expr):  # symbols are plain local names in the generated code
        return expr.name


_PRINTER = _Printer({"fully_qualified_modules": True})


def module_key(b: MechanismBuilder, torques: tuple[TorqueSpec, ...], points: tuple[PointSpec, ...]) -> str:
    """Hash of the description, the compiled load layout and the fast path's sources."""
    layout = repr([(t.name, t.body) for t in torques] + [(pt.name, pt.point, pt.kind) for pt in points])
    text = "\n".join([SOURCE_HASH, description_key(b), layout, repr([c.name for c in b.contacts])])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _cse_block(exprs: list[sp.Expr], indent: str = "    ") -> tuple[list[str], list[str]]:
    """Lines assigning the common subexpressions, and the printed reduced expressions."""
    replacements, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("x_"), optimizations="basic")
    lines = [f"{indent}{sym} = {_PRINTER.doprint(e)}" for sym, e in replacements]
    return lines, [_PRINTER.doprint(e) for e in reduced]


def _unpack(b: MechanismBuilder, params: list[str], with_qd: bool) -> list[str]:
    lines = [f"    {s} = q[{i}]" for i, s in enumerate(b.q)]
    if with_qd:
        lines += [f"    {s} = qd[{i}]" for i, s in enumerate(b.qd)]
    lines += [f"    p_{k} = p[{i}]" for i, k in enumerate(params)]
    return lines


def _evaluate(b, eqs: SymbolicEquations, torques, points, params) -> list[str]:
    m, r = len(b.q), eqs.phi.shape[0]
    targets: list[tuple[str, sp.Expr]] = []
    for i in range(m):
        for j in range(m):
            targets.append((f"M[{i}, {j}]", eqs.mass[i, j]))
    for i in range(m):
        targets.append((f"Q[{i}]", -eqs.velocity_terms[i] - eqs.potential_gradient[i]))
    for i in range(r):
        targets.append((f"phi[{i}]", eqs.phi[i]))
        for j in range(m):
            targets.append((f"J[{i}, {j}]", eqs.phi_q[i, j]))
        targets.append((f"gamma[{i}]", eqs.gamma[i]))
    for k, c in enumerate(b.contacts):
        jac, bias = eqs.point_jacobians[c.point.name], eqs.point_bias[c.point.name]
        for j in range(m):
            targets.append((f"Jt[{k}, {j}]", c.tangent[0] * jac[0, j] + c.tangent[1] * jac[1, j]))
        targets.append((f"bt[{k}]", c.tangent[0] * bias[0] + c.tangent[1] * bias[1]))
    temps: list[tuple[str, sp.Expr]] = []
    for k, t in enumerate(torques):
        ja = eqs.angle_jacobians[t.body]
        temps += [(f"ja{k}_{j}", ja[0, j]) for j in range(m)]
    for k, pt in enumerate(points):
        pos, jac = eqs.point_positions[pt.point], eqs.point_jacobians[pt.point]
        temps += [(f"rx{k}", pos[0])] + [(f"jx{k}_{j}", jac[0, j]) for j in range(m)]
        temps += [(f"jy{k}_{j}", jac[1, j]) for j in range(m)]
    cse_lines, printed = _cse_block([e for _, e in targets + temps])
    lines = ["@njit(EVALUATE, cache=True)",
             "def evaluate(t, q, qd, mode, p, lp, M, Q, phi, J, gamma, Jt, bt, powers):"]
    lines += _unpack(b, params, True) + cse_lines
    lines += [f"    {name} = {code}" for (name, _), code in zip(targets, printed[:len(targets)])]
    lines += [f"    {name} = {code}" for (name, _), code in zip(temps, printed[len(targets):])]
    offset, mode_offset = 0, 0
    for k, t in enumerate(torques):  # tau = c0 + c1 * rate, generalized force ja * tau
        lines.append(f"    rate = " + " + ".join(f"ja{k}_{j} * qd[{j}]" for j in range(m)))
        lines.append(f"    tau = lp[{offset}] + lp[{offset + 1}] * rate")
        lines += [f"    Q[{j}] += ja{k}_{j} * tau" for j in range(m)]
        lines.append(f"    powers[{len(points) + k}] = tau * rate")  # works: point loads first, as the reference
        offset += 2
    for k, pt in enumerate(points):
        w = k
        lines.append(f"    vx = " + " + ".join(f"jx{k}_{j} * qd[{j}]" for j in range(m)))
        if pt.kind == "cutting_smooth":
            args = ", ".join(f"lp[{offset + i}]" for i in range(5))
            lines.append(f"    fx = cutting_smooth(rx{k}, vx, {args})")
        else:
            lines.append(f"    fx = cutting_on_off(mode[{mode_offset}], mode[{mode_offset + 1}], "
                         f"mode[{mode_offset + 2}], lp[{offset}])")
            mode_offset += pt.n_indicators
        lines += [f"    Q[{j}] += jx{k}_{j} * fx" for j in range(m)]  # cutting force is along x only
        lines.append(f"    powers[{w}] = fx * vx")
        offset += len(pt.values)
    return lines


def _indicators(b, eqs, torques, points, params) -> list[str]:
    m = len(b.q)
    lines = ["@njit(INDICATORS, cache=True)", "def indicators(t, q, qd, p, lp, out):"]
    exprs, plan = [], []
    offset, slot = 2 * len(torques), 0  # lp holds the torques' (c0, c1) first
    for k, pt in enumerate(points):
        if pt.kind == "cutting_on_off":
            pos, jac = eqs.point_positions[pt.point], eqs.point_jacobians[pt.point]
            exprs += [pos[0]] + [jac[0, j] for j in range(m)]
            plan.append((len(exprs) - m - 1, offset, slot))
            slot += pt.n_indicators
        offset += len(pt.values)
    if not exprs:
        return lines + ["    return"]
    cse_lines, printed = _cse_block(exprs)
    lines += _unpack(b, params, True) + cse_lines
    for start, off, s in plan:  # (v_D, x_D - x_min, x_max - x_D), as CuttingLaw.indicators
        lines.append(f"    x = {printed[start]}")
        lines.append("    vx = " + " + ".join(f"({printed[start + 1 + j]}) * qd[{j}]" for j in range(m)))
        lines += [f"    out[{s}] = vx", f"    out[{s + 1}] = x - lp[{off + 1}]", f"    out[{s + 2}] = lp[{off + 2}] - x"]
    return lines


def _kinematics(b, eqs, params) -> list[str]:
    m, r = len(b.q), eqs.phi.shape[0]
    targets = [(f"phi[{i}]", eqs.phi[i]) for i in range(r)]
    targets += [(f"J[{i}, {j}]", eqs.phi_q[i, j]) for i in range(r) for j in range(m)]
    targets += [(f"M[{i}, {j}]", eqs.mass[i, j]) for i in range(m) for j in range(m)]
    cse_lines, printed = _cse_block([e for _, e in targets])
    lines = ["@njit(KINEMATICS, cache=True)", "def kinematics(q, p, phi, J, M):"]
    lines += [ln for ln in _unpack(b, params, False)] + cse_lines
    return lines + [f"    {name} = {code}" for (name, _), code in zip(targets, printed)]


def generate_source(b: MechanismBuilder, torques, points) -> str:
    """Source of the numba module of one description (see the module docstring)."""
    eqs = derive(b)
    params = sorted(vars(b.p))
    header = [
        f'"""Generated by study.fast.codegen for mechanism {b.name!r}. Do not edit."""',
        "import math",
        "from numba import njit",
        "from study.fast.loads import cutting_on_off, cutting_smooth",
        "from study.fast.signatures import EVALUATE, INDICATORS, KINEMATICS",
        f"PARAMETERS = {params!r}",
        f"N_LOAD_INDICATORS = {sum(pt.n_indicators for pt in points)}",
        f"N_WORK = {len(torques) + len(points)}",
        "",
    ]
    body = _evaluate(b, eqs, torques, points, params) + [""] + _indicators(b, eqs, torques, points, params)
    body += [""] + _kinematics(b, eqs, params)
    return "\n".join(header + body) + "\n"


def generated_module(b: MechanismBuilder, torques, points) -> ModuleType:
    """The numba module of a description, generated on first use and imported from the cache folder."""
    key = module_key(b, torques, points)
    name = f"study_fast_{b.name}_{key}"
    if name in sys.modules:
        return sys.modules[name]
    folder = generated_dir()
    path = folder / f"{name}.py"
    ensure_generated(path, lambda: generate_source(b, torques, points))  # checksum-verified (issue 14)
    spec = importlib.util.spec_from_file_location(name, Path(path))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # numba's cache pickles the module name and imports it on reload
    spec.loader.exec_module(module)
    return module
