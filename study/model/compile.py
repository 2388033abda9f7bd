"""The reference path's equations of a description: its generated module, cached on disk, bound to parameters.

The module (plain Python with ``math`` scalar functions after common-subexpression elimination, written by
:func:`study.model.codegen.reference_source`) is keyed by a hash of the symbolic description, of this package's
source and of sympy's version (:func:`description_key`, which the compiled module's key includes too), and stored
under the cache folder (``study.cache_folder.cache_dir()``: ``$STUDY_CACHE_DIR``, ``.cache`` in a checkout, or the
user's cache folder)/codegen, so the sympy derivation is paid once.
Parameters stay symbolic in the generated code; every variant reuses it. A system without a description of this
package (a spatial one, :mod:`study.spatial.equations`) is keyed by its symbolic equations (:func:`system_key`) and
bound as :class:`GeneratedEquations`, which keep the system so that the compiled path generates its kernels from the
same equations (:mod:`study.fast.user`).
"""

from __future__ import annotations

import hashlib
import importlib.util
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Callable

import numpy as np
import sympy as sp

from study.cache_folder import cache_dir  # noqa: F401  (the cache root; imported from here by callers)
from study.integrity import ensure_generated
from study.model.builder import MechanismBuilder
from study.model.codegen import SymbolicSystem, planar_system, reference_source
from study.model.derive import derive
from study.model.eom import EquationsOfMotion, FrictionalPin, SlidingContact
from study.sources import source_files, source_hash


def _generator_source() -> str:
    """The source of the derivation and code generation (study/model/*.py) and sympy's version."""
    return source_hash(source_files("model"), extra=sp.__version__)


def description_key(b: MechanismBuilder) -> str:
    """Hash of everything the generated code depends on: the description, the generator's source, sympy."""
    parts = [_generator_source(), b.name, repr(b.coordinate_names), repr(sorted(vars(b.p)))]
    parts += [sp.srepr((x.name, x.x, x.y, x.angle, x.mass, x.inertia)) for x in b.bodies]
    parts += [sp.srepr((x.name, x.x, x.y)) for x in b.points]
    parts += [sp.srepr(c) for c in b.constraints + b.potentials]
    parts += [repr(b.gravity_g)]
    parts += [sp.srepr((x.name, x.point.name, x.components)) for x in b.point_loads]
    parts += [sp.srepr((x.name, x.body.name, x.torque)) for x in b.torque_loads]
    parts += [sp.srepr(x) for x in b.switches]
    parts += [sp.srepr((c.name, c.point.name, c.normal, c.tangent, c.mu_static, c.mu_kinetic, c.resistance,
                        c.guide.name if c.guide else None)) for c in b.contacts]
    parts += [sp.srepr((x.name, x.rows, x.body_a.name if x.body_a else None, x.body_b.name if x.body_b else None,
                        x.mu_static, x.mu_kinetic, x.radius, x.torque)) for x in b.pin_frictions]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


def system_key(s: SymbolicSystem) -> str:
    """Hash of a symbolic system's equations (every field), the generator's source and sympy's version."""
    parts = [_generator_source()] + [sp.srepr(value) if isinstance(value, (sp.Basic, sp.MatrixBase)) else
                                     sp.srepr(tuple(value.items())) if isinstance(value, dict) else sp.srepr(value)
                                     for value in vars(s).values()]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class GeneratedEquations(EquationsOfMotion):
    """Equations bound from the reference module of ``system`` (keyed ``key``, :func:`system_key`): the compiled path
    generates its kernels from the same system. Its numbers are in its expressions: no symbolic parameters."""

    system: SymbolicSystem | None = None
    key: str = ""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.system is None or self.system.parameters:
            raise ValueError(f"GeneratedEquations {self.name!r}: needs a symbolic system without parameters, got "
                             f"{None if self.system is None else self.system.parameters!r}")


def _load_module(path: Path, key: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"study_codegen_{key}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def reference_module(name: str, key: str, source: Callable[[], str]) -> ModuleType:
    """The reference module ``name`` keyed ``key``, from the disk cache or freshly written by ``source()``."""
    path = cache_dir() / "codegen" / f"{name}_{key}.py"
    ensure_generated(path, source)  # checksum-verified; regenerated if it fails
    return _load_module(path, key)


def generated_module(b: MechanismBuilder) -> ModuleType:
    """The generated module for a description, from the disk cache or freshly generated."""
    return reference_module(b.name, description_key(b), lambda: reference_source(planar_system(b, derive(b))))


def bound_forces(f: dict, load_names, live_indicators) -> tuple[Callable, Callable]:
    """``applied_forces(t, q, qd, mode=None)`` (each load's generalized force, by name) and ``forces(t, q, qd,
    mode=None)`` (loads - C qd - dV/dq) of the bound reference functions ``f``; without a mode, the loads take the
    live signs of the switching functions ``live_indicators``."""
    velocity_terms, potential_gradient = f["velocity_terms"], f["potential_gradient"]
    load_functions = {name: f[f"load__{name}"] for name in load_names}

    def applied_forces(t, q, qd, mode=None):
        if mode is None:  # no frozen mode: the live signs of the switching functions
            mode = tuple(1 if g >= 0 else -1 for g in live_indicators(t, q, qd))
        return {name: fn(t, q, qd, mode) for name, fn in load_functions.items()}

    def forces(t, q, qd, mode=None):
        total = -velocity_terms(q, qd) - potential_gradient(q)
        for gen in applied_forces(t, q, qd, mode).values():
            total += gen
        return total

    return applied_forces, forces


def _sliding_contacts(b: MechanismBuilder, f: dict, subs: dict) -> list[SlidingContact]:
    """The sliding contacts with their tangent Jacobians and biases from the generated functions ``f``."""
    contacts = []
    for c in b.contacts:
        if c.guide is None:   # fixed guide: the constant tangent times the point's Jacobian and bias
            tangent = np.array([float(sp.sympify(v).subs(subs)) for v in c.tangent])
            jac, bias = f[f"jac__{c.point.name}"], f[f"bias__{c.point.name}"]
            tangent_jacobian = lambda q, jac=jac, tangent=tangent: tangent @ jac(q)  # noqa: E731
            tangent_bias = lambda q, qd, bias=bias, tangent=tangent: float(tangent @ bias(q, qd))  # noqa: E731
        else:                 # moving guide: the generated J_t and Jdot_t qd of the velocity relative to it
            tangent_jacobian = f[f"contact_jac__{c.name}"]
            tangent_bias = lambda q, qd, bias=f[f"contact_bias__{c.name}"]: float(bias(q, qd))  # noqa: E731
        contacts.append(SlidingContact(
            name=c.name,
            constraint_index=[name for name, _ in b.constraints].index(c.name),
            tangent_jacobian=tangent_jacobian,
            tangent_bias=tangent_bias,
            mu_static=float(c.mu_static.subs(subs)),
            mu_kinetic=float(c.mu_kinetic.subs(subs)),
            resistance=float(c.resistance.subs(subs)),
        ))
    return contacts


def _pin_frictions(b: MechanismBuilder, f: dict, subs: dict) -> list[FrictionalPin]:
    """The revolute joints with friction with their rate Jacobians and biases from the generated functions ``f``."""
    constraint_names = [name for name, _ in b.constraints]
    pins = []
    for pin in b.pin_frictions:
        jacs = [None if body is None else f[f"angle_jac__{body.name}"] for body in (pin.body_a, pin.body_b)]
        biases = [None if body is None else f[f"angle_bias__{body.name}"] for body in (pin.body_a, pin.body_b)]

        def rate_jacobian(q, ja=jacs[0], jb=jacs[1], m=len(b.q)):   # d(omega_a - omega_b)/dqd
            out = np.zeros(m) if ja is None else np.array(ja(q), dtype=float)
            return out if jb is None else out - jb(q)

        def rate_bias(q, qd, ba=biases[0], bb=biases[1]):           # omega_rel' - rate_jacobian(q) @ qdd
            return (0.0 if ba is None else float(ba(q, qd))) - (0.0 if bb is None else float(bb(q, qd)))

        values = {k: float(getattr(pin, k).subs(subs)) for k in ("mu_static", "mu_kinetic", "radius", "torque")}
        pins.append(FrictionalPin(name=pin.name, rows=tuple(constraint_names.index(r) for r in pin.rows),
                                rate_jacobian=rate_jacobian, rate_bias=rate_bias, **values))
    return pins


def compile_description(b: MechanismBuilder, parameter_hash: str = "") -> EquationsOfMotion:
    """Validate a description, bind its generated code to its numeric parameters -> EquationsOfMotion."""
    b.validate()
    module = generated_module(b)
    p = [float(b.values[k]) for k in module.PARAMETERS]
    f = module.bind(p)
    subs = {getattr(b.p, k): float(v) for k, v in b.values.items()}

    live_indicators = f["indicators"]
    applied_forces, forces = bound_forces(f, [ld.name for ld in b.point_loads + b.torque_loads], live_indicators)

    return EquationsOfMotion(
        n_coordinates=len(b.q),
        n_constraints=len(b.constraints),
        mass=f["mass"],
        forces=forces,
        phi=f["phi"],
        phi_q=f["phi_q"],
        gamma=f["gamma"],
        name=b.name,
        coordinate_names=b.coordinate_names,
        constraint_names=tuple(name for name, _ in b.constraints),
        contacts=tuple(_sliding_contacts(b, f, subs)),
        pin_frictions=tuple(_pin_frictions(b, f, subs)),
        potential_energy=f["potential"],
        applied_forces=applied_forces,
        indicators=live_indicators if b.switches else None,
        indicator_names=tuple(name for name, _, _ in b.switches),
        parameter_hash=parameter_hash,
        points={pt.name: f[f"pos__{pt.name}"] for pt in b.points},
        kinematics=f,
    )
