"""The Exudyn model of any joint-level description (:class:`study.model.joints.Description`), and its run.

No mechanism is named here: bodies, joints, loads, friction and the result mapping are all read from the
description of a :class:`study.model.Mechanism` (a user's, or a study mechanism's). :func:`build` assembles
the model at the in-house consistent initial state with one handler per element kind; :func:`run` solves it and
maps Exudyn's outputs back into a SimulationResult (:mod:`study.exudyn_models.mapping`). The in-house equations of
motion are used for nothing but the consistent initial state and for evaluating the in-house Phi on Exudyn's
coordinates (so both codes are compared like for like).

Modules of the translation
--------------------------
kinematics
    The description's kinematics bound to its values: the initial body states, and Exudyn's body poses back to q.
load_law
    A load law lambdified once, evaluated from Exudyn's live kinematics or as a symbolic user function.
assembly
    What the handlers share while the model is built (markers, reference angles, live readers) and what the build
    returns (:class:`~study.exudyn_models.assembly.Built`).
elements
    Bodies and joints (revolute, distance, prismatic): one handler each.
loads
    Loads and potentials (springs): constant, symbolic or Python user functions.
friction
    Contacts with friction (a guide) and pins with friction: one handler each.
mapping, series, conventions
    The result mapping: Exudyn's outputs into the SimulationResult (q, lam, forces, energies), the description's
    quantities on Exudyn's body series, and the texts of the conventions a result carries.
"""

from __future__ import annotations

import numpy as np

import study.exudyn_models.mapping as mapping
import study.exudyn_models.settings as settings
import study.exudyn_models.solve as solve
from study.exudyn_models.assembly import Assembly, Built
from study.exudyn_models.building import Model
from study.exudyn_models.elements import add_bodies, add_joint
from study.exudyn_models.friction import active, add_contact_friction, add_pin_friction, loads_jacobian
from study.exudyn_models.guards import initialize, seed_reaction_guards
from study.exudyn_models.kinematics import body_states, kinematics
from study.exudyn_models.loads import add_load, add_potential
from study.mechanisms import as_mechanism
from study.model import Mechanism
from study.params import ParameterSet
from study.reference_data import tolerance
from study.results import SimulationResult

Array = np.ndarray


def build(mechanism: Mechanism | ParameterSet, q0, qd0, friction: str = "regularized",
          eps: float = settings.DEFAULT_EPS, configuration: str = "python") -> Built:
    """Assemble the Exudyn model of a mechanism's description at the state (q0, qd0) (relative coordinates).

    The elements in order (the order of Exudyn's items): bodies, joints, the markers of the laws' input points,
    loads, potentials, then (``friction`` 'regularized') the contacts' and pins' friction.
    ``configuration`` (settings.CONFIGURATIONS): 'python' evaluates every state-dependent law in a
    Python load user function; 'tuned' records it as an Exudyn symbolic user function where the law's
    inputs are those of the element carrying it (:func:`study.exudyn_models.loads.symbolic_law`), else keeps the
    Python one, and leaves the numerical load Jacobian off unless a Python load remains that needs it (the friction).
    """
    mech = as_mechanism(mechanism)
    kin = kinematics(mech)
    d = kin.d
    built = Built(mech, d, kin, Model(), friction, eps, loads_jacobian(d), configuration)
    built.q0 = np.asarray(q0, dtype=float).copy()
    a = Assembly(built, body_states(mech, q0, qd0))
    add_bodies(a)
    for j in d.joints:
        add_joint(a, j)
    a.read_inputs()
    for load in d.loads:
        add_load(a, load)
    for pot in d.potentials:
        add_potential(a, pot)
    if friction == "regularized":
        for j in d.contacts():
            if active(d, j):
                add_contact_friction(a, j)
        delta = tolerance("pin_friction_norm_width")
        for j in d.pins():
            if active(d, j):
                add_pin_friction(a, j, delta)
    if configuration == "tuned" and not built.frictions:
        built.loads_jacobian = 0    # no Python load left whose derivative Newton needs
    built.model.assemble()
    return built


def run(mechanism: Mechanism | ParameterSet, t_end: float, h: float, solver: str = "index3",
        output_step: float | None = None, friction: str = "regularized", eps: float = settings.DEFAULT_EPS,
        configuration: str = "python", ignore_singular: bool = False, linear_solver: str = "dense",
        newton_tolerance: float = settings.NEWTON_TOLERANCE) -> SimulationResult:
    """Simulate a mechanism in Exudyn from the in-house consistent initial state.

    Parameters
    ----------
    mechanism : study.Mechanism (a description with its parameter set), or a study mechanism's ParameterSet
    t_end : float
        End time [s], a whole number of steps.
    h : float
        Fixed step [s].
    solver : {'index3', 'index2'} (or an explicit name, which Exudyn refuses; see settings.SOLVERS)
    output_step : float, optional
        Sampling of the result, a whole multiple of h; default every step.
    friction : {'regularized', 'none'}
        'none' leaves out the Coulomb friction and resistance of every contact and pin.
    eps : float
        Velocity scale of tanh(v/eps) in the friction and resistance laws [m/s] (settings.DEFAULT_EPS); a pin's
        law reads the same number in rad/s (tanh(omega_rel/eps)), as the in-house friction_eps.
    configuration : {'python', 'tuned'}
        How Exudyn evaluates the load laws and iterates (settings.CONFIGURATIONS); both solve the same
        model, 'tuned' as Exudyn recommends for speed.
    ignore_singular : bool
        Exudyn's option for redundant constraints / singular poses (settings.simulation_settings); dense
        linear solver only.
    linear_solver : {'dense', 'sparse'}
        The linear solver of Newton's iteration (settings.LINEAR_SOLVERS): Exudyn's dense inverse, or Eigen's
        sparse LU, which Exudyn recommends for larger systems (e.g. the N-four-bar at N = 40).
    newton_tolerance : float
        Relative and absolute tolerance of Newton's iteration (default settings.NEWTON_TOLERANCE). A run whose
        residual cannot reach it (a round-off floor at a singular pose) stops with exudyn.SolverError.

    Returns
    -------
    SimulationResult (see the module docstring for the mapping of every quantity)
    """
    grid = settings.check_arguments(t_end, h, solver, output_step, friction, eps, configuration, linear_solver,
                                    ignore_singular, newton_tolerance)
    mech = as_mechanism(mechanism)
    eom = mech.equations()
    state0 = mech.initial_state()
    built = build(mech, state0.q, state0.qd, friction, eps, configuration)
    simulation = settings.simulation_settings(grid, solver, built.loads_jacobian, configuration, ignore_singular,
                                              linear_solver, newton_tolerance)
    stats = {"configuration": configuration, "linear_solver": linear_solver, "newton_tolerance": newton_tolerance}
    if solver in settings.IMPLICIT_SOLVERS:
        stats.update(seed_reaction_guards(built.model, simulation, built.frictions))
    stats.update(solve.solve(built.model, simulation, solver))
    return mapping.result(built, eom, grid, solver, stats)


def initial_accelerations(mechanism: Mechanism | ParameterSet, q, qd, friction: str = "regularized",
                          eps: float = settings.DEFAULT_EPS) -> tuple[Array, Array]:
    """Exudyn's accelerations and multipliers at a state (relative coordinates), from its solver
    initialization alone: the initial-acceleration solve SolveDynamic performs at t = 0 (with the seeded
    normal force if friction is on), mapped to the in-house coordinates and multiplier convention.

    Returns
    -------
    qdd : (m,) array
    lam : (r,) array, in ``eom.constraint_names`` order
    """
    settings.check_arguments(1.0, 1.0, "index3", None, friction, eps)
    built = build(as_mechanism(mechanism), q, qd, friction, eps)
    simulation = settings.simulation_settings(settings.RunGrid(1.0, 1.0, 1, 1), "index3", built.loads_jacobian)
    seed_reaction_guards(built.model, simulation, built.frictions)
    return initialize(built.model, simulation, lambda: mapping.initial_values(built))
