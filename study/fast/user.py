"""Compiled kernels of an EquationsOfMotion without a planar description: generated, or written as plain callables.

A described mechanism's kernels are generated from its description (:mod:`study.model.codegen`). Equations bound from
generated code (:class:`~study.model.compile.GeneratedEquations`, e.g. a spatial description's) get the compiled
module of the same symbolic system (:func:`study.fast.codegen.system_module`), whose ``evaluate`` fills the rate
Jacobians and biases of the system's friction entries (a spatial joint's friction, :mod:`study.spatial.friction`), so
the compiled loop runs them as it runs a planar description's pins; the compiled path has no solver for
rank-deficient rows, so equations with redundant rows (Bricard's) are refused by name. A user's other equations have
no description: their callables (mass, forces, phi, phi_q, gamma) are compiled by numba
as they are and wrapped into kernels of the generated ones' signatures
(:mod:`study.kernels.signatures`), so the same compiled loop runs them. The callables must be in the
subset of Python and NumPy that numba compiles (numbers, arrays and math; closures over plain
numbers, not over objects). Anything else is refused with one message that says why and names
``backend='reference'``, which runs every EquationsOfMotion: there is no silent fallback.

Not compiled (refused by name): sliding contacts and revolute joints with friction, switching loads (``indicators``)
and applied loads whose work is tracked (``applied_forces``); their kernels need the description's
point kinematics.
"""

from __future__ import annotations

from types import ModuleType, SimpleNamespace

from numba import njit
from numba.core.errors import NumbaError

from study.fast.codegen import system_module
from study.kernels.cache import kernel
from study.kernels.signatures import EVALUATE, INDICATORS, KINEMATICS
from study.model.compile import GeneratedEquations
from study.model.eom import EquationsOfMotion, _no_forces


def _evaluate_kernel(mass, forces, phi, phi_q, gamma):
    def evaluate(t, q, qd, mode, p, lp, M, Q, ph, J, gam, Jt, bt, powers):
        M[:, :] = mass(q)
        Q[:] = forces(t, q, qd)
        if ph.size:
            ph[:] = phi(q)
            J[:, :] = phi_q(q)
            gam[:] = gamma(q, qd)
    return evaluate


def _kinematics_kernel(mass, phi, phi_q):
    def kinematics(q, p, ph, J, M):
        ph[:] = phi(q)
        J[:, :] = phi_q(q)
        M[:, :] = mass(q)
    return kinematics


@kernel(INDICATORS)
def _no_indicators(t, q, qd, p, lp, out):
    return


def unsupported(eom: EquationsOfMotion) -> list[str]:
    """What of ``eom`` the compiled kernels of a user's equations do not cover (empty: all of it)."""
    out = []
    if eom.contacts:
        out.append(f"{len(eom.contacts)} sliding contact(s) with friction")
    if eom.pin_frictions:
        out.append(f"{len(eom.pin_frictions)} revolute joint(s) with friction")
    if eom.indicators is not None:
        out.append("switching loads (indicators)")
    if eom.applied_forces is not _no_forces:
        out.append("applied loads with tracked work (applied_forces)")
    return out


def user_kernels(eom: EquationsOfMotion) -> ModuleType | SimpleNamespace:
    """``evaluate``, ``indicators`` and ``kinematics`` of equations without a planar description, with
    ``PARAMETERS``, ``N_LOAD_INDICATORS`` and ``WORK_NAMES`` (none for a user's callables): the generated module of
    :class:`GeneratedEquations`, else the callables compiled now.

    Raises
    ------
    ValueError
        Generated equations with redundant rows; or the equations use what the kernels do not cover, or numba cannot
        compile a callable; the message names it, gives numba's first line, and says ``backend='reference'`` runs them.
    """
    if isinstance(eom, GeneratedEquations):
        return generated_kernels(eom)
    missing = unsupported(eom)
    if missing:
        raise ValueError(f"backend='compiled' cannot compile the EquationsOfMotion {eom.name!r}: it has "
                         f"{', '.join(missing)}, which only a described mechanism's generated kernels cover; "
                         f"use backend='reference'")
    try:
        f = {k: njit(getattr(eom, k)) for k in ("mass", "forces", "phi", "phi_q", "gamma")}
        evaluate = njit(EVALUATE)(_evaluate_kernel(f["mass"], f["forces"], f["phi"], f["phi_q"], f["gamma"]))
        kinematics = njit(KINEMATICS)(_kinematics_kernel(f["mass"], f["phi"], f["phi_q"]))
    except NumbaError as exc:
        first = next((line.strip() for line in str(exc).splitlines() if line.strip()), type(exc).__name__)
        raise ValueError(f"backend='compiled': numba cannot compile the EquationsOfMotion {eom.name!r} ({first}); "
                         "its callables must use numba's subset of Python and NumPy (numbers, arrays, math; "
                         "closures over numbers, not over objects); use backend='reference', which runs any "
                         "callables") from exc
    return SimpleNamespace(evaluate=evaluate, indicators=_no_indicators, kinematics=kinematics, PARAMETERS=[],
                           N_LOAD_INDICATORS=0, WORK_NAMES=())


def generated_kernels(eom: GeneratedEquations) -> ModuleType:
    """The compiled module of the symbolic system ``eom`` was generated from (no symbolic parameters); its friction
    entries (sliding contacts, then pins) must be the system's rates, one each, or the kernels would not fill them."""
    entries = len(eom.contacts) + len(eom.pin_frictions)
    if entries != len(eom.system.rates):
        raise ValueError(f"backend='compiled' cannot run the EquationsOfMotion {eom.name!r}: it has {entries} friction "
                         f"entries (sliding contacts and pins) but its symbolic system {eom.system.name!r} generates "
                         f"{len(eom.system.rates)} rate rows for them; use backend='reference'")
    if eom.redundant_rows:
        raise ValueError(f"backend='compiled' cannot run the EquationsOfMotion {eom.name!r}: {eom.redundant_rows} of "
                         f"its {eom.n_constraints} constraint rows are redundant (rank-deficient Phi_q at every "
                         f"configuration) and the compiled path solves the accelerations with the multipliers, which "
                         f"need independent rows; use backend='reference' with "
                         f"acceleration_solver='augmented_lagrangian'")
    return system_module(eom.system, eom.key)
