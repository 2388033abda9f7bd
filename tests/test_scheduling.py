"""tests/scheduling.py: every file it names exists, so a renamed file is not silently scheduled last."""

from pathlib import Path

from scheduling import LEAD, UNITS

ROOT = Path(__file__).resolve().parents[1]


def test_every_named_file_exists_and_every_unit_is_led():
    for path in [p for p in LEAD if p not in UNITS.values()] + list(UNITS):
        assert (ROOT / path).is_file(), f"{path} in tests/scheduling.py does not exist"
    for unit in set(UNITS.values()):
        assert unit in LEAD, f"the unit {unit} is not in LEAD"
        assert (ROOT / f"{unit}.py").is_file(), f"the unit {unit} names no shared module"
