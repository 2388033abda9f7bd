"""A bad description gets one clear error naming the body, joint, load or point at fault and why.

Each test builds a one-degree-of-freedom pendulum (a bar pinned to ground), breaks it in one way and checks the
error's type and that its message names the culprit and the reason, in both coordinate sets where the fault is
the description's (``lower`` validates first) and in the coordinate set that has the fault otherwise.
"""

from __future__ import annotations

import pytest
import sympy as sp

import study
from study.model.coordinates import lower
from study.model.joints import GROUND, Description, DescriptionError, Potential
from study.model.initial_state import InitialConditionError
from test_free_bodies import parameter_set

VALUES = {"m": 1.0, "J": 0.1, "a": 0.5, "g": 9.81, "zero": 0.0}
BOTH = ("relative", "absolute")


def pendulum(mass=None, inertia=None) -> Description:
    d = Description("pend", ["th"], VALUES)
    p = d.p
    d.ground("O", 0, 0)
    d.body("bar", p.m if mass is None else mass, p.J if inertia is None else inertia,
           {"pin": (0, p.a), "tip": (0, -p.a)}, angle=d.q[0])
    d.revolute("O", (GROUND, "O"), ("bar", "pin"))
    d.gravity(p.g)
    return d


def refused(d: Description, coordinates: str, *parts: str) -> str:
    """Lower ``d``; the DescriptionError's message must contain every part."""
    with pytest.raises(DescriptionError) as err:
        lower(d, coordinates)
    msg = str(err.value)
    missing = [p for p in parts if p not in msg]
    assert not missing, f"{missing} not in: {msg}"
    return msg


def test_the_pendulum_itself_is_valid():
    for coordinates in BOTH:
        assert len(lower(pendulum(), coordinates).constraints) == (0 if coordinates == "relative" else 2)


# --- a body that no joint places ----------------------------------------------------------------
@pytest.mark.parametrize("coordinates", BOTH)
def test_a_body_no_joint_touches_is_refused_by_name(coordinates):
    d = pendulum()
    d.body("lost", 1.0, 0.1, {"c": (0, 0)}, angle=0)
    refused(d, coordinates, "body 'lost'", "no joint places it", "no position of its own")


@pytest.mark.parametrize("attach, reason", [
    (lambda d: d.distance("rod", (GROUND, "O"), ("lost", "c"), 1), "'rod' is a distance joint"),
    (lambda d: d.revolute("pin2", ("bar", "tip"), ("lost", "c"), cut=True), "'pin2' is marked cut=True"),
    (lambda d: d.prismatic("rail", ("lost", "c"), (GROUND, "O"), (1, 0), (0, 1)),
     "'rail' is a prismatic joint without a travel"),
])
def test_a_body_only_cut_joints_touch_cannot_be_placed_in_relative_coordinates(attach, reason):
    d = pendulum()
    d.body("lost", 1.0, 0.1, {"c": (0, 0)}, angle=d.q[0])
    attach(d)
    refused(d, "relative", "bodies ['lost'] cannot be placed from ground", "body 'lost': " + reason)


# --- a point not on its body --------------------------------------------------------------------
@pytest.mark.parametrize("add, culprit", [
    (lambda d: d.revolute("pin2", (GROUND, "O"), ("bar", "nowhere")), "joint 'pin2'"),
    (lambda d: d.distance("rod", (GROUND, "O"), ("bar", "nowhere"), 1), "joint 'rod'"),
    (lambda d: d.prismatic("rail", ("bar", "nowhere"), (GROUND, "O"), (1, 0), (0, 1)), "joint 'rail'"),
    (lambda d: d.force("push", "bar", "nowhere", 1, 0), "load 'push'"),
    (lambda d: d.force("pull", "bar", "tip", -d.position("bar", "nowhere")[0], 0),
     "load 'pull': input x, y of point bar.nowhere"),
    (lambda d: d.spring("spring", (GROUND, "O"), ("bar", "nowhere"), 1, 0),
     "potential 'spring': input x, y of point bar.nowhere"),
])
def test_a_point_not_on_its_body_is_refused_naming_who_uses_it(add, culprit):
    d = pendulum()
    add(d)
    refused(d, "absolute", culprit, "body 'bar' has no point 'nowhere' (has ['pin', 'tip'])")


def test_an_unknown_ground_point_is_refused():
    d = pendulum()
    d.revolute("pin2", (GROUND, "nowhere"), ("bar", "tip"))
    refused(d, "relative", "joint 'pin2': unknown ground point 'nowhere'")


# --- a joint between a body and itself ----------------------------------------------------------
@pytest.mark.parametrize("add, what", [
    (lambda d: d.revolute("self", ("bar", "pin"), ("bar", "tip")), "body 'bar'"),
    (lambda d: d.distance("self", ("bar", "pin"), ("bar", "tip"), 1), "body 'bar'"),
    (lambda d: d.prismatic("self", ("bar", "pin"), ("bar", "tip"), (1, 0), (0, 1)), "body 'bar'"),
    (lambda d: (d.ground("P", 1, 0), d.revolute("self", (GROUND, "O"), (GROUND, "P"))), "ground"),
])
@pytest.mark.parametrize("coordinates", BOTH)
def test_a_joint_between_a_body_and_itself_is_refused_by_name(add, what, coordinates):
    d = pendulum()
    add(d)
    refused(d, coordinates, f"joint 'self' joins {what} to itself")


# --- an unknown input in a load law -------------------------------------------------------------
@pytest.mark.parametrize("add, parts", [
    (lambda d: d.torque("drive", "bar", sp.Symbol("w")), ("load 'drive' uses unknown symbols ['w']",)),
    (lambda d: d.torque("drive", "bar", -d.rate("nobody")), ("load 'drive': input rate of 'nobody'",
                                                           "unknown body 'nobody'")),
    (lambda d: d.torsion_spring("coil", "nobody", 1.0), ("potential 'coil': input angle of 'nobody'",
                                                          "unknown body 'nobody'")),
    (lambda d: d.potentials.append(Potential("lift", d.p.m * d.p.g * sp.Symbol("h"))),
     ("potential 'lift' uses unknown symbols ['h']",)),
    (lambda d: d.potentials.append(Potential("drag", d.rate("bar") ** 2)),
     ("potential 'drag' uses unknown symbols ['in_rate__bar']", "position or angle inputs")),
    (lambda d: d.switch("flip", sp.Symbol("s")), ("switch 'flip' uses unknown symbols ['s']",)),
])
@pytest.mark.parametrize("coordinates", BOTH)
def test_an_unknown_input_in_a_load_law_is_refused_naming_the_load(add, parts, coordinates):
    d = pendulum()
    add(d)
    refused(d, coordinates, *parts)


# --- the assembly branch ------------------------------------------------------------------------
def branch_pendulum(branch) -> Description:
    d = Description("pend", ["th"], {k: VALUES[k] for k in "mJag"})
    d.ground("O", 0, 0)
    d.body("bar", d.p.m, d.p.J, {"pin": (0, d.p.a)}, angle=d.q[0])
    d.revolute("O", (GROUND, "O"), ("bar", "pin"))
    d.assembly_branch(*branch)
    return d


def test_a_branch_condition_false_at_the_initial_state_is_refused(tmp_path):
    ps = parameter_set(tmp_path, "pend", {k: VALUES[k] for k in "mJag"}, [3.0], [0.0], [0])
    d = branch_pendulum((sp.cos(sp.Symbol("q_th", real=True)), "cos(th) > 0"))
    with pytest.raises(InitialConditionError, match=r"pend: .*q = \[3\.\], which is not on the assembly branch "
                                                    r"'cos\(th\) > 0' .*its condition cos\(q_th\) > 0 is -0\.98999"):
        study.Mechanism(d, ps).initial_state()
    d = branch_pendulum((-sp.cos(sp.Symbol("q_th", real=True)), "cos(th) < 0"))   # the same state on its branch
    assert study.Mechanism(d, ps).initial_state().q[0] == 3.0


@pytest.mark.parametrize("coordinates", BOTH)
def test_a_branch_condition_in_unknown_symbols_is_refused(coordinates):
    refused(branch_pendulum((sp.Symbol("u"), "u > 0")), coordinates,
            "assembly branch 'u > 0' uses unknown symbols ['u']", "an expression of q and parameters")


# --- a mass or inertia that is not positive ------------------------------------------------------
@pytest.mark.parametrize("key, given, shown", [
    ("mass", 0, "body 'bar'.mass = 0 is not positive"),
    ("mass", -1.5, "body 'bar'.mass = -1.5 is not positive"),
    ("mass", "zero", "body 'bar'.mass = 0 (p_zero with the parameter values) is not positive"),
    ("mass", "-m", "body 'bar'.mass = -1 (-p_m with the parameter values) is not positive"),
    ("inertia", -0.1, "body 'bar'.inertia = -0.1 is not positive"),
    ("inertia", "J - m", "body 'bar'.inertia = -0.9 (p_J - p_m with the parameter values) is not positive"),
])
@pytest.mark.parametrize("coordinates", BOTH)
def test_a_mass_or_inertia_that_is_not_positive_is_refused_with_its_value(key, given, shown, coordinates):
    d0 = pendulum()
    if isinstance(given, str):
        given = sp.sympify(given, locals={k: getattr(d0.p, k) for k in VALUES})
    d = pendulum(**{key: given})
    refused(d, coordinates, shown)


def test_a_positive_mass_in_parameters_is_accepted():
    d0 = pendulum()
    lower(pendulum(mass=d0.p.m + d0.p.zero, inertia=2 * d0.p.J), "absolute")


# --- no degree of freedom, or a negative number -------------------------------------------------
@pytest.mark.parametrize("add, dof, joints", [
    (lambda d: (d.ground("T", 0, -1), d.distance("tie", (GROUND, "T"), ("bar", "tip"), 1)), 0,
     {"relative": "(joints 'tie' (1 row))", "absolute": "(joints 'O' (2 rows), 'tie' (1 row))"}),
    (lambda d: d.revolute("extra", (GROUND, "O"), ("bar", "tip")), -1,
     {"relative": "(joints 'extra' (2 rows))", "absolute": "(joints 'O' (2 rows), 'extra' (2 rows))"}),
])
@pytest.mark.parametrize("coordinates", BOTH)
def test_no_or_negative_degrees_of_freedom_are_refused_with_the_counts(add, dof, joints, coordinates):
    d = pendulum()
    add(d)
    m = 1 if coordinates == "relative" else 3
    rows = f"{m - dof} constraint row" + ("" if m - dof == 1 else "s")
    counts = f"in {coordinates} coordinates, {m} coordinate{'s' if m > 1 else ''} and {rows}"
    refused(d, coordinates, counts, joints[coordinates], f"leave {dof} degrees of freedom",
            "a mechanism needs at least one")


def test_a_coordinate_that_moves_no_body_is_refused():
    d = Description("pend", ["th", "z"], VALUES)
    d.ground("O", 0, 0)
    d.body("bar", d.p.m, d.p.J, {"pin": (0, d.p.a)}, angle=d.q[0])
    d.revolute("O", (GROUND, "O"), ("bar", "pin"))
    refused(d, "relative", "coordinates ['z'] move no body")


def test_problems_of_several_kinds_come_in_one_error():
    d = pendulum(mass=0)
    d.revolute("self", ("bar", "pin"), ("bar", "tip"))
    d.body("lost", 1.0, 0.1, {"c": (0, 0)}, angle=0)
    msg = refused(d, "relative", "body 'bar'.mass = 0", "joint 'self' joins body 'bar'", "body 'lost': no joint")
    assert msg.startswith("mechanism 'pend': ")
