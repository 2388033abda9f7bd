"""A second catalogue of bad inputs, each judged good, weak or bad (none of them in test_reliability_catalogue.py).

Groups: flags and options, work that cannot finish, case lists and parameter files, saved files, a user's
equations. Every try states the outcome a demanding user expects:

- a library try: the exception class, and fragments of its message naming the value, where it came from
  and why it is wrong;
- a command-line try: the exit code (2 for a refused input, 1 for a run that failed) and the same fragments
  on one stderr line starting "error:" (after any progress lines), with no traceback.

:func:`judge` grades a try:

- **bad**: no error where one is due, an undocumented exception (a raw TypeError, KeyError ...), a
  traceback, or a file written by a refused input;
- **weak**: the documented kind of error, but its message misses a fragment (it does not say which value,
  from where, or why) or the exit code is the other documented one;
- **good**: everything as stated.

A try of the group "work bounds" that expects a stopped run (a RunBoundError, or exit 1 on the command line) is
judged by what stopped it, never by the seconds it took (a host twice as slow takes twice as long): its message must
give the count at which it stopped ("after N evaluations", "N evaluations reached", "after N steps"), and an
evaluation count must not exceed the run's max_evaluations (its own, or the default of reference/tolerances.toml).
A run that goes on past its bound is bad; one that does not say what stopped it is weak.

``python tests/test_reliability_probe.py`` prints the tally; the test requires every try to be good.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import os
import re
import sys
import textwrap
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
import handwritten  # noqa: E402
from shared_cache import linked_cache  # noqa: E402
from study import pipeline as pl  # noqa: E402
from study.cli import main  # noqa: E402
from study.errors import (EquationsError, NonFiniteError, ResultIntegrityError, RunBoundError,  # noqa: E402
                          SimulationError)
from study.params import ParameterError, load_parameters  # noqa: E402
from study.results import SimulationResult  # noqa: E402
from study.simulate import simulate  # noqa: E402

@dataclass
class Try:
    name: str
    group: str
    action: Callable[[Path], object]   # (tmp) -> argv list (command line), or the library call itself
    expect: type | int                 # exception class (library) or exit code (command line)
    fragments: tuple[str, ...]
    writes: bool = False               # the try may write files (a recomputation); ``then`` checks them
    then: Callable[[Path], None] | None = None
    slow: bool = False                 # runs until its pace is measured (tens of seconds): in the slow suite


TRIES: list[Try] = []


def add(group, name, action, expect, *fragments, writes=False, then=None, slow=False):
    TRIES.append(Try(name, group, action, expect, fragments, writes, then, slow))


# --- 1. flags and options --------------------------------------------------------------------------
def sim(*tail, mechanism="slider_crank", t_end="0.05"):
    """``simulate`` argv with a short horizon and an --out in the try's folder."""
    return lambda tmp: ["simulate", mechanism, "--t-end", t_end, "--out", str(tmp / "out" / "x"), *tail]


F = "flags and options"
for flag, option, value in (("--friction", "friction", "exact"), ("--integrator", "integrator", "RK4"),
                            ("--rtol", "rtol", "1e-6"), ("--atol", "atol", "1e-9"), ("--t-end", "t_end", "1"),
                            ("--step", "step", "0.01"), ("--backend", "backend", "compiled"),
                            ("--variant", "variant", "seed"), ("--friction-eps", "friction_eps", "0.1"),
                            ("--friction-sgn", "friction_sgn", "sat"), ("--max-evaluations", "max_evaluations", "100"),
                            ("--method", "method", "baumgarte"),
                            ("--acceleration-solver", "acceleration_solver", "orthonormal"),
                            ("--output-step", "output_step", "0.1")):
    add(F, f"option_{option}_collides_with_flag", sim("--option", f"{option}={value}"), 2,
        f"--option {option}", flag)
for option in ("progress=1", "check=0", "q0=1", "min_step=x", "max_output_bytes=1e3x", "resistance_reading=holds"):
    key = option.partition("=")[0]
    add(F, f"option_{key}_not_a_method_option", sim("--method", "baumgarte", "--option", option), 2,
        f"--option {key}", "baumgarte")
add(F, "option_unknown_for_method", sim("--method", "baumgarte", "--option", "omgea=10"), 2,
    "--option omgea", "valid options", "omega")
add(F, "option_for_method_none", sim("--option", "omega=10"), 2, "--option omega", "--method none")
add(F, "option_not_a_number", sim("--method", "baumgarte", "--option", "omega=fast"), 2,
    "--option omega", "'fast'", "number")
add(F, "option_integer_given_a_float", sim("--method", "projection", "--option", "max_iter=2.5"), 2,
    "--option max_iter", "2.5", "whole number")
add(F, "option_integer_as_float_text", sim("--method", "projection", "--option", "max_iter=3.0"), 2,
    "--option max_iter", "3.0", "whole number")
add(F, "option_name_relabels_method", sim("--method", "baumgarte", "--option", "name=none"), 2,
    "--option name", "valid options")
add(F, "option_turns_projection_off", sim("--method", "projection", "--option", "projects=0"), 2,
    "--option projects", "valid options")
add(F, "option_sgn_unknown", sim("--method", "sliding_mode", "--option", "sgn=step"), 2,
    "sgn", "'step'", "valid choices")
add(F, "option_sgn_given_a_number", sim("--method", "sliding_mode", "--option", "sgn=1"), 2,
    "--option sgn", "'1'", "valid choices")
add(F, "option_width_negative", sim("--method", "sliding_mode", "--option", "width=-1"), 2,
    "width", "-1", "> 0")
add(F, "option_gain_infinite", sim("--method", "sliding_mode", "--option", "Lambda=inf"), 2, "Lambda", "inf")
add(F, "option_omega_zero", sim("--method", "baumgarte", "--option", "omega=0"), 2, "omega", "0", "> 0")
add(F, "option_weighting_unknown", sim("--method", "projection", "--option", "weighting=euclid"), 2,
    "weighting", "'euclid'", "minimum_norm")
add(F, "option_given_twice", sim("--method", "baumgarte", "--option", "omega=10", "--option", "omega=20"), 2,
    "--option omega", "twice")
add(F, "option_empty_key", sim("--option", "=5"), 2, "--option '=5'", "KEY=VALUE")
add(F, "option_alpha_with_omega", sim("--method", "baumgarte", "--option", "alpha=1", "--option", "omega=10"), 2,
    "d and omega or alpha and beta")
add(F, "fixed_step_for_adaptive", sim("--step", "0.01"), 2, "--step", "RK45", "adaptive")
add(F, "rk4_without_step", sim("--integrator", "RK4"), 2, "RK4", "--step")
add(F, "step_longer_than_horizon", sim("--integrator", "RK4", "--step", "1"), 2, "--step = 1", "--t-end = 0.05")
add(F, "eps_for_exact_friction", sim("--friction", "exact", "--friction-eps", "0.1"), 2,
    "--friction-eps", "exact", "no width")
add(F, "eps_without_friction", sim("--friction", "none", "--friction-eps", "0.1"), 2, "--friction-eps", "none")
add(F, "sgn_for_plain_sign", sim("--friction", "sign", "--friction-sgn", "sat", "--integrator", "RK4",
                                 "--step", "0.001"), 2, "--friction-sgn", "sign")
add(F, "sgn_for_exact_friction", sim("--friction", "exact", "--friction-sgn", "sat"), 2, "--friction-sgn", "exact")
for value in ("0", "-1", "nan", "inf"):
    add(F, f"friction_eps_{value}", sim("--friction", "regularized", "--friction-eps", value), 2,
        "--friction-eps", value)
for value in ("0", "-1", "nan", "inf"):
    add(F, f"t_end_{value}", sim(t_end=value), 2, "--t-end", value)
for flag, value in (("--rtol", "0"), ("--rtol", "nan"), ("--atol", "-1"), ("--atol", "inf")):
    add(F, f"{flag[2:]}_{value}", sim(flag, value), 2, flag, value)
add(F, "max_evaluations_fraction", sim("--max-evaluations", "1.5"), 2, "--max-evaluations", "1.5", "whole number")
add(F, "max_evaluations_zero", sim("--max-evaluations", "0"), 2, "--max-evaluations", "0")
add(F, "step_zero", sim("--integrator", "RK4", "--step", "0"), 2, "step", "0", "> 0")
add(F, "step_nan", sim("--integrator", "RK4", "--step", "nan"), 2, "step", "nan")
add(F, "compiled_augmented_lagrangian", sim("--backend", "compiled", "--acceleration-solver",
                                            "augmented_lagrangian"), 2, "augmented_lagrangian", "compiled")
add(F, "compiled_ali3p", sim("--backend", "compiled", "--integrator", "ALI3P", "--step", "0.001", "--friction", "none"),
    2, "ALI3P", "compiled")
add(F, "variant_unknown_named", sim("--variant", "nope"), 2, "'nope'", "valid choices")
add(F, "ali3p_without_step", sim("--integrator", "ALI3P"), 2, "--integrator ALI3P", "fixed-step", "--step")
add(F, "ali3p_with_default_exact_friction", sim("--integrator", "ALI3P", "--step", "0.001"), 2,
    "--friction = 'exact'", "--integrator ALI3P", "--friction none")
for flags, fragment in ((("--method", "baumgarte"), "--method = 'baumgarte'"),
                        (("--acceleration-solver", "multiplier"), "--acceleration-solver = 'multiplier'"),
                        (("--backend", "compiled"), "--backend = 'compiled'"),
                        (("--rtol", "1e-8"), "--rtol/--atol")):
    add(F, f"ali3p_with_{flags[0][2:].replace('-', '_')}", sim("--integrator", "ALI3P", "--step", "0.001",
                                                             "--friction", "none", *flags), 2, fragment, "ALI3P")
add(F, "output_step_longer_than_horizon", sim("--output-step", "1"), 2, "--output-step = 1", "--t-end = 0.05")
add(F, "verify_zero_ulps", lambda tmp: ["verify", "slider_crank", "--perturb", "--ulps", "0",
                                        "--out", str(tmp / "r")], 2, "--ulps 0")
add(F, "run_negative_workers", lambda tmp: ["run", "slider_crank", "--workers", "-1", "--out", str(tmp / "r")], 2,
    "workers = -1")


def lib(**kwargs):
    def action(tmp):
        simulate("slider_crank", t_end=kwargs.pop("t_end", 0.05), **kwargs)
    return action


L = "library arguments"
add(L, "t_end_as_text", lib(t_end="1"), ValueError, "t_end = '1'", "number")
add(L, "t_end_boolean", lib(t_end=True), ValueError, "t_end = True", "number")
add(L, "rtol_as_text", lib(rtol="1e-8"), ValueError, "rtol = '1e-8'", "number")
add(L, "max_evaluations_boolean", lib(max_evaluations=True), ValueError, "max_evaluations = True")
add(L, "max_evaluations_fraction", lib(max_evaluations=10.5), ValueError, "max_evaluations = 10.5", "whole number")
add(L, "method_as_list", lib(method=["baumgarte"]), ValueError, "method = ['baumgarte']")
add(L, "integrator_none", lib(integrator=None), ValueError, "integrator", "None", "valid choices")
add(L, "acceleration_solver_unknown", lib(acceleration_solver="lu"), ValueError, "acceleration_solver", "'lu'",
    "valid choices")
add(L, "progress_not_callable", lib(progress=1), ValueError, "progress = 1", "callable")
add(L, "friction_unknown", lib(friction="viscous"), ValueError, "friction", "'viscous'", "valid choices")
add(L, "friction_sgn_unknown", lib(friction="regularized", friction_sgn="cubic"), ValueError, "friction_sgn",
    "'cubic'", "valid choices")
add(L, "backend_unknown", lib(backend="gpu"), ValueError, "backend", "'gpu'", "valid choices")
add(L, "step_with_adaptive", lib(step=0.01), ValueError, "step = 0.01", "RK45", "adaptive")
add(L, "eps_with_exact", lib(friction="exact", friction_eps=0.1), ValueError, "friction_eps", "exact")
add(L, "sgn_with_sign", lib(friction="sign", friction_sgn="sat", integrator="RK4", step=1e-3), ValueError,
    "friction_sgn", "sign")
add(L, "output_step_longer_than_horizon", lib(output_step=1.0), ValueError, "output_step = 1", "t_end = 0.05")
add(L, "rk4_step_longer_than_horizon", lib(integrator="RK4", step=1.0), ValueError, "step = 1", "t_end = 0.05")
add(L, "check_not_boolean", lib(check="no"), ValueError, "check = 'no'")
add(L, "mechanism_number", lambda tmp: simulate(123), ValueError, "123", "EquationsOfMotion, a Mechanism or a "
    "mechanism name")
add(L, "variant_not_text", lib(variant=1), ValueError, "variant = 1")
add(L, "option_unknown", lib(method="baumgarte", omgea=10.0), ValueError, "omgea", "valid options")
add(L, "option_for_none", lib(omega=10.0), ValueError, "omega", "method 'none'")
add(L, "option_integer_float", lib(method="projection", max_iter=2.5), ValueError, "max_iter = 2.5", "whole number")
add(L, "option_name", lib(method="baumgarte", name="none"), ValueError, "name", "valid options")
add(L, "option_projects_off", lib(method="projection", projects=False), ValueError, "projects", "valid options")
add(L, "q0_text", lib(q0="abc"), ValueError, "q0", "'abc'")
add(L, "q0_complex", lib(q0=[0.1j, 0, 0, 0, 0, 0, 0, 0, 0]), ValueError, "q0", "complex")
add(L, "q0_wrong_length", lib(q0=[0.0, 0.0, 0.0]), ValueError, "q0", "(3,)", "2 coordinates")
add(L, "resistance_reading_unknown", lib(friction="exact", resistance_reading="maybe"), ValueError,
    "resistance_reading", "'maybe'", "valid choices")


# --- 2. work that cannot finish in reasonable time ---------------------------------------------------
W = "work bounds"
add(W, "plain_sgn_adaptive_chatters", sim("--variant", "slip_then_stick", "--friction", "sign", t_end="6"), 1,
    "chatter", "sign", "RK4", slow=True)
add(W, "plain_sgn_adaptive_library", lambda tmp: simulate("slider_crank", variant="slip_then_stick", t_end=6.0,
                                                          friction="sign"), RunBoundError, "chatter", "RK4", slow=True)
add(W, "plain_sgn_radau_chatters", sim("--variant", "slip_then_stick", "--friction", "sign", "--integrator", "Radau",
                                       t_end="6"), 1, "chatter")


def stiff_pendulum(k):
    """The pendulum held on its circle by a spring of stiffness k [N/m] as well (a very stiff but valid load)."""
    base = handwritten.cartesian_pendulum()

    def forces(t, q, qd):
        radius = np.hypot(*q)
        return np.array([0.0, -9.81]) - k * (radius - 1.0) * q / radius
    return dataclasses.replace(base, forces=forces, name="stiff_pendulum")


add(W, "very_stiff_spring", lambda tmp: simulate(stiff_pendulum(1e14), [0.6, -0.8], [0.8, 0.6], t_end=50.0,
                                                 method="baumgarte", omega=1e7, d=1.0),
    RunBoundError, "estimate", "max_evaluations", slow=True)
add(W, "sliding_mode_huge_gain", sim("--method", "sliding_mode", "--option", "Lambda=1e9", "--option", "K=1e9",
                                     mechanism="quick_return", t_end="20"), 1, "estimate", "max_evaluations", slow=True)


def case_folder(tmp, text, name="probe"):
    folder = tmp / "cases"
    folder.mkdir(exist_ok=True)
    (folder / f"{name}.toml").write_text(textwrap.dedent(text))
    return folder


def run_list(text, name="probe"):
    return lambda tmp: ["run", "--cases", str(case_folder(tmp, text, name)), "--out", str(tmp / "r")]


HEAD = '[study]\nsummary = "study.studies.sliding_mode"\n'
GROUP = '[[group]]\nname = "g"\nmechanism = "quick_return"\nt_end = 0.1\n'
add(W, "sweep_expands_to_1e12_cases",
    run_list(HEAD + GROUP + "".join(f"sweep.o{i} = [{', '.join(str(j) for j in range(100))}]\n" for i in range(6))),
    2, "probe.toml", "1e+12 cases", "max_cases")
add(W, "sweep_expands_to_1e5_cases",
    run_list(HEAD + GROUP + 'options = { method = "baumgarte" }\n'
             + "sweep.omega = [" + ", ".join(f"{1 + i}.0" for i in range(1000)) + "]\n"
             + "sweep.d = [" + ", ".join(f"{(1 + i) / 100}" for i in range(100)) + "]\n"), 2,
    "probe.toml", "100000 cases", "max_cases")


# --- 3. case lists and parameter files -------------------------------------------------------------
C = "case lists"
for name, body, fragments in (
        ("t_end_boolean", GROUP.replace("0.1", "true"), ("t_end = True", "number")),
        ("t_end_date", GROUP.replace("0.1", "1979-05-27"), ("t_end", "1979-05-27", "number")),
        ("t_end_text", GROUP.replace("0.1", '"0.1"'), ("t_end = '0.1'", "number")),
        ("options_text", GROUP + 'options = "fast"\n', ("options = 'fast'", "table")),
        ("sweep_text", GROUP + 'sweep = "omega"\n', ("sweep = 'omega'", "table")),
        ("sweep_value_table_without_label", GROUP + 'sweep.x = [1, "a"]\n', ("x: not an option",)),
        ("group_not_a_list_of_tables", 'group = "g"\n', ("group", "array of tables")),
        ("group_name_empty", GROUP.replace('"g"', '""'), ("name = ''",)),
        ("group_name_number", GROUP.replace('"g"', "5"), ("name = 5",)),
        ("group_duplicated", GROUP + GROUP, ("'g'", "unique")),
        ("mechanism_unknown", GROUP.replace("quick_return", "crank"), ("mechanism", "'crank'", "valid choices")),
        ("variant_unknown", GROUP + 'variant = "nope"\n', ("variant", "'nope'", "valid choices")),
        ("integrator_unknown", GROUP + 'options = { integrator = "RK99" }\n', ("integrator", "'RK99'", "valid choices")),
        ("option_unknown", GROUP + 'options = { method = "baumgarte", omgea = 10.0 }\n', ("omgea", "valid options")),
        ("option_boolean_number", GROUP + "options = { rtol = true }\n", ("rtol = True",)),
        ("option_text_number", GROUP + 'options = { rtol = "1e-8" }\n', ("rtol = '1e-8'", "number")),
        ("option_date", GROUP + "options = { output_step = 2020-01-01 }\n", ("output_step", "2020-01-01")),
        ("option_not_a_simulate_argument", GROUP + "options = { speed = 2.0 }\n", ("speed",)),
        ("exclude_removes_everything", GROUP + 'options = { method = "baumgarte" }\nsweep.omega = [1.0, 2.0]\n'
                                               'exclude = [{ method = "baumgarte" }]\n',
         ("exclude", "removes every case")),
        ("exclude_not_tables", GROUP + 'sweep.omega = [1.0]\nexclude = "omega"\n', ("exclude = 'omega'", "tables")),
        ("engine_number", GROUP + "engine = 5\n", ("engine = 5",)),
        ("expect_error_unknown", GROUP + 'expect_error = "NoSuchError"\n', ("expect_error", "'NoSuchError'")),
        ("summary_number", GROUP, ("summary = 5",)),
        ("description_number", GROUP, ("description = 5", "text")),
        ("section_order_boolean", GROUP, ("section_order = True", "number")),
        ("exudyn_h_text", GROUP + 'engine = "exudyn"\noptions = { h = "1e-3" }\n', ("h = '1e-3'", "number")),
        ("exudyn_h_zero", GROUP + 'engine = "exudyn"\noptions = { h = 0.0 }\n', ("h = 0", "> 0")),
        ("exudyn_solver_unknown", GROUP + 'engine = "exudyn"\noptions = { h = 1e-3, solver = "euler" }\n',
         ("solver", "'euler'", "valid choices")),
        ("sweep_duplicate_values", GROUP + 'options = { method = "baumgarte" }\nsweep.omega = [1.0, 1.0]\n',
         ("sweep.omega", "twice")),
        ("not_toml", "[study\n", ("probe.toml", "not valid TOML")),
        ("t_end_huge", GROUP.replace("0.1", "1e12"), ("t_end = 1e+12", "max_output_bytes")),
):
    head = {"summary_number": "[study]\nsummary = 5\n", "description_number": HEAD + "description = 5\n",
            "section_order_boolean": HEAD + 'section = "sliding_mode"\nsection_order = true\n',
            "not_toml": ""}.get(name, HEAD)
    text = body + head if name == "group_not_a_list_of_tables" else head + body   # a top-level key goes first
    add(C, name, run_list(text), 2, "probe.toml", *fragments)


P = "parameter files"


def param_edit(edit):
    """Load slider_crank/seed from a copy of reference/ whose slider_crank.toml is ``edit(text)``."""
    def action(tmp):
        folder = tmp / "reference"
        folder.mkdir()
        source = Path(__file__).parents[1] / "reference" / "slider_crank.toml"
        (folder / "slider_crank.toml").write_text(edit(source.read_text()))
        load_parameters("slider_crank", "seed", reference_dir=folder)
    return action


J1 = "[parameters.J1]\nvalue = 15.0\n"
for name, new, fragments in (
        ("value_boolean", "[parameters.J1]\nvalue = true\n", ("J1", "True", "number")),
        ("value_date", "[parameters.J1]\nvalue = 2020-01-01\n", ("J1", "2020-01-01", "number")),
        ("value_text", '[parameters.J1]\nvalue = "15"\n', ("J1", "'15'", "number")),
        ("value_nan", "[parameters.J1]\nvalue = nan\n", ("J1", "nan")),
        ("value_inf", "[parameters.J1]\nvalue = inf\n", ("J1", "inf")),
        ("value_negative", "[parameters.J1]\nvalue = -15.0\n", ("J1", "-15", "positive")),
        ("value_missing", "[parameters.J1]\n", ("J1", "value")),
        ("unit_empty", None, ("J1", "unit", "empty")),
        ("rule_unknown", None, ("J1", "rule", "'positiv'")),
        ("entry_text", None, ("J1", "table")),
):
    if name == "unit_empty":
        edit = (lambda text: text.replace('unit = "kg m^2"', 'unit = ""', 1))
    elif name == "rule_unknown":
        edit = (lambda text: text.replace('rule = "positive"', 'rule = "positiv"', 1))
    elif name == "entry_text":
        edit = (lambda text: text.replace(J1, '[parameters]\nJ1 = "fifteen"\n[parameters.J1x]\nvalue = 15.0\n', 1))
    else:
        edit = (lambda new: lambda text: text.replace(J1, new, 1))(new)
    add(P, f"parameter_{name}", param_edit(edit), ParameterError, "slider_crank.toml", *fragments)


# --- 4. saved files ----------------------------------------------------------------------------------
S = "saved files"


def saved(tmp):
    """A small saved result (slider-crank, 0.05 s) and its base path."""
    base = tmp / "saved" / "run"
    simulate("slider_crank", t_end=0.05, output_step=0.01).save(base)
    return base


def edit_json(change):
    def action(tmp):
        base = saved(tmp)
        path = base.with_name("run.json")
        data = json.loads(path.read_text())
        change(data)
        path.write_text(json.dumps(data))
        SimulationResult.load(base)
    return action


def _set(path, value):
    def change(data):
        node = data
        for key in path[:-1]:
            node = node[key]
        if value is KeyError:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return change


for name, path, value, fragments in (
        ("json_nfev_edited", ("stats", "nfev"), 1, ("run.json", "SHA-256")),
        ("json_cpu_edited", ("stats", "cpu_seconds"), 1e-9, ("run.json", "SHA-256")),
        ("json_meta_edited", ("meta", "integrator"), "DOP853", ("run.json", "SHA-256")),
        ("json_shape_edited", ("shape", "m"), 2, ("run.json", "SHA-256")),
        ("json_shape_missing", ("shape",), KeyError, ("run.json", "SHA-256")),
        ("json_energies_text", ("energies",), "kinetic", ("run.json", "SHA-256")),
        ("json_forces_missing", ("forces",), KeyError, ("run.json", "SHA-256")),
        ("json_checksum_removed", ("json_sha256",), KeyError, ("run.json", "checksum")),
):
    add(S, name, edit_json(_set(path, value)), ResultIntegrityError, *fragments)


def one_case(tmp):
    folder = tmp / "cases"
    folder.mkdir()
    (folder / "one.toml").write_text(HEAD + '[[group]]\nname = "g"\nmechanism = "quick_return"\nt_end = 0.1\n'
                                     'options = { integrator = "RK45", rtol = 1e-6, atol = 1e-8, output_step = 0.05 }\n')
    case = pl.load_case_list(folder / "one.toml").cases[0]
    store = pl.Store(tmp / "cache" / "runs")
    pl.run_cases([case], store, pl.InlineExecutor(), stream=io.StringIO())
    return case, store


def store_json_edit(change):
    def action(tmp):
        case, store = one_case(tmp)
        path = store.file(case, ".json")
        data = json.loads(path.read_text())
        change(data)
        path.write_text(json.dumps(data))
        store.load(case)
    return action


add(S, "store_json_nfev_edited", store_json_edit(_set(("stats", "nfev"), 7)), pl.CorruptResult, "SHA-256", "is not used")
add(S, "store_json_meta_edited", store_json_edit(_set(("meta", "rtol"), 1e-12)), pl.CorruptResult, "SHA-256")
add(S, "store_json_shape_missing", store_json_edit(_set(("shape",), KeyError)), pl.CorruptResult, "SHA-256")


def store_rerun_after_edit(tmp):
    case, store = one_case(tmp)
    path = store.file(case, ".json")
    data = json.loads(path.read_text())
    data["stats"]["nfev"] = 7
    path.write_text(json.dumps(data))
    log = io.StringIO()
    summary = pl.run_cases([case], store, pl.InlineExecutor(), stream=log)
    if summary.rejected and summary.computed == 1:
        raise ResultIntegrityError(log.getvalue())
    raise AssertionError(f"the edited result was reused: {summary}")


def recomputed_nfev(tmp):
    store = pl.Store(tmp / "cache" / "runs")
    case = pl.load_case_list(tmp / "cases" / "one.toml").cases[0]
    assert store.load(case).stats["nfev"] != 7


add(S, "store_edited_json_is_recomputed", store_rerun_after_edit, ResultIntegrityError,
    "saved result rejected, recomputing", "SHA-256", writes=True, then=recomputed_nfev)


def failed_save(tmp):
    """A save that fails while writing the JSON keeps the previous good result readable."""
    import study.integrity as integrity
    import study.results as results

    base = saved(tmp)
    before = SimulationResult.load(base)
    real = integrity.atomic_write

    def failing(path, text):
        if str(path).endswith(".json"):
            raise OSError(28, "No space left on device")
        real(path, text)
    try:
        integrity.atomic_write = results.atomic_write = failing
        simulate("slider_crank", t_end=0.1, output_step=0.01).save(base)
    except OSError as exc:
        failure = exc
    else:
        raise AssertionError("the failing save did not report its failure")
    finally:
        integrity.atomic_write = results.atomic_write = real
    after = SimulationResult.load(base)   # the previous result, intact
    assert len(after.t) == len(before.t) == 6
    raise failure


add(S, "failed_save_keeps_previous", failed_save, OSError, "previous result intact", writes=True)


def summary_tables(tmp):
    """The summary tables of a one-case study written by the pipeline, and the folder of its record."""
    folder = tmp / "cases"
    folder.mkdir()
    (folder / "sliding_mode.toml").write_text(
        HEAD + '[[group]]\nname = "reference"\nmechanism = "quick_return"\nt_end = 0.1\n'
        'options = { integrator = "RK45", rtol = 1e-6, atol = 1e-8, output_step = 0.05 }\n')
    record = tmp / "record"
    pl.run_pipeline(tmp / "reports", tmp / "cache", workers=1, folder=folder, stream=io.StringIO(),
                    record_root=record)
    written = [*(tmp / "reports" / "tables").glob("sliding_mode*.csv"),
               *(tmp / "reports" / "timing").glob("sliding_mode*.csv")]
    return record, max(written, key=lambda p: p.read_text().count("\n"))


def table_edit(edit):
    def action(tmp):
        record, path = summary_tables(tmp)
        path.write_text(edit(path.read_text()))
        pl.read_table(path, record)
    return action


def first_data_digit_changed(text):
    header, body = text.split("\n", 1)
    return header + "\n" + re.sub(r"\d", lambda m: "3" if m.group() == "2" else "2", body, count=1)


add(S, "table_digit_edited", table_edit(first_data_digit_changed), ResultIntegrityError,
    "sliding_mode_", "SHA-256")
add(S, "table_header_edited", table_edit(lambda text: text.replace(",", ";", 1)), ResultIntegrityError,
    "sliding_mode_", "SHA-256")
add(S, "table_emptied", table_edit(lambda text: ""), ResultIntegrityError, "sliding_mode_", "0 data rows")
add(S, "table_row_dropped", table_edit(lambda text: "".join(text.splitlines(keepends=True)[:-1])), ResultIntegrityError,
    "sliding_mode_", "data rows")


def record_garbage(tmp):
    record, path = summary_tables(tmp)
    for written in (record / "tables").glob("*.json"):
        written.write_text("{not json")
    pl.read_table(path, record)


add(S, "pipeline_record_garbage", record_garbage, ResultIntegrityError, ".json", "not valid JSON")


def load_not_a_result(tmp):
    (tmp / "x.csv").write_text("a,b\n1,2\n")
    SimulationResult.load(tmp / "x")


add(S, "load_without_json", load_not_a_result, ResultIntegrityError, "x.json", "missing")


# --- 5. a user's equations --------------------------------------------------------------------------
U = "user equations"
Q0, QD0 = [0.6, -0.8], [-0.8, -0.6]   # on the unit circle, moving tangentially towards the bottom


def pendulum(**changes):
    return dataclasses.replace(handwritten.cartesian_pendulum(), **changes)


def after(t_bad, good, bad):
    """A callable of (t, q, qd) that is ``good`` before t_bad and ``bad`` after."""
    return lambda t, q, qd: good(t, q, qd) if t < t_bad else bad(t, q, qd)


def mass_after(t_bad_y, bad):
    """A mass matrix that turns ``bad`` once the pendulum has fallen below y = t_bad_y."""
    return lambda q: np.eye(2) if q[1] > t_bad_y else bad(q)


def run_user(eom, t_end=1.0, **kw):
    return lambda tmp: simulate(eom, Q0, QD0, t_end=t_end, **kw)


gravity = handwritten.cartesian_pendulum().forces
add(U, "mass_indefinite_mid_run", run_user(pendulum(mass=mass_after(-0.95, lambda q: np.diag([1.0, -1.0])))),
    NonFiniteError, "mass(q)", "positive-definite", "t = ")
add(U, "mass_singular_mid_run", run_user(pendulum(mass=mass_after(-0.95, lambda q: np.diag([1.0, 0.0])))),
    NonFiniteError, "mass(q)", "singular", "t = ")
add(U, "mass_complex_at_start", run_user(pendulum(mass=lambda q: np.eye(2) * (1 + 0j))), EquationsError,
    "mass(q0)", "complex")
add(U, "mass_complex_mid_run", run_user(pendulum(mass=mass_after(-0.95, lambda q: np.eye(2) * (1 + 1e-3j))),
                                        check=False), NonFiniteError, "mass(q)", "complex", "t = ")
add(U, "forces_complex_mid_run", run_user(pendulum(forces=after(0.1, gravity, lambda t, q, qd: gravity(t, q, qd) + 0j))),
    NonFiniteError, "forces(t, q, qd)", "complex", "t = ")
add(U, "phi_complex", run_user(pendulum(phi=lambda q: np.array([0.5 * (q @ q - 1.0) + 0j]))), EquationsError,
    "phi(q0)", "complex")
add(U, "gamma_complex", run_user(pendulum(gamma=lambda q, qd: np.array([-(qd @ qd) + 0j]))), EquationsError,
    "gamma", "complex")


def raising(exc, t_bad=0.1):
    def forces(t, q, qd):
        if t >= t_bad:
            raise exc
        return gravity(t, q, qd)
    return forces


for name, exc in (("value_error", ValueError("table lookup out of range")), ("key_error", KeyError("k")),
                  ("zero_division", ZeroDivisionError("division by zero")), ("index_error", IndexError("idx"))):
    add(U, f"forces_raises_{name}_mid_run", run_user(pendulum(forces=raising(exc))), SimulationError,
        "forces(t, q, qd) raised", type(exc).__name__, "t = ")
add(U, "mass_raises_mid_run", run_user(pendulum(mass=mass_after(-0.95, lambda q: 1 / 0)), check=False),
    SimulationError, "mass(q) raised", "ZeroDivisionError", "t = ")
add(U, "phi_q_raises_mid_run",
    run_user(pendulum(phi_q=lambda q: q.reshape(1, 2).copy() if q[1] > -0.95 else {}["x"]), check=False),
    SimulationError, "phi_q(q) raised", "KeyError", "t = ")
add(U, "forces_wrong_shape_mid_run",
    run_user(pendulum(forces=after(0.1, gravity, lambda t, q, qd: np.zeros(3)))), SimulationError,
    "forces(t, q, qd)", "shape (3,)", "(2,)", "t = ")
add(U, "forces_returns_none", run_user(pendulum(forces=lambda t, q, qd: None)), EquationsError, "forces", "None")
add(U, "forces_returns_text", run_user(pendulum(forces=lambda t, q, qd: "down")), EquationsError, "forces", "'down'")
add(U, "mass_wrong_shape", run_user(pendulum(mass=lambda q: np.eye(3))), EquationsError, "mass(q0)", "(3, 3)",
    "(2, 2)")
add(U, "potential_raises", run_user(pendulum(potential_energy=lambda q: 1 / 0)), EquationsError,
    "potential_energy", "ZeroDivisionError")
add(U, "potential_not_scalar", run_user(pendulum(potential_energy=lambda q: q)), EquationsError,
    "potential_energy", "scalar")


# --- runner ------------------------------------------------------------------------------------------
def _files(root: Path) -> dict[str, tuple]:
    """Every file under root with its size and time, except the shared generated-code and numba caches."""
    return {str(p.relative_to(root)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in root.rglob("*") if p.is_file() and p.relative_to(root).parts[:2] not in
            (("cache", "codegen"), ("cache", "numba"))}


STOP_COUNT = re.compile(r"after (\d+) evaluations|(\d+) evaluations reached|after (\d+) steps|(\d+) steps in a row")
STOP_BOUND = re.compile(r"max_evaluations = ([0-9.e+]+)")


def stopped_by_count(message: str) -> tuple[str, str] | None:
    """None if a stopped run's message gives the count at which it stopped, within its evaluation bound; else the
    verdict ('bad' past the bound, 'weak' without a count) and why."""
    from study.reference_data import tolerance

    found = STOP_COUNT.search(message)
    if found is None:
        return "weak", f"a stopped run that does not give the count that stopped it: {' '.join(message.split())[:300]}"
    bound = STOP_BOUND.search(message)
    limit = float(bound.group(1).rstrip(".")) if bound else tolerance("max_evaluations")
    used = found.group(1) or found.group(2)
    if used is not None and int(used) > limit:
        return "bad", f"stopped after {used} evaluations, past its bound max_evaluations = {limit:g}"
    return None


def _stop_expected(t: Try) -> bool:
    """A try of the work bounds that expects a run stopped on its way (not refused before it starts)."""
    if t.group != "work bounds":
        return False
    return t.expect == 1 if isinstance(t.expect, int) else issubclass(t.expect, RunBoundError)


def judge(t: Try, tmp: Path) -> tuple[str, str]:
    """Run one try in ``tmp`` and grade it: ('good' | 'weak' | 'bad', what happened)."""
    stderr = io.StringIO()
    before = None
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            if isinstance(t.expect, int):
                argv = t.action(tmp)
                before = _files(tmp)
                try:
                    code = main(argv)
                except SystemExit as exc:   # argparse
                    code = exc.code
            else:
                try:
                    t.action(tmp)
                    code = None
                except Exception as exc:  # noqa: BLE001 - graded below
                    caught = exc
                else:
                    caught = None
    except Exception as exc:  # noqa: BLE001 - an exception out of main() is a traceback for the user
        return "bad", f"raw {type(exc).__name__}: {exc}".splitlines()[0][:300]
    if isinstance(t.expect, int):   # progress lines of a long run may come first; the error is one line
        lines = stderr.getvalue().strip().splitlines()
        message = "\n".join(lines[next((i for i, line in enumerate(lines) if line.startswith("error:")), 0):])
        if code == 0:
            return "bad", "accepted (exit 0)"
        if "Traceback" in message:
            return "bad", "traceback on stderr"
        if before is not None and not t.writes and _files(tmp) != before:
            return "bad", f"exit {code} but files were written: {sorted(set(_files(tmp)) - set(before))}"
        if code == t.expect and _stop_expected(t) and stopped_by_count(message):
            return stopped_by_count(message)
        missing = [f for f in t.fragments if f not in message]
        if code != t.expect or missing or len(message.splitlines()) != 1:
            return "weak", f"exit {code}, missing {missing}: {message[:300]}"
        return "good", message[:200]
    if caught is None:
        return "bad", "accepted (no error)"
    if not isinstance(caught, t.expect):
        return "bad", f"{type(caught).__name__}: {caught}".splitlines()[0][:300]
    message = str(caught)
    if _stop_expected(t) and stopped_by_count(message):
        return stopped_by_count(message)
    missing = [f for f in t.fragments if f not in message]
    if missing:
        return "weak", f"missing {missing}: {' '.join(message.split())[:300]}"
    if t.then is not None:
        t.then(tmp)
    return "good", " ".join(message.split())[:200]


def isolate(tmp: Path) -> None:
    """The try's folder as working directory and cache root; the generated code and numba's compiled
    kernels are shared with the usual cache (tests/shared_cache.py), so a try does not compile them again."""
    os.environ["STUDY_CACHE_DIR"] = str(linked_cache(tmp / "cache"))
    os.environ.pop("STUDY_TRACEBACK", None)
    os.chdir(tmp)


@pytest.fixture
def isolated(tmp_path, monkeypatch):
    # restored after the try; unchanged until isolate() links the configured cache (not the checkout's, when
    # STUDY_CACHE_DIR names another)
    monkeypatch.setenv("STUDY_CACHE_DIR", os.environ.get("STUDY_CACHE_DIR", ""))
    monkeypatch.chdir(tmp_path)
    isolate(tmp_path)
    return tmp_path


def test_the_probe_has_at_least_120_tries_with_unique_names():
    names = [(t.group, t.name) for t in TRIES]
    assert len(names) >= 120
    assert len(set(names)) == len(names)


def _raises(message):
    def action(tmp):
        raise RunBoundError(message)
    return action


@pytest.mark.parametrize("message, verdict", [
    ("x: stopped at t = 1 s after 150000 evaluations: ... above max_evaluations = 5e+06", "good"),
    ("x: 200 evaluations reached max_evaluations = 200 at t = 1 s", "good"),
    ("RK45 stopped at t = 1 s: 50 steps in a row below min_step = 1e-12 s", "good"),
    ("Radau stopped at t = 4.4 s after 3021 steps: Required step size is less than spacing", "good"),
    ("x: stopped at t = 1 s after 6000000 evaluations: ... above max_evaluations = 5e+06", "bad"),
    ("x: stopped after 300 evaluations, above max_evaluations = 200", "bad"),
    ("x: stopped at t = 1 s: the run is too slow", "weak")])
def test_a_stopped_run_is_judged_by_its_counts_not_its_seconds(message, verdict, tmp_path):
    """The judge grades a run bound by the count that stopped it: past the bound is bad, no count is weak."""
    attempt = Try("stop", W, _raises(message), RunBoundError, ())
    assert judge(attempt, tmp_path)[0] == verdict
    assert judge(dataclasses.replace(attempt, group="flags and options"), tmp_path)[0] == "good"


@pytest.mark.parametrize("attempt", [pytest.param(t, marks=pytest.mark.slow) if t.slow else t for t in TRIES],
                         ids=[f"{t.group}:{t.name}" for t in TRIES])
def test_every_try_is_good(attempt, isolated):
    verdict, what = judge(attempt, isolated)
    assert verdict == "good", what


def print_tally(chosen: list, grade_one) -> None:
    """Run each try in a folder of its own and print its verdict, then the tally in all and per group."""
    import tempfile
    from collections import Counter

    os.environ.pop("STUDY_TRACEBACK", None)
    tally: Counter = Counter()
    for t in chosen:
        with tempfile.TemporaryDirectory() as d:
            cwd, env = os.getcwd(), os.environ.get("STUDY_CACHE_DIR")
            isolate(Path(d))
            try:
                verdict, what = grade_one(t, Path(d))
            except Exception:  # noqa: BLE001
                verdict, what = "bad", traceback.format_exc().splitlines()[-1]
            finally:
                os.chdir(cwd)
                os.environ.pop("STUDY_CACHE_DIR") if env is None else os.environ.update(STUDY_CACHE_DIR=env)
        tally[verdict] += 1
        tally[(t.group, verdict)] += 1
        print(f"{verdict:4} {t.group:28} {t.name:44} {what}", flush=True)
    print({k: v for k, v in tally.items() if isinstance(k, str)}, len(chosen))
    for group in dict.fromkeys(t.group for t in chosen):
        print(f"  {group:28}", {v: tally[(group, v)] for v in ("good", "weak", "bad")})


if __name__ == "__main__":   # the tally: python tests/test_reliability_probe.py [name-fragment]
    print_tally([t for t in TRIES if len(sys.argv) < 2 or sys.argv[1] in t.name], judge)
