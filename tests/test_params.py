"""Parameter files: every bad input is named in one clear error."""

import copy
import math
import tomllib
from pathlib import Path

import pytest

from study.mechanisms import CATALOGUE, description
from study.params import REFERENCE_DIR, ParameterError, available_mechanisms, load_parameters, parse_parameters


def raw(mechanism):
    with open(REFERENCE_DIR / f"{mechanism}.toml", "rb") as fh:
        return tomllib.load(fh)


def parse(doc, mechanism="slider_crank", variant="seed"):
    return parse_parameters(doc, mechanism, variant, Path(f"{mechanism}.toml"), CATALOGUE[mechanism].parameters)


@pytest.mark.parametrize("mechanism,variants", [
    ("slider_crank", {"seed", "sustained_sliding", "slip_then_stick", "alpha_damping"}),
    ("quick_return", {"seed", "smooth_cutting", "guide_friction"}),
])
def test_variants_load(mechanism, variants):
    for v in variants:
        ps = load_parameters(mechanism, v)
        assert ps.variant == v and len(ps.sha256) == 64
        for name in ps.sources:
            assert ps.sources[name] and ps.units[name] is not None


def test_variant_overrides_and_hash():
    seed = load_parameters("slider_crank", "seed")
    sliding = load_parameters("slider_crank", "sustained_sliding")
    stick = load_parameters("slider_crank", "slip_then_stick")
    assert (seed.M, sliding.M, stick.M) == (0.5, 10.0, 5.0)
    assert len({seed.sha256, sliding.sha256, stick.sha256}) == 3
    assert load_parameters("quick_return", "seed").cutting_law == "on_off"
    assert load_parameters("quick_return", "smooth_cutting").cutting_law == "smooth"


def test_frozen():
    ps = load_parameters("quick_return")
    with pytest.raises(Exception):
        ps.values.l1 = 2.0


def test_missing_key_named():
    doc = raw("slider_crank")
    del doc["parameters"]["J2"]
    with pytest.raises(ParameterError, match=r"parameters\.J2 = None: missing"):
        parse(doc)


def test_unknown_key_named():
    doc = raw("slider_crank")
    doc["parameters"]["l9"] = {"value": 1.0, "unit": "m", "source": "x"}
    with pytest.raises(ParameterError, match=r"parameters\.l9 .*unknown parameter"):
        parse(doc)


@pytest.mark.parametrize("change,message", [
    ("missing", r"parameters\.J2 = None: missing \(the description of slider_crank needs it"),
    ("unknown", r"parameters\.l9 = 1\.0: unknown parameter for slider_crank"),
])
def test_a_set_read_without_the_names_is_checked_before_it_is_described(change, message):
    # without required= the file is its own schema; the catalogue checks the names before describing the set
    doc = raw("slider_crank")
    if change == "missing":
        del doc["parameters"]["J2"]
    else:
        doc["parameters"]["l9"] = {"value": 1.0, "unit": "m", "source": "x", "doc": "x", "rule": "positive"}
    ps = parse_parameters(doc, "slider_crank", "seed", Path("slider_crank.toml"))
    with pytest.raises(ParameterError, match=message):
        description(ps)


@pytest.mark.parametrize("key,value,rule", [
    ("m2", -0.1, "must be > 0"),
    ("l2", 0.0, "must be > 0"),
    ("J1", math.inf, "must be finite"),
    ("J2", math.nan, "must be finite"),
    ("c2", "5", "must be a number, got str"),
    ("m3", True, "must be a number, got bool"),
])
def test_bad_values_named(key, value, rule):
    doc = raw("slider_crank")
    doc["parameters"][key]["value"] = value
    with pytest.raises(ParameterError) as info:
        parse(doc)
    msg = str(info.value)
    assert "slider_crank.toml" in msg and f"parameters.{key} = {value!r}" in msg and rule in msg


def test_bad_variant_value_named():
    doc = raw("slider_crank")
    doc["variants"]["seed"]["M"] = "ten"
    with pytest.raises(ParameterError, match=r"variants\.seed\.M = 'ten': must be a number"):
        parse(doc)


def test_unknown_variant_lists_choices():
    with pytest.raises(ParameterError, match="valid choices: seed"):
        load_parameters("slider_crank", "nope")


def test_all_problems_in_one_error():
    doc = copy.deepcopy(raw("quick_return"))
    doc["parameters"]["m1"]["value"] = -1.0
    del doc["parameters"]["h2"]
    doc["parameters"]["cutting_law"]["value"] = "sometimes"
    with pytest.raises(ParameterError) as info:
        parse(doc, "quick_return")
    msg = str(info.value)
    assert "parameters.m1" in msg and "parameters.h2" in msg and "must be one of on_off, smooth" in msg


def test_entry_needs_unit_and_source():
    doc = raw("quick_return")
    del doc["parameters"]["l1"]["source"]
    with pytest.raises(ParameterError, match=r"parameters\.l1 .*missing keys"):
        parse(doc, "quick_return")


# --- a file that extends another ([meta] extends) ---------------------------------------------------------------
def test_extending_file_holds_the_base_entries_and_variants_as_they_are():
    """reference/slider_crank_pins.toml extends slider_crank.toml: every entry and variant of the paper's file, with
    its value, unit and source, and its own pin entries; its hash covers both."""
    from study.params import available_variants

    assert available_variants("slider_crank_pins") == available_variants("slider_crank")
    for variant in available_variants("slider_crank"):
        base, ext = load_parameters("slider_crank", variant), load_parameters("slider_crank_pins", variant)
        for name in vars(base.values):
            assert getattr(ext.values, name) == getattr(base.values, name), (variant, name)
            assert ext.units[name] == base.units[name] and ext.sources[name] == base.sources[name]
        assert {"r_O", "mu_B"} <= set(ext.sources) and ext.variant_note == base.variant_note
        assert ext.sha256 != base.sha256 and ext.initial != base.initial


def _entry(value):
    return f'value = {value}\nunit = "-"\nsource = "test"\nrule = "finite"\ndoc = "test"\n'


def _file(folder, name, extends=None, entries=None, variants=None):
    meta = f'[meta]\nmechanism = "{name}"\n' + (f'extends = "{extends}"\n' if extends else "")
    text = [meta] + [f"[parameters.{k}]\n{_entry(v)}" for k, v in (entries or {}).items()]
    text.append('[initial_conditions.printed]\nq = [0.0]\nqd = [0.0]\nsource = "test"\n'
                '[initial_conditions.consistent]\nindependent = [0]\nq_independent = [0.0]\nqd_independent = [0.0]\n'
                'branch = "none"\nsource = "test"\n')
    for v, overrides in (variants or {}).items():
        text.append(f"[variants.{v}]\nnote = \"{v}\"\n" + "".join(f"{k} = {x}\n" for k, x in overrides.items()))
    (folder / f"{name}.toml").write_text("\n".join(text))


def test_extending_file_adds_entries_and_variants_of_its_own(tmp_path):
    _file(tmp_path, "base_m", entries={"a": 1.0, "b": 2.0}, variants={"seed": {}, "big": {"a": 10.0}})
    _file(tmp_path, "ext_m", extends="base_m", entries={"c": 3.0}, variants={"big_c": {"c": 30.0, "b": 20.0}})
    from study.params import available_variants

    assert available_variants("ext_m", tmp_path) == ("seed", "big", "big_c")
    values = {v: vars(load_parameters("ext_m", v, reference_dir=tmp_path).values) for v in ("seed", "big", "big_c")}
    assert values == {"seed": {"a": 1.0, "b": 2.0, "c": 3.0}, "big": {"a": 10.0, "b": 2.0, "c": 3.0},
                      "big_c": {"a": 1.0, "b": 20.0, "c": 30.0}}


@pytest.mark.parametrize("case, message", [
    ("entry", r"parameters\.a = '\.\.\.': is also an entry of base_m\.toml, which this file extends: the file "
              r"inherits it as it is and cannot replace it \(a variant of its own changes a value\)"),
    ("variant", r"variants\.big = '\.\.\.': is also a variant of base_m\.toml, which this file extends"),
    ("missing", r"meta\.extends = 'nowhere': the file it names cannot be read: .*nowhere\.toml: parameter file not "
                r"found"),
    ("cycle", r"meta\.extends = 'ext_m': the files extend each other in a cycle: ext_m -> base_m -> ext_m"),
])
def test_extending_file_refuses_replacements_missing_bases_and_cycles(tmp_path, case, message):
    _file(tmp_path, "base_m", extends="ext_m" if case == "cycle" else None, entries={"a": 1.0},
          variants={"seed": {}, "big": {"a": 10.0}})
    _file(tmp_path, "ext_m", extends="nowhere" if case == "missing" else "base_m",
          entries={"a": 5.0} if case == "entry" else {"c": 3.0}, variants={"big": {}} if case == "variant" else None)
    with pytest.raises(ParameterError, match=message):
        load_parameters("ext_m", "seed", reference_dir=tmp_path)


def test_catalogue_names_the_parameter_files():
    """Every registered description has its parameter file, and every parameter file of the study its description."""
    assert set(CATALOGUE) == set(available_mechanisms())
