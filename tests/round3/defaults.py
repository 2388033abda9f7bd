"""Round three, group 'defaults and silent physics': see tests/round3/__init__.py.

The physics a parameter set states is the physics that runs: every friction entry of a description (a sliding
contact's or a pin's) with a nonzero coefficient, resistance or constant torque gets the parameter set's treatment
(exact stick/slip) unless the user asks otherwise, through the command line and the library alike; a run without it
says so in its metadata. The entries with friction are typed here from the parameter files (reference/*.toml), not
read from the code under test. Also the weak cases of issue 38 item 7 that concern run arguments.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

from round3 import OK, add

G = "defaults and silent physics"

# (mechanism, variant) -> the friction entries whose coefficients are nonzero in its parameter file, and a horizon
# over which each of them slides (reference/pin_pendulum.toml: mu 0.3, T0 0.05 N m, released from rest at 60 deg;
# slider_crank.toml: guide mu 0.25, F 5.5 N; slider_crank_pins.toml: pins O, A, B mu 0.1 and the guide;
# quick_return.toml: guide_friction mu_guide 0.1, slot_friction mu_slot 0.15).
# The treatment is exact stick/slip unless the parameter file states another (slider_crank_pins.toml:
# friction_treatment = "regularized", since the exact treatment cannot split a holding force among joints held together).
FRICTIONAL = {("pin_pendulum", "seed"): (("pin",), "0.5", "exact"),
              ("slider_crank", "seed"): (("guide",), "0.05", "exact"),
              ("slider_crank_pins", "seed"): (("guide", "O", "A", "B"), "0.05", "regularized"),
              ("quick_return", "guide_friction"): (("ram_guide",), "0.2", "exact"),
              ("quick_return", "slot_friction"): (("block_on_rocker",), "0.2", "exact")}


def _load(path: Path):
    from study.results import SimulationResult

    return SimulationResult.load(path)


def did_work(entries, path="out/x", treatment="exact"):
    """``then``: the saved run applied ``treatment`` and every entry's friction did (dissipative) work."""
    def then(tmp):
        r = _load(tmp / path)
        assert r.meta.get("friction") == treatment, f"friction {r.meta.get('friction')!r}, not {treatment!r}"
        for e in entries:
            work = r.energies.get(f"work_friction_{e}")
            assert work is not None, f"no work_friction_{e}: the entry's friction did not run"
            assert work[-1] < 0, f"work_friction_{e} = {work[-1]!r} at t_end: its friction did no work"
    return then


def cli(mechanism, variant, t_end, *tail):
    return lambda tmp: ["simulate", mechanism, "--variant", variant, "--t-end", t_end, *tail,
                        "--out", str(tmp / "out" / "x")]


for (mech, variant), (entries, t_end, treatment) in FRICTIONAL.items():
    add(G, f"cli_default_friction_{mech}_{variant}", cli(mech, variant, t_end), OK, cli=True,
        then=did_work(entries, treatment=treatment))


def lib_saved(name, variant="seed", t_end=0.5, **kw):
    """simulate(name, ...) through the library, saved to out/x for ``then``."""
    def action(tmp):
        from study.simulate import simulate

        simulate(name, variant=variant, t_end=t_end, **kw).save(tmp / "out" / "x")
    return action


for mech in ("pin_pendulum", "slider_crank_pins"):
    entries, t_end, treatment = FRICTIONAL[(mech, "seed")]
    add(G, f"lib_default_friction_{mech}", lib_saved(mech, t_end=float(t_end)), OK,
        then=did_work(entries, treatment=treatment))


def left_out(entries):
    """``then``: the saved run ran without friction and its metadata names the entries it left out."""
    def then(tmp):
        r = _load(tmp / "out" / "x")
        assert r.meta.get("friction") is None, f"friction {r.meta.get('friction')!r}"
        assert r.meta.get("friction_default") is False, f"friction_default {r.meta.get('friction_default')!r}"
        assert r.meta.get("friction_left_out") == list(entries), f"friction_left_out {r.meta.get('friction_left_out')!r}"
        assert not any(k.startswith("work_friction_") for k in r.energies)
    return then


add(G, "cli_friction_none_is_stated_in_metadata", cli("pin_pendulum", "seed", "0.2", "--friction", "none"), OK,
    cli=True, then=left_out(["pin"]))
add(G, "lib_friction_none_text_is_stated", lib_saved("pin_pendulum", t_end=0.2, friction="none"), OK,
    then=left_out(["pin"]))
add(G, "lib_friction_none_object_is_stated", lib_saved("slider_crank_pins", t_end=0.05, friction=None), OK,
    then=left_out(["guide", "O", "A", "B"]))


def default_stated(tmp):
    r = _load(tmp / "out" / "x")
    assert r.meta.get("friction_default") is True and r.meta.get("friction_left_out") == [], r.meta


add(G, "cli_default_is_stated_in_metadata", cli("pin_pendulum", "seed", "0.2"), OK, cli=True, then=default_stated)


def nothing_to_leave_out(tmp):
    """quick_return's seed has a ram-guide contact with mu = 0 (reference/quick_return.toml): no friction runs, and
    nothing with friction was left out."""
    r = _load(tmp / "out" / "x")
    assert r.meta.get("friction") is None and r.meta.get("friction_left_out") == [], r.meta


add(G, "cli_default_zero_coefficients_run_no_friction", cli("quick_return", "seed", "0.05"), OK, cli=True,
    then=nothing_to_leave_out)
add(G, "cli_ali3p_with_default_pin_friction", cli("pin_pendulum", "seed", "0.2", "--integrator", "ALI3P", "--step",
                                                   "1e-3"), 2, "--friction = 'exact'", "ALI3P", "--friction none")


def lib_ali3p(tmp):
    from study.simulate import simulate

    simulate("pin_pendulum", t_end=0.2, integrator="ALI3P", step=1e-3)


add(G, "lib_ali3p_with_default_pin_friction", lib_ali3p, ValueError, "'exact'", "pin", "ALI3P", "default",
    "friction='none'")
add(G, "cli_eps_with_default_pin_friction", cli("pin_pendulum", "seed", "0.2", "--friction-eps", "0.1"), 2,
    "--friction-eps", "exact", "no width")

# --- issue 38 item 7: the weak cases among a run's arguments ---------------------------------------------------------
# --out '' is refused before any work: the horizon would take minutes (friction transitions over 200 s)
add(G, "cli_empty_out_refused_before_the_run",
    lambda tmp: ["simulate", "pin_pendulum", "--t-end", "200", "--out", ""], 2, "--out ''", "empty")
add(G, "cli_blank_out_refused_before_the_run",
    lambda tmp: ["simulate", "pin_pendulum", "--t-end", "200", "--out", "  "], 2, "--out '", "empty")
add(G, "cli_negative_friction_eps_in_exponent_form",
    cli("slider_crank", "seed", "0.05", "--friction", "regularized", "--friction-eps", "-1e-3"), 2,
    "--friction-eps", "-0.001", "> 0")
add(G, "cli_validate_negative_friction_eps",
    lambda tmp: ["validate", str(Path(__file__).resolve().parents[2] / "examples" / "cart_pendulum" /
                                 "cart_pendulum.py"), "--friction-eps", "-1e-3", "--out", str(tmp / "v")], 2,
    "friction_eps", "-0.001", "> 0")
add(G, "cli_negative_t_end_in_exponent_form", cli("slider_crank", "seed", "-1e-1"), 2, "--t-end", "-0.1", "> 0")


def lambda_wrong_length(tmp):
    from study.simulate import simulate

    simulate("slider_crank", t_end=0.05, method="sliding_mode", Lambda=(10.0, 10.0, 10.0))


add(G, "lib_sliding_mode_lambda_wrong_length", lambda_wrong_length, ValueError, "Lambda", "3 values", "1 constraint")
add(G, "cli_sliding_mode_lambda_list_refused", cli("slider_crank", "seed", "0.05", "--method", "sliding_mode",
                                                   "--option", "Lambda=1,2"), 2, "--option Lambda", "'1,2'")


def numpy_integers(tmp):
    """np.int64 wherever an integer is accepted: the equations' sizes, max_evaluations, max_iter."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    import handwritten
    from study.simulate import simulate

    eom = handwritten.cartesian_pendulum()
    eom = dataclasses.replace(eom, n_coordinates=np.int64(eom.n_coordinates), n_constraints=np.int64(eom.n_constraints))
    r = simulate(eom, [0.6, -0.8], [-0.8, -0.6], t_end=0.1, method="projection", max_iter=np.int64(5),
                 max_evaluations=np.int64(100_000))
    r.save(tmp / "out" / "x")
    (tmp / "sizes.json").write_text(json.dumps([type(eom.n_coordinates).__name__, r.q.shape[1]]))


def sizes_are_python_ints(tmp):
    kind, columns = json.loads((tmp / "sizes.json").read_text())
    assert kind == "int" and columns == 2, (kind, columns)


add(G, "lib_numpy_integers_accepted", numpy_integers, OK, then=sizes_are_python_ints)


def numpy_worker_count(tmp):
    """The pipeline's worker count as a numpy integer: one worker runs the cases in this process."""
    from study.pipeline.executors import InlineExecutor, make_executor

    with make_executor(np.int64(1)) as pool:
        (tmp / "pool.json").write_text(json.dumps(isinstance(pool, InlineExecutor)))


def runs_inline(tmp):
    assert json.loads((tmp / "pool.json").read_text()) is True


add(G, "lib_numpy_worker_count_accepted", numpy_worker_count, OK, then=runs_inline)
