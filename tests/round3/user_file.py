"""Round three, group 'a user's file': see tests/round3/__init__.py.

A user's mechanism file (``describe(ps)`` in ``<name>.py``, its parameters in ``<name>.toml`` beside it) that is
wrong fails in the user's terms: one message naming the file, the function, the line and the cause, through
``study.load_mechanism`` and through ``python -m study simulate|validate|describe <file>`` (exit 2, one line, no
traceback). Each try writes its own file into the try's folder; line numbers are counted from the text written here.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

from round3 import OK, add
from study.errors import UserFileError

G = "a user's file"

TOML = """\
[meta]
mechanism = "{name}"
paper = "none: a try of the reliability catalogue"
description = "a uniform bar on a ground pin, vertical plane"
{parameters}
[initial_conditions.printed]
q = [0.5]
qd = [0.0]
source = "the try's own"

[initial_conditions.consistent]
independent = [0]
q_independent = [0.5]
qd_independent = [0.0]
branch = "none: one coordinate"
source = "the try's own"

[variants.seed]
note = "the try's set"
"""
PARAMETER = """
[parameters.{key}]
value = {value}
unit = "-"
source = "the try's own"
rule = "positive"
doc = "{key}"
"""
VALUES = {"m": 1.0, "L": 0.5, "g": 9.81}

# A valid description: line numbers below count from its first line.
GOOD = """\
import study


def describe(ps):
    v = ps.values
    d = study.Description("pend", ["th"], {"m": v.m, "L": v.L, "g": v.g})
    p = d.p
    d.ground("O", 0, 0)
    d.body("bar", p.m, p.m * p.L ** 2 / 12, {"top": (0, p.L / 2)}, angle=d.q[0])
    d.revolute("pin", (study.GROUND, "O"), ("bar", "top"))
    d.gravity(p.g)
    return d
"""


def write(tmp: Path, source: str = GOOD, name: str = "pend", values=VALUES, toml: bool = True) -> Path:
    """``<tmp>/<name>.py`` with ``source`` and (``toml``) its parameter file with ``values``; returns the .py path."""
    path = tmp / f"{name}.py"
    path.write_text(textwrap.dedent(source))
    if toml:
        params = "".join(PARAMETER.format(key=k, value=v if not isinstance(v, str) else f'"{v}"')
                         for k, v in values.items())
        (tmp / f"{name}.toml").write_text(TOML.format(name=name, parameters=params))
    return path


def line_of(source: str, text: str) -> str:
    """'line N' of the first line of ``source`` holding ``text``."""
    return f"line {next(i for i, s in enumerate(source.splitlines(), 1) if text in s)}"


def library(source=GOOD, **kw):
    def action(tmp):
        import study

        study.load_mechanism(write(tmp, source, **kw))
    return action


def command(verb, source=GOOD, *tail, **kw):
    def action(tmp):
        path = write(tmp, source, **kw)
        extra = ("--t-end", "0.05") if verb == "simulate" else ("--t-end", "0.1") if verb == "validate" else ()
        out = ("--out", str(tmp / "out" / "x")) if verb in ("simulate", "validate") else ()
        return [verb, str(path), *extra, *tail, *out]
    return action


RAISES = GOOD.replace("    p = d.p\n", "    p = d.p\n    scale = 1 / 0\n")
add(G, "describe_raises_library", library(RAISES), UserFileError, "pend.py", "describe", line_of(RAISES, "1 / 0"),
    "ZeroDivisionError", "division by zero")
add(G, "describe_raises_validate", command("validate", RAISES), 2, "pend.py", "describe", line_of(RAISES, "1 / 0"),
    "ZeroDivisionError")
HELPER = GOOD.replace("    p = d.p\n", "    p = d.p\n    helper()\n") + "\n\ndef helper():\n    raise KeyError('length')\n"
add(G, "describe_raises_in_a_helper_describe_cmd", command("describe", HELPER), 2, "pend.py", "helper",
    line_of(HELPER, "raise KeyError"), "KeyError", "'length'")
for what, value, fragment in (("int", "42", "returned an int, not a study.Description"),
                              ("none", "None", "returned None, not a study.Description"),
                              ("dict", "{'m': 1}", "returned a dict, not a study.Description")):
    source = GOOD.replace("    return d\n", f"    return {value}\n")
    add(G, f"describe_returns_{what}_library", library(source), UserFileError, "pend.py", "describe(ps)", fragment)
    add(G, f"describe_returns_{what}_simulate", command("simulate", source), 2, "pend.py", fragment)
add(G, "describe_returns_a_mechanism", library(GOOD.replace("    return d\n", "    return study.Mechanism(d, ps)\n")),
    UserFileError, "pend.py", "returned a study.Mechanism, not a study.Description")
add(G, "describe_returns_a_builder",
    library(GOOD.replace("    return d\n", "    return study.model.builder.MechanismBuilder('pend', ['th'], {'m': 1.0})\n")),
    UserFileError, "pend.py", "returned a study.MechanismBuilder, not a study.Description")
SYNTAX = GOOD.replace("    p = d.p\n", "    p = d.p(\n")
add(G, "syntax_error_validate", command("validate", SYNTAX), 2, "pend.py", "line 7", "syntax")
add(G, "syntax_error_library", library(SYNTAX), UserFileError, "pend.py", "line 7", "syntax")
add(G, "indentation_error_simulate", command("simulate", GOOD.replace("    p = d.p\n", "  p = d.p\n")), 2,
    "pend.py", "line 7")
add(G, "import_error_at_module_level", command("simulate", "import no_such_package_xyz\n" + GOOD), 2, "pend.py",
    "line 1", "no_such_package_xyz")
add(G, "missing_toml_simulate", command("simulate", GOOD, toml=False), 2, "pend.toml", "does not exist")
add(G, "missing_toml_library", library(GOOD, toml=False), ValueError, "pend.toml", "does not exist")
add(G, "parameter_missing_from_toml", command("simulate", GOOD, values={"m": 1.0, "g": 9.81}), 2, "pend.py",
    "'L'", "pend.toml", line_of(GOOD, "v.L"))
add(G, "parameter_missing_library", library(GOOD, values={"m": 1.0, "g": 9.81}), UserFileError, "'L'", "pend.toml")
add(G, "parameters_listed_but_missing",
    library("PARAMETERS = ('m', 'L', 'g')\n" + GOOD, values={"m": 1.0, "g": 9.81}), ValueError, "pend.toml",
    "parameters.L", "missing")
add(G, "parameter_of_the_wrong_type", command("simulate", GOOD, values={"m": 1.0, "L": "long", "g": 9.81}), 2,
    "pend.toml", "parameters.L", "'long'", "number")
add(G, "ground_point_twice", library(GOOD.replace('    d.ground("O", 0, 0)\n',
                                                  '    d.ground("O", 0, 0)\n    d.ground("O", 1, 0)\n')),
    UserFileError, "pend.py", "ground point 'O'", "twice", "line 9")
add(G, "empty_file", command("validate", ""), 2, "pend.py", "describe(ps)")
add(G, "describe_not_a_function", library("describe = 5\n"), UserFileError, "pend.py", "describe", "not a function")
add(G, "describe_without_the_parameter_set", library(GOOD.replace("def describe(ps):", "def describe():")),
    UserFileError, "pend.py", "describe()", "line 4", "describe(ps)")
add(G, "file_does_not_exist", lambda tmp: ["simulate", str(tmp / "nope.py"), "--t-end", "0.05", "--out",
                                           str(tmp / "x")], 2, "nope.py", "does not exist")
add(G, "folder_given_as_the_file", lambda tmp: (tmp / "mech.py").mkdir() or
    ["validate", str(tmp / "mech.py"), "--out", str(tmp / "x")], 2, "mech.py", "folder")
add(G, "file_without_py_suffix", lambda tmp: write(tmp).rename(tmp / "pend.txt") and
    ["simulate", str(tmp / "pend.txt"), "--t-end", "0.05", "--out", str(tmp / "x")], 2, "pend.txt")
GUESS = GOOD + "\n\ndef initial_guess(ps):\n    return ps.values.q0\n"
add(G, "initial_guess_raises", library(GUESS), UserFileError, "pend.py", "initial_guess", line_of(GUESS, "q0"), "'q0'")
add(G, "user_file_named_like_a_study_mechanism", library(GOOD, name="four_bar"), UserFileError, "four_bar.py",
    "study's mechanism 'four_bar'", "rename")
add(G, "user_file_unknown_variant", command("simulate", GOOD, "--variant", "nope"), 2, "pend.toml", "'nope'",
    "seed")


def good_runs(tmp):
    from study.results import SimulationResult

    r = SimulationResult.load(tmp / "out" / "x")
    assert r.meta["mechanism"] == "pend" and r.q.shape[1] == 1, r.meta


add(G, "good_file_simulates", command("simulate", GOOD), OK, cli=True, then=good_runs)


def missing_reference_dir(tmp):
    from study.params import load_parameters

    load_parameters("slider_crank", reference_dir=tmp / "no_such_folder")


add(G, "missing_reference_dir", missing_reference_dir, ValueError, "no_such_folder", "does not exist")


def reference_dir_is_a_file(tmp):
    from study.params import load_parameters

    (tmp / "notes.txt").write_text("x")
    load_parameters("slider_crank", reference_dir=tmp / "notes.txt")


add(G, "reference_dir_is_a_file", reference_dir_is_a_file, ValueError, "notes.txt", "not a folder")


def toml_names_another_mechanism(tmp):
    import study

    path = write(tmp)
    toml = tmp / "pend.toml"
    toml.write_text(toml.read_text().replace('mechanism = "pend"', 'mechanism = "pendulum"'))
    study.load_mechanism(path)


add(G, "toml_meta_names_another_mechanism", toml_names_another_mechanism, ValueError, "pend.toml",
    "mechanism = 'pendulum'", "'pend'")
