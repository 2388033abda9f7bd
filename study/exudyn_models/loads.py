"""The handlers of a description's loads and potentials (springs, dampers' energy): one function per kind.

* A constant law (no state, time or mode dependence after binding the parameter values) is a constant
  LoadTorqueVector / LoadForceVector (no Python in the loop); any other law is a load user function evaluating the
  law (:class:`study.exudyn_models.load_law.Law`) from Exudyn's own kinematics.
* ``configuration='tuned'`` (what Exudyn's documentation recommends for speed; 'python' is the above): a law whose
  inputs are all those of the element carrying it is recorded once as an Exudyn symbolic user function
  (``exudyn.symbolic``, evaluated in C++, no Python per call): a point force reading only its point's x, y, vx, vy
  as ObjectConnectorCartesianSpringDamper from the ground origin, a torque reading only its body's angle and rate
  as ObjectConnectorCoordinateSpringDamper on the rotation coordinate (see building.Model.point_law / angle_law);
  other laws and the friction (it reads a joint reaction, which only Python can) stay Python user functions;
  Newton reuses one Jacobian per step. tests/test_exudyn_tuned.py checks both configurations give the same answers.
* Potentials (springs): user-function torques / forces = minus the gradient of the energy with respect to the
  angle and point-position inputs; their energy is part of the result's potential.
"""

from __future__ import annotations

import sympy as sp

from study.exudyn_models.assembly import Assembly
from study.exudyn_models.building import Model
from study.exudyn_models.load_law import Law
from study.model.joints import GROUND


def add_load(a: Assembly, load) -> None:
    """A load: constant, a symbolic user function ('tuned', where it can be one) or a Python user function."""
    d, model, built = a.d, a.model, a.built
    law = Law(d, a.subs, load.components)
    built.laws[load.name] = law
    m = a.com(load.body) if load.point is None else a.marker(load.body, load.point)
    if law.constant:
        if load.point is None:
            model.torque(m, value=law.values[0])
        else:
            model.force(m, value=tuple(law.values))
        built.evaluation[load.name] = "constant load"
        return
    if built.configuration == "tuned" and symbolic_law(model, law, load.body, load.point, m):
        built.evaluation[load.name] = "symbolic user function"
        return
    model_load = user_function(law, a.readers.reader(law), torque=load.point is None)
    (model.torque if load.point is None else model.force)(m, user=model_load)
    built.evaluation[load.name] = "Python user function"


def add_potential(a: Assembly, pot) -> None:
    """A potential: its energy recorded, and minus its gradient as a load on every body (point) whose angle
    (position) it reads."""
    d, model, built = a.d, a.model, a.built
    built.potentials[pot.name] = Law(d, a.subs, [pot.energy])
    groups: dict[tuple[str, str | None], list] = {}
    for sym in sorted(pot.energy.free_symbols & set(d.inputs), key=str):
        inp = d.inputs[sym]
        if inp.kind not in ("x", "y", "angle"):
            raise ValueError(f"potential {pot.name!r}: energy depends on {inp.kind} of {inp.body!r}; only "
                             f"positions and angles are allowed")
        groups.setdefault((inp.body, inp.point), []).append((inp.kind, sym))
    for (body, point), syms in groups.items():
        if body == GROUND:   # the reaction on a ground point moves nothing (its inputs are read, not loaded)
            continue
        kinds = dict(syms)
        if point is None:
            law = Law(d, a.subs, [-sp.diff(pot.energy, kinds["angle"])])
            m = a.com(body)
        else:
            law = Law(d, a.subs, [-sp.diff(pot.energy, kinds[k]) if k in kinds else sp.Integer(0) for k in ("x", "y")])
            m = a.marker(body, point)
        key = f"{pot.name} on {body}" + (f".{point}" if point else "")
        if built.configuration == "tuned" and symbolic_law(model, law, body, point, m):
            built.evaluation[key] = "symbolic user function"
            continue
        user = user_function(law, a.readers.reader(law), torque=point is None)
        (model.torque if point is None else model.force)(m, user=user)
        built.evaluation[key] = "Python user function"


def symbolic_law(model: Model, law: Law, body: str, point: str | None, marker: int) -> bool:
    """Record ``law`` as an Exudyn symbolic user function if Exudyn has an element whose user function
    sees exactly the law's inputs, and say whether it did.

    * a force at a body point whose law reads only that point's x, y, vx, vy (and t, modes):
      ObjectConnectorCartesianSpringDamper from the ground origin to the point (Model.point_law);
    * a torque on a body whose law reads only that body's angle and rate (and t, modes):
      ObjectConnectorCoordinateSpringDamper on its rotation coordinate (Model.angle_law).

    Any other law (e.g. a spring between two bodies' points) stays a Python load user function.
    """
    if point is not None and all(k.body == body and k.point == point for k in law.kinds):
        f, kinds = law.symbolic(), [k.kind for k in law.kinds]

        def force(t, pos, vel):
            values = {"x": pos[0], "y": pos[1], "vx": vel[0], "vy": vel[1]}
            return f(t, [values[k] for k in kinds])
        model.point_law(marker, force)
        return True
    if point is None and all(k.body == body and k.point is None for k in law.kinds):
        f, kinds = law.symbolic(), [k.kind for k in law.kinds]

        def torque(t, angle, rate):
            return f(t, [angle if k == "angle" else rate for k in kinds])[0]
        model.angle_law(body, torque)
        return True
    return False


def user_function(law: Law, read, torque: bool):
    f = law

    if torque:
        def user(mbs, t, load_vector):
            return [0.0, 0.0, f(t, read(mbs))[0]]
    else:
        def user(mbs, t, load_vector):
            fx, fy = f(t, read(mbs))
            return [fx, fy, 0.0]
    return user
