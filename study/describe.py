"""A mechanism's joint-level description as text: what ``python -m study describe`` prints.

Everything printed is read from the description and the parameter file (nothing is typed per
mechanism): coordinates, parameters with units, bodies with their points, joints (tree or cut in
the relative coordinates, with their constraint rows and contact data), loads with their laws in
readable names, switching functions, the file's variants, and the consistent initial state.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from study import mechanisms
from study.model import Mechanism
from study.model.coordinates import joint_rows, poses
from study.model.joints import Description, Distance, Prismatic
from study.params import ParameterSet, available_variants, load_parameters


def _readable(d: Description):
    """``expr -> str`` with parameters by their names and inputs as x(body.point), angle(body), ..."""
    names = {sym: sp.Symbol(name) for name, sym in vars(d.p).items()}
    for sym, inp in d.inputs.items():
        where = inp.body if inp.point is None else f"{inp.body}.{inp.point}"
        names[sym] = sp.Symbol(f"{inp.kind}({where})")
    names.update({m: sp.Symbol(f"mode[{name}]") for name, _, m in d.switches})
    names.update({q: sp.Symbol(c) for q, c in zip(d.q, d.coordinate_names)})
    return lambda e: sp.sstr(sp.sympify(e).xreplace(names))


def _point(ref: tuple[str, str]) -> str:
    return f"{ref[0]}.{ref[1]}"


def describe_text(mechanism: str | Mechanism, variant: str = "seed") -> str:
    """A mechanism's description as a plain-text page: a study mechanism by name (variant ``variant``), or a
    :class:`study.Mechanism` (its own parameter set)."""
    mech = mechanisms.named_mechanism(mechanism, variant) if isinstance(mechanism, str) else mechanism
    ps, d = mech.parameters, mech.description
    name, variant, folder = ps.mechanism, ps.variant, ps.path.parent
    show = _readable(d)
    lines = [f"{name}: {d.label}", f"parameters: {ps.path} (variant {variant}: {ps.variant_note or 'no note'})", ""]
    unit = f" [{mechanisms.coordinate_unit(name)}]" if isinstance(mechanism, str) else ""
    lines.append(f"relative coordinates q: {', '.join(d.coordinate_names)}{unit}")
    lines += ["", "parameters:"]
    lines += [f"  {k} = {_number(ps, k)}" for k in d.values]
    lines += ["", "bodies (points in the body's centre-of-mass frame):"]
    for b in d.bodies.values():
        points = ", ".join(f"{p} ({show(x)}, {show(y)})" for p, (x, y) in b.points.items())
        lines.append(f"  {b.name}: mass {show(b.mass)}, inertia {show(b.inertia)}, angle {show(b.angle)}; {points}")
    if d.ground_points:
        lines.append("  ground points: " + ", ".join(f"{p} ({show(x)}, {show(y)})" for p, (x, y) in d.ground_points.items()))
    lines += ["", "joints (relative coordinates: tree joints place the bodies, cut joints give the constraint rows):"]
    _, _, placed, cut = poses(d, "relative")
    cut_names = {j.name for j in cut}
    for j in d.joints:
        role = "cut, rows " + ", ".join(r for r, _ in joint_rows(d, placed, j)) if j.name in cut_names else "tree"
        if isinstance(j, Prismatic):
            text = (f"  {j.name}: prismatic, {_point(j.slider)} slides on {_point(j.guide)} along ({show(j.axis[0])}, "
                    f"{show(j.axis[1])})" + (f" by the travel {show(j.travel)}" if j.travel is not None else "")
                    + f" [{role}]")
            if j.friction is not None:
                f = j.friction
                text += (f"; Coulomb contact mu_s = {show(f.mu_static)}, mu_k = {show(f.mu_kinetic)}, "
                         f"resistance {show(f.resistance)}")
        elif isinstance(j, Distance):
            text = f"  {j.name}: distance {show(j.length)} between {_point(j.a)} and {_point(j.b)} [{role}]"
        else:
            text = f"  {j.name}: revolute, {_point(j.a)} = {_point(j.b)} [{role}]"
        lines.append(text)
    lines += ["", "loads:"]
    if d.gravity_g is not None:
        lines.append(f"  gravity {show(d.gravity_g)} along -y on every body")
    for ld in d.loads:
        if ld.point is None:
            lines.append(f"  {ld.name}: torque on {ld.body} = {show(ld.components[0])}")
        else:
            lines.append(f"  {ld.name}: force at {ld.body}.{ld.point} = ({', '.join(map(show, ld.components))})")
    for pot in d.potentials:
        lines.append(f"  {pot.name}: potential V = {show(pot.energy)}")
    for sname, expr, _ in d.switches:
        lines.append(f"  switching function {sname}: {show(expr)} (mode[{sname}] = its sign, located as an event)")
    if lines[-1] == "loads:":
        lines.append("  none")
    lines += ["", "variants:"]
    seed = load_parameters(name, reference_dir=folder)
    for v in available_variants(name, folder):
        other = load_parameters(name, v, reference_dir=folder)
        changed = [f"{k} = {_number(other, k)}" for k in d.values if getattr(other.values, k) != getattr(seed.values, k)]
        changed += [f"{k} = {getattr(other.values, k)!r}" for k in vars(seed.values)
                    if k not in d.values and getattr(other.values, k) != getattr(seed.values, k)]
        lines.append(f"  {v}: {other.variant_note or 'no note'}" + (f" [{'; '.join(changed)}]" if changed else ""))
    lines += ["", f"consistent initial state ({variant}):"]
    state = mech.initial_state()
    lines.append(f"  q(0)  = {_vector(state.q)}  ({', '.join(d.coordinate_names)})")
    lines.append(f"  qd(0) = {_vector(state.qd)}")
    lines.append(f"  max|Phi| = {state.phi_residual:.2e}, max|Phi_q qd| = {state.velocity_residual:.2e}; "
                 f"independent coordinates {[d.coordinate_names[i] for i in ps.initial.independent]} "
                 f"({ps.initial.source})")
    if d.branch is not None:
        lines.append(f"  assembly branch: {d.branch[1]}")
    return "\n".join(lines)


def _number(ps: ParameterSet, key: str) -> str:
    unit = ps.units.get(key, "")
    return f"{getattr(ps.values, key):.10g}" + (f" {unit}" if unit not in ("", "1", "-") else "")


def _vector(v: np.ndarray) -> str:
    return "[" + ", ".join(f"{x:.10g}" for x in v) + "]"

