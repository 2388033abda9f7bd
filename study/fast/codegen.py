"""Generate a numba module for one mechanism description from the same sympy CSE output as the reference.

The reference generator (``study.model.compile``) writes one plain-Python function per quantity with
the parameters bound in a closure. Here the quantities one right-hand-side evaluation needs are put
through one common-subexpression elimination and written as compiled functions (``study.kernels.cache.kernel``) that
take the parameter vector ``p`` (same order as ``PARAMETERS``) and fill caller-owned arrays:

- ``evaluate``: M, Q = applied loads - C(q, qd) qd - dV/dq, Phi, Phi_q, gamma, the contacts' tangent
  Jacobians and biases followed by those of the revolute joints with friction (their rate Jacobians P and
  biases Pdot qd: rows nc.. of Jt and bt), and the power of each applied load;
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

from study.kernels.cache import SOURCE_HASH, compile_lock, generated_dir
from study.integrity import ensure_generated
from study.model.builder import MechanismBuilder
from study.model.compile import description_key
from study.model.derive import SymbolicEquations, derive


class _Printer(PythonCodePrinter):
    def _print_Symbol(self, expr):  # symbols are plain local names in the generated code
        return expr.name


_PRINTER = _Printer({"fully_qualified_modules": True})


def module_key(b: MechanismBuilder) -> str:
    """Hash of the description (loads and switching functions included) and the fast path's sources."""
    text = "\n".join([SOURCE_HASH, description_key(b), repr([c.name for c in b.contacts])])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _cse_block(exprs: list[sp.Expr], indent: str = "    ") -> tuple[list[str], list[str]]:
    """Lines assigning the common subexpressions, and the printed reduced expressions."""
    replacements, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("x_"), optimizations="basic")
    lines = [f"{indent}{sym} = {_PRINTER.doprint(e)}" for sym, e in replacements]
    return lines, [_PRINTER.doprint(e) for e in reduced]


def _unpack(b: MechanismBuilder, params: list[str], with_qd: bool, with_mode: bool = False) -> list[str]:
    lines = [f"    {s} = q[{i}]" for i, s in enumerate(b.q)]
    if with_qd:
        lines += [f"    {s} = qd[{i}]" for i, s in enumerate(b.qd)]
    if with_mode:
        lines += [f"    {m} = float(mode[{i}])" for i, (_, _, m) in enumerate(b.switches)]
    lines += [f"    p_{k} = p[{i}]" for i, k in enumerate(params)]
    return lines


def _evaluate(b, eqs: SymbolicEquations, params) -> list[str]:
    m, r = len(b.q), eqs.phi.shape[0]
    targets: list[tuple[str, sp.Expr]] = []
    for i in range(m):
        for j in range(m):
            targets.append((f"M[{i}, {j}]", eqs.mass[i, j]))
    for i in range(m):
        targets.append((f"Q[{i}]", -eqs.velocity_terms[i] - eqs.potential_gradient[i]
                        + sum((g[i] for g in eqs.loads.values()), sp.Integer(0))))
    for i in range(r):
        targets.append((f"phi[{i}]", eqs.phi[i]))
        for j in range(m):
            targets.append((f"J[{i}, {j}]", eqs.phi_q[i, j]))
        targets.append((f"gamma[{i}]", eqs.gamma[i]))
    for k, c in enumerate(b.contacts):   # J_t and Jdot_t qd (relative to a moving guide), study.model.derive
        for j in range(m):
            targets.append((f"Jt[{k}, {j}]", eqs.contact_jacobians[c.name][0, j]))
        targets.append((f"bt[{k}]", eqs.contact_bias[c.name]))
    for k, pin in enumerate(b.pin_frictions, start=len(b.contacts)):   # P and Pdot qd of omega_a - omega_b
        for j in range(m):
            targets.append((f"Jt[{k}, {j}]", eqs.pin_jacobians[pin.name][0, j]))
        targets.append((f"bt[{k}]", eqs.pin_bias[pin.name]))
    for k, g in enumerate(eqs.loads.values()):   # the power of each load, in the reference's work order
        targets.append((f"powers[{k}]", sum((g[j] * b.qd[j] for j in range(m)), sp.Integer(0))))
    cse_lines, printed = _cse_block([e for _, e in targets])
    lines = ["@kernel(EVALUATE)",
             "def evaluate(t, q, qd, mode, p, lp, M, Q, phi, J, gamma, Jt, bt, powers):"]
    lines += _unpack(b, params, True, True) + cse_lines
    return lines + [f"    {name} = {code}" for (name, _), code in zip(targets, printed)]


def _indicators(b, eqs, params) -> list[str]:
    lines = ["@kernel(INDICATORS)", "def indicators(t, q, qd, p, lp, out):"]
    if not b.switches:
        return lines + ["    return"]
    cse_lines, printed = _cse_block(list(eqs.indicators))
    lines += _unpack(b, params, True) + cse_lines
    return lines + [f"    out[{k}] = {code}" for k, code in enumerate(printed)]


def _kinematics(b, eqs, params) -> list[str]:
    m, r = len(b.q), eqs.phi.shape[0]
    targets = [(f"phi[{i}]", eqs.phi[i]) for i in range(r)]
    targets += [(f"J[{i}, {j}]", eqs.phi_q[i, j]) for i in range(r) for j in range(m)]
    targets += [(f"M[{i}, {j}]", eqs.mass[i, j]) for i in range(m) for j in range(m)]
    cse_lines, printed = _cse_block([e for _, e in targets])
    lines = ["@kernel(KINEMATICS)", "def kinematics(q, p, phi, J, M):"]
    lines += [ln for ln in _unpack(b, params, False)] + cse_lines
    return lines + [f"    {name} = {code}" for (name, _), code in zip(targets, printed)]


def generate_source(b: MechanismBuilder) -> str:
    """Source of the numba module of one description (see the module docstring)."""
    eqs = derive(b)
    params = sorted(vars(b.p))
    header = [
        f'"""Generated by study.fast.codegen for mechanism {b.name!r}. Do not edit."""',
        "import math",
        "from study.kernels.cache import kernel",
        "from study.kernels.signatures import EVALUATE, INDICATORS, KINEMATICS",
        f"PARAMETERS = {params!r}",
        f"N_LOAD_INDICATORS = {len(b.switches)}",
        f"N_WORK = {len(eqs.loads)}",
        f"WORK_NAMES = {tuple(eqs.loads)!r}",
        "",
    ]
    body = _evaluate(b, eqs, params) + [""] + _indicators(b, eqs, params)
    body += [""] + _kinematics(b, eqs, params)
    return "\n".join(header + body) + "\n"


def generated_module(b: MechanismBuilder) -> ModuleType:
    """The numba module of a description, generated on first use and imported from the cache folder."""
    key = module_key(b)
    name = f"study_fast_{b.name}_{key}"
    if name in sys.modules:
        return sys.modules[name]
    folder = generated_dir()
    path = folder / f"{name}.py"
    ensure_generated(path, lambda: generate_source(b))  # checksum-verified; regenerated if it fails
    spec = importlib.util.spec_from_file_location(name, Path(path))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # numba's cache pickles the module name and imports it on reload
    with compile_lock():   # its kernels have declared signatures: they compile (or load) now
        spec.loader.exec_module(module)
    return module
