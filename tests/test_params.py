"""Parameter files: every bad input is named in one clear error."""

import copy
import math
import tomllib
from pathlib import Path

import pytest

from study.params import REFERENCE_DIR, ParameterError, load_parameters, parse_parameters


def raw(mechanism):
    with open(REFERENCE_DIR / f"{mechanism}.toml", "rb") as fh:
        return tomllib.load(fh)


def parse(doc, mechanism="slider_crank", variant="seed"):
    return parse_parameters(doc, mechanism, variant, Path(f"{mechanism}.toml"))


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
