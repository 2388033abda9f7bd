"""The examples: users' mechanisms that no file of study/ names, each run through the public API (``import study``)
as its own script does.

Independent references, derived by hand: the oscillating cylinder's loop closure at its initial state and its
energy conservation; the Scotch yoke's energy integral, which fixes the crank's rate by its angle. The stabilization
methods must follow the same motion.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from study.reference_data import tolerance

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
RTOL = 1e-10


def example(name: str):
    """The example's script, imported from its own folder like a user's file."""
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / name / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_oscillating_cylinder_through_every_method():
    """1 s at rtol 1e-10: every method runs; the consistent initial state is the hand-solved closure; the methods
    that add no forces of their own beyond the constraints' (none, Baumgarte, projection) conserve the energy and
    follow the projection run's motion within twice the adaptive runs' global error bound. (The sliding mode's
    sgn term, at its default gains, moves the motion by ~1e-7 rad here: a property of that law, not of the run.)"""
    results = example("oscillating_cylinder").run(t_end=1.0, rtol=RTOL)
    rc, d = 0.1, 0.3   # the example's parameter file
    assert np.allclose(results["none"].q[0], [np.pi / 2, np.arctan2(rc, -d), np.hypot(rc, d)], rtol=0, atol=1e-12)
    kinetic = max(r.energies["kinetic"].max() for r in results.values())
    for method in ("none", "baumgarte", "projection"):
        energy = results[method].energies["kinetic"] + results[method].energies["potential"]
        assert np.abs(energy - energy[0]).max() <= tolerance("energy_drift_factor") * RTOL * kinetic, method
    reference = results["projection"].q
    bound = 2 * tolerance("adaptive_global_error_factor") * RTOL * np.abs(reference).max()
    for method in ("none", "baumgarte"):
        assert np.abs(results[method].q - reference).max() <= bound, method
    assert set(results) == {"none", "baumgarte", "sliding_mode", "projection"}


def test_scotch_yoke_follows_its_energy_integral():
    """1 s at rtol 1e-10, no loads: the crank's rate is fixed by the crank's angle through the kinetic energy,
    I(th) th'^2 = const with I = mc rc^2/3 + mb rc^2 + my rc^2 sin^2(th) (the block turns with nothing, the yoke
    moves at -rc sin(th) th'), derived by hand. The runs that add no forces of their own (none, Baumgarte,
    projection) keep it within the adaptive runs' global error bound; the slot keeps the yoke at x = rc cos(th)."""
    results = example("scotch_yoke").run(t_end=1.0, rtol=RTOL)
    rc, mc, mb, my = 0.15, 1.2, 0.3, 2.5   # the example's parameter file

    def inertia(th):
        return mc * rc ** 2 / 3 + mb * rc ** 2 + my * rc ** 2 * np.sin(th) ** 2

    for method in ("none", "baumgarte", "projection"):
        th, rate = results[method].q[:, 0], results[method].qd[:, 0]
        exact = rate[0] * np.sqrt(inertia(th[0]) / inertia(th))
        bound = tolerance("adaptive_global_error_factor") * RTOL * np.abs(rate).max()
        assert np.abs(rate - exact).max() <= bound, method
        assert np.abs(results[method].q[:, 1] - rc * np.cos(th)).max() <= bound * rc, method
