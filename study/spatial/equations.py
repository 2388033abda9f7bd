"""A spatial description's symbolic equations as the solver's :class:`~study.model.eom.EquationsOfMotion`.

The matrices of :func:`study.spatial.derive.derive_spatial` go through the one code generator of both backends
(:mod:`study.model.codegen`, by :func:`study.spatial.derive.spatial_system`): the reference module (cached on disk
under the system's key, :func:`study.model.compile.system_key`) is bound here, so the reference path
(``study.simulate``) runs a spatial mechanism as it runs any equations: the same stabilizations, integrators and
acceleration solvers act on the joint rows and on the Euler-parameter norm rows alike, and the joints with friction
are the planar pins' :class:`~study.model.eom.FrictionalPin` (:mod:`study.spatial.friction`). The result is a
:class:`~study.model.compile.GeneratedEquations`, which keeps the system: ``backend='compiled'`` generates its kernels
from the same equations (:mod:`study.fast.user`).
"""

from __future__ import annotations

from study.model.codegen import reference_source
from study.model.compile import GeneratedEquations, bound_forces, reference_module, system_key
from study.spatial.derive import derive_spatial, spatial_system
from study.spatial.description import SpatialDescription, spatial_only
from study.spatial.friction import joint_pins


#: (symbolic equations, system, its key) by the content they are derived from: derived once per process
_DERIVED: dict[str, tuple] = {}


def _derived(d: SpatialDescription) -> tuple:
    """The symbolic equations of ``d``, its system and the system's key, derived on the first call for its content
    (the declared redundancy does not enter them; a description changed since is derived anew)."""
    content = spatial_only(d).fingerprint(redundancy=False)
    if content not in _DERIVED:
        s = derive_spatial(d)
        system = spatial_system(d.name, s)
        _DERIVED[content] = (s, system, system_key(system))
    return _DERIVED[content]


def spatial_equations(d: SpatialDescription) -> GeneratedEquations:
    """The EquationsOfMotion of a spatial description (a planar one is refused by name)."""
    s, system, key = _derived(d)
    f = reference_module(d.name, key, lambda: reference_source(system)).bind([])
    applied_forces, forces = bound_forces(f, tuple(s.loads), f["indicators"])
    return GeneratedEquations(
        n_coordinates=len(s.q), n_constraints=s.phi.shape[0], mass=f["mass"], forces=forces, phi=f["phi"],
        phi_q=f["phi_q"], gamma=f["gamma"], name=d.name, coordinate_names=s.coordinate_names,
        constraint_names=s.constraint_names, potential_energy=f["potential"], applied_forces=applied_forces,
        points={name: f[f"pos__{name}"] for name in s.points}, kinematics=f, redundant_rows=d.redundant,
        pin_frictions=joint_pins(d, s.constraint_names, f), system=system, key=key)
