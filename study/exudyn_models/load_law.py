"""A load law of a description, lambdified once with the parameter values bound, and its live inputs from Exudyn.

A law without state, time or mode dependence (after binding the parameter values) is constant (``Law.constant``,
``Law.values``). Any other law is evaluated from Exudyn's own kinematics (:class:`Readers`): marker position /
velocity of the input point, node angle = reference + displacement, node angular velocity. A mode symbol is +1 if
its switching function (evaluated live on the same inputs) is >= 0, else -1: the law is evaluated without event
location, as Exudyn cannot locate a switch within a step. :meth:`Law.symbolic` gives the same law on Exudyn
symbolic values (``exudyn.symbolic``) for a symbolic user function.
"""

from __future__ import annotations

import sympy as sp

import study.exudyn_models.building as building
from study.exudyn_models.building import OVT, Model
from study.model.joints import GROUND, Description


#: sympy function names -> Exudyn symbolic functions, for laws recorded as symbolic user functions
_ESYM = {name: getattr(building.esym, name) for name in ("sin", "cos", "tan", "tanh", "sinh", "cosh", "exp", "log",
                                                        "sqrt", "atan", "atan2", "asin", "acos", "sign")}
_ESYM["Abs"] = building.esym.abs


class Law:
    """Expressions in the description's inputs, t and mode symbols, with the parameter values bound."""

    def __init__(self, d: Description, subs: dict, exprs):
        exprs = [sp.sympify(e).xreplace(subs).xreplace(ground_values(d, subs)) for e in exprs]
        self.exprs = exprs
        syms = set().union(*(e.free_symbols for e in exprs))
        switches = [(name, sp.sympify(e).xreplace(subs), m) for name, e, m in d.switches if m in syms]
        inputs = syms | set().union(set(), *(e.free_symbols for _, e, _ in switches))
        self.inputs = [s for s in d.inputs if s in inputs]          # description order
        self.kinds = [d.inputs[s] for s in self.inputs]
        self.modes = [m for _, _, m in switches]
        self.constant = not syms                                   # no input, t or mode left
        args = [d.t, *self.inputs]
        self.f = sp.lambdify([*args, *self.modes], exprs, "math")
        self.switch_f = [sp.lambdify(args, e, "math") for _, e, _ in switches]
        self.values = [float(e) for e in exprs] if self.constant else None
        self._args = [*args, *self.modes]
        self._switch_exprs = [e for _, e, _ in switches]

    def __call__(self, t: float, inputs) -> list[float]:
        modes = [1.0 if s(t, *inputs) >= 0 else -1.0 for s in self.switch_f]
        return self.f(t, *inputs, *modes)

    def symbolic(self):
        """The law as a function of Exudyn symbolic values (``exudyn.symbolic``), for recording a symbolic
        user function: same arguments as ``__call__``; a mode is IfThenElse(switch >= 0, 1, -1), the
        same rule as the Python evaluation."""
        esym = building.esym
        f = sp.lambdify(self._args, self.exprs, modules=[_ESYM])
        switch_f = [sp.lambdify(self._args[:1 + len(self.inputs)], e, modules=[_ESYM]) for e in self._switch_exprs]

        def evaluate(t, inputs):
            modes = [esym.IfThenElse(s(t, *inputs) >= 0, esym.Real(1.0), esym.Real(-1.0)) for s in switch_f]
            return f(t, *inputs, *modes)
        return evaluate


def ground_values(d: Description, subs: dict) -> dict:
    """The inputs of ground points as the numbers they are (a fixed point's position; velocity 0), so a
    law between a body point and a ground point reads only the body point (e.g. Andrews' spring)."""
    values = {}
    for sym, inp in d.inputs.items():
        if inp.body == GROUND:
            x, y = d.ground_points[inp.point]
            values[sym] = {"x": x, "y": y}.get(inp.kind, sp.Integer(0))
    return {k: sp.sympify(v).xreplace(subs) for k, v in values.items()}


class Readers:
    """Live readers of the description's inputs from Exudyn (markers and nodes)."""

    def __init__(self, model: Model, markers: dict, refs: dict):
        self.model, self.markers, self.refs = model, markers, refs

    def reader(self, law: Law):
        mbs_reads = []
        for inp in law.kinds:
            if inp.point is not None:
                marker = self.markers[(inp.body, inp.point)]
                ovt = OVT.Position if inp.kind in ("x", "y") else OVT.Velocity
                k = 0 if inp.kind in ("x", "vx") else 1
                mbs_reads.append(lambda mbs, m=marker, o=ovt, k=k: mbs.GetMarkerOutput(m, o)[k])
            elif inp.kind == "angle":
                node, ref = self.model.node(inp.body), self.refs[inp.body]
                mbs_reads.append(lambda mbs, n=node, r=ref: r + mbs.GetNodeOutput(n, OVT.Coordinates)[2])
            else:
                node = self.model.node(inp.body)
                mbs_reads.append(lambda mbs, n=node: mbs.GetNodeOutput(n, OVT.AngularVelocity)[2])
        return lambda mbs: [r(mbs) for r in mbs_reads]
