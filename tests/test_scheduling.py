"""tests/scheduling.py and tests/slow_tier.toml: every file they name exists, so nothing renamed is silently moved."""

from pathlib import Path

from scheduling import LEAD, UNITS

ROOT = Path(__file__).resolve().parents[1]


def test_every_named_file_exists_and_every_unit_is_led():
    for path in [p for p in LEAD if p not in UNITS.values()] + list(UNITS):
        assert (ROOT / path).is_file(), f"{path} in tests/scheduling.py does not exist"
    for unit in set(UNITS.values()):
        assert unit in LEAD, f"the unit {unit} is not in LEAD"
        assert (ROOT / f"{unit}.py").is_file(), f"the unit {unit} names no shared module"


def test_every_slow_tier_group_gives_its_reason_and_names_existing_files():
    """tests/slow_tier.toml: each group says why it is slow and what stands for it in make test; a test it names
    that is gone from a collected file stops the collection (conftest.pytest_collection_modifyitems)."""
    import tomllib

    from conftest import SLOW_TIER, slow_tier

    groups = tomllib.loads(SLOW_TIER.read_text())["group"]
    assert groups and all(g["reason"].strip() and g["in_make_test"].strip() and g["tests"] for g in groups)
    for test in slow_tier():
        assert (ROOT / test.split("::")[0]).is_file(), f"{test} in {SLOW_TIER.name}: no such file"
