"""The physics a parameter set states is the physics that runs (issue 38 item 1).

Every study mechanism, in every variant, run with the defaults (the library's ``study.simulate`` and
``python -m study simulate`` without ``--friction``) for a short horizon: each friction entry of its description, a
sliding contact's or a pin's, whose coefficients, resistance or constant torque are nonzero with the variant's values
did work (``work_friction_<entry>`` < 0 at the end: friction dissipates). The entries are read from the description's
joints and the parameter values here, not from the solver's own list. A run without friction (asked for) says so
in its metadata.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import study
from study.cli import main
from study.mechanisms import mechanism, time_scale
from study.params import available_mechanisms, available_variants, load_parameters
from study.results import SimulationResult

# The fraction of a mechanism's time scale (study.mechanisms.time_scale) each run covers: every entry with friction
# slides within it (the pendulum is released from rest and swings at once; the slider-cranks' slider moves for
# milliseconds before it sticks, their pins turn with the crank; the quick-return's guide and slot move with the drive).
HORIZON = 0.05


def frictional_entries(ps) -> list[str]:
    """The joints of the description with friction data that is nonzero with the parameter values."""
    d = mechanism(ps).description
    values = {getattr(d.p, k): v for k, v in d.values.items()}
    return [j.name for j in d.joints if getattr(j, "friction", None) is not None
            and any(sp.sympify(x).xreplace(values) != 0 for x in (j.friction.mu_static, j.friction.mu_kinetic,
                                                                   j.friction.resistance))]


CATALOGUE = [(m, v) for m in available_mechanisms() for v in available_variants(m)]
WITH_FRICTION = [(m, v) for m, v in CATALOGUE if frictional_entries(load_parameters(m, v))]


def test_the_catalogue_has_pins_and_contacts_with_friction():
    """The check below is not empty: the pendulum's pin and the slider-crank's guide are among the entries."""
    assert ("pin_pendulum", "seed") in WITH_FRICTION and ("slider_crank", "seed") in WITH_FRICTION
    assert "pin" in frictional_entries(load_parameters("pin_pendulum"))


def _did_work(r: SimulationResult, entries: list[str]) -> None:
    assert r.meta["friction"] is not None and r.meta["friction_default"] is True, r.meta
    for e in entries:
        work = r.energies.get(f"work_friction_{e}")
        assert work is not None, f"{r.meta['mechanism']}/{r.meta['variant']}: the friction of {e!r} did not run"
        assert work[-1] < 0, f"{r.meta['mechanism']}/{r.meta['variant']}: work_friction_{e} = {work[-1]!r}"


@pytest.mark.parametrize("name,variant", WITH_FRICTION, ids=[f"{m}/{v}" for m, v in WITH_FRICTION])
def test_every_friction_entry_does_work_by_default_in_the_library(name, variant):
    r = study.simulate(name, variant=variant, t_end=HORIZON * time_scale(name))
    _did_work(r, frictional_entries(load_parameters(name, variant)))


@pytest.mark.parametrize("name,variant", WITH_FRICTION, ids=[f"{m}/{v}" for m, v in WITH_FRICTION])
def test_every_friction_entry_does_work_by_default_on_the_command_line(name, variant, tmp_path, capsys):
    out = tmp_path / "x"
    assert main(["simulate", name, "--variant", variant, "--t-end", f"{HORIZON * time_scale(name):g}",
                 "--out", str(out)]) == 0
    assert "[parameter set's default]" in capsys.readouterr().out
    _did_work(SimulationResult.load(out), frictional_entries(load_parameters(name, variant)))


def test_a_run_without_friction_says_so(tmp_path, capsys):
    out = tmp_path / "x"
    assert main(["simulate", "pin_pendulum", "--t-end", "0.1", "--friction", "none", "--out", str(out)]) == 0
    assert "friction none (asked: the friction of pin left out)" in capsys.readouterr().out
    r = SimulationResult.load(out)
    assert (r.meta["friction"], r.meta["friction_default"], r.meta["friction_left_out"]) == (None, False, ["pin"])
    assert not any(k.startswith("work_friction_") for k in r.energies)


def test_the_default_without_friction_data_runs_none():
    """A variant whose entries all have zero coefficients (quick_return's seed: mu_guide = 0) runs no friction, and
    leaves nothing out."""
    assert frictional_entries(load_parameters("quick_return")) == []
    r = study.simulate("quick_return", t_end=0.02)
    assert (r.meta["friction"], r.meta["friction_default"], r.meta["friction_left_out"]) == (None, True, [])
    assert np.all(np.isfinite(r.q))
