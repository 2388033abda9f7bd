"""The consistent initial state of a spatial mechanism from each body's position, Euler parameters and angular
velocity.

Positions: each body's Euler parameters must be within ``spatial_euler_norm_start`` (reference/tolerances.toml) of
unit norm (a larger deviation is not rounding but a wrong value, refused by name), and each universal joint's two
axes perpendicular within ``spatial_universal_perpendicular`` (else refused by name); then Newton's method on all
constraint rows (the joints' and the norm rows), with the minimum-norm correction, brings q onto Phi(q) = 0.
Velocities: each body's angular velocity, given in the 'global' or the 'body' frame, sets its Euler-parameter rates
p_dot = 1/2 E^T omega = 1/2 G^T omega' (:mod:`study.spatial.rotations`); the centres' velocities (given ones as the
start) and the Euler-parameter rates of the bodies whose angular velocity is not given (zero as the start) are
corrected by the least change that satisfies Phi_q qd = 0 with the given rates held: in a closed loop (a slider-crank)
the crank's angular velocity is given and the coupler's follows from the joints. If no such change exists (the given
angular velocities violate a joint, e.g. a turn about a revolute joint's crossing axis) the start is refused.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from study.model.eom import EquationsOfMotion
from study.reference_data import tolerance
from study.spatial.description import FRAMES, SpatialDescription, real_vector, spatial_only
from study.spatial.elements import GROUND, SpatialDescriptionError, Universal
from study.spatial.joints import body_axis
from study.spatial.rotations import e_matrix, g_matrix, rotation

NEWTON_MAX_ITER = 20


def euler_rates(p: np.ndarray, omega: np.ndarray, frame: str) -> np.ndarray:
    """p_dot = 1/2 E(p)^T omega (global frame) or 1/2 G(p)^T omega' (body frame)."""
    matrix = e_matrix(list(p)) if frame == "global" else g_matrix(list(p))
    return 0.5 * np.array(matrix.T.tolist(), dtype=float) @ omega


def _start(d: SpatialDescription, positions, orientations, angular_velocities, velocities):
    """q (unassembled), the centres' velocities and the angular velocities, each checked."""
    q, v, w = [], [], []
    for name in d.bodies:
        p = real_vector(orientations.get(name, (1, 0, 0, 0)), 4, f"Euler parameters of body {name!r}")
        off = abs(float(np.linalg.norm(p)) - 1)
        if off > tolerance("spatial_euler_norm_start"):
            raise SpatialDescriptionError(f"Euler parameters of body {name!r} = {p.tolist()} have norm "
                                          f"{np.linalg.norm(p):.6g}, not 1 (| |p| - 1 | = {off:.3g} > "
                                          f"{tolerance('spatial_euler_norm_start'):g}): not a rotation")
        if name not in positions:
            raise SpatialDescriptionError(f"no initial position of body {name!r} (positions: {sorted(positions)})")
        r = real_vector(positions[name], 3, f"position of body {name!r}")
        w.append(real_vector(angular_velocities.get(name, (0, 0, 0)), 3, f"angular velocity of body {name!r}"))
        v.append(real_vector(velocities.get(name, (0, 0, 0)), 3, f"velocity of body {name!r}"))
        q += [*r, *p]
    return np.array(q), v, w


def _check_universal(d: SpatialDescription, q: np.ndarray) -> None:
    """A universal joint's two axes must start perpendicular (within ``spatial_universal_perpendicular``): Newton
    would otherwise turn the bodies until they are, a start the user did not give."""
    names = list(d.bodies)
    for j in d.joints:
        if not isinstance(j, Universal):
            continue
        axes = []
        for body, axis in ((j.body_a, j.axis_a), (j.body_b, j.axis_b)):
            h = body_axis(d, body, axis)
            if body != GROUND:
                k = 7 * names.index(body) + 3
                h = np.array(rotation(list(q[k:k + 4] / np.linalg.norm(q[k:k + 4]))).tolist(), dtype=float) @ h
            axes.append(h)
        cosine = float(axes[0] @ axes[1])
        if abs(cosine) > tolerance("spatial_universal_perpendicular"):
            raise SpatialDescriptionError(
                f"universal joint {j.name!r}: axis {j.axis_a!r} of {j.body_a!r} and axis {j.axis_b!r} of "
                f"{j.body_b!r} are not perpendicular at the start (global {axes[0].round(6).tolist()} and "
                f"{axes[1].round(6).tolist()}, cosine {cosine:.3g}, angle {np.degrees(np.arccos(cosine)):.4g} deg)")


def _newton(eom: EquationsOfMotion, q: np.ndarray) -> np.ndarray:
    tol = tolerance("spatial_newton")
    for _ in range(NEWTON_MAX_ITER):
        phi = eom.phi(q)
        if np.max(np.abs(phi), initial=0.0) <= tol:
            return q
        q = q - np.linalg.lstsq(eom.phi_q(q), phi, rcond=None)[0]
    worst = int(np.argmax(np.abs(eom.phi(q))))
    raise SpatialDescriptionError(f"{eom.name}: the initial positions cannot be assembled: after {NEWTON_MAX_ITER} "
                                  f"Newton steps {eom.constraint_names[worst]} = {eom.phi(q)[worst]:.3g} (tolerance "
                                  f"{tol:g})")


def _check_rank(d: SpatialDescription, eom: EquationsOfMotion, q: np.ndarray) -> None:
    """rank(Phi_q) at the assembled start must be r - the declared redundant rows (``singular_ratio`` of the largest
    singular value decides): fewer is a locking or singular pose, or dependent rows the description does not
    declare; more, rows declared redundant that are not."""
    if not eom.n_constraints:
        return
    s = np.linalg.svd(eom.phi_q(q), compute_uv=False)
    rank = int(np.sum(s >= tolerance("singular_ratio") * s[0]))
    expected = eom.n_constraints - d.redundant
    if rank != expected:
        declared = f"{d.redundant} declared redundant ({d.redundancy_reason})" if d.redundant else "none declared"
        raise SpatialDescriptionError(
            f"{eom.name}: Phi_q at the start has rank {rank} of {eom.n_constraints} rows, {declared}: expected "
            f"{expected}; smallest singular values {np.sort(s)[:d.redundant + 2].tolist()} (relative threshold "
            f"{tolerance('singular_ratio'):g}, singular_ratio): " + ("a locking or singular pose, or dependent rows "
                                                                 "not declared (SpatialDescription.redundant_rows)"
                                                                 if rank < expected else "the declared rows are "
                                                                 "not dependent here"))


def _velocities(eom: EquationsOfMotion, q: np.ndarray, v: list, w: list, frame: str, turning: list[bool]) -> np.ndarray:
    """qd from the centres' velocities v and angular velocities w; the centres' velocities and the rates of the
    bodies not ``turning`` (no angular velocity given) corrected by the least change onto Phi_q qd = 0."""
    qd = np.concatenate([np.concatenate([v_i, euler_rates(q[7 * i + 3:7 * i + 7], w_i, frame)])
                         for i, (v_i, w_i) in enumerate(zip(v, w))])
    jac = eom.phi_q(q)
    free = np.array([7 * i + k for i, given in enumerate(turning) for k in range(3 if given else 7)])
    qd[free] -= np.linalg.lstsq(jac[:, free], jac @ qd, rcond=None)[0]
    residual = jac @ qd
    if not residual.size:
        return qd
    worst = int(np.argmax(np.abs(residual)))
    if abs(residual[worst]) > tolerance("spatial_newton") * max(1.0, float(np.max(np.abs(qd)))):
        raise SpatialDescriptionError(f"{eom.name}: the initial angular velocities violate the joints: the velocity "
                                      f"of {eom.constraint_names[worst]} stays {residual[worst]:.3g} whatever the "
                                      f"centres' velocities")
    return qd


def initial_state(d: SpatialDescription, eom: EquationsOfMotion, positions: Mapping[str, Sequence[float]],
                  orientations: Mapping[str, Sequence[float]] | None = None,
                  angular_velocities: Mapping[str, Sequence[float]] | None = None, frame: str = "global",
                  velocities: Mapping[str, Sequence[float]] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(q0, qd0) on Phi = 0 and Phi_q qd = 0, by body name: centres, Euler parameters (default: no rotation),
    angular velocities in ``frame`` ('global' or 'body'; a body left out: the least rotation the joints allow, zero
    when they allow it) and centres' velocities (default zero, corrected onto the joints)."""
    d = spatial_only(d)
    if frame not in FRAMES:
        raise SpatialDescriptionError(f"frame = {frame!r} of the angular velocities must be one of {FRAMES}")
    given = {"positions": positions, "orientations": orientations or {}, "angular_velocities": angular_velocities or {},
             "velocities": velocities or {}}
    for what, mapping in given.items():
        unknown = sorted(set(mapping) - set(d.bodies))
        if unknown:
            raise SpatialDescriptionError(f"{what} name bodies {unknown} that {d.name!r} does not have "
                                          f"(bodies: {sorted(d.bodies)})")
    q, v, w = _start(d, positions, given["orientations"], given["angular_velocities"], given["velocities"])
    _check_universal(d, q)
    q = _newton(eom, q)
    _check_rank(d, eom, q)
    return q, _velocities(eom, q, v, w, frame, [name in given["angular_velocities"] for name in d.bodies])
