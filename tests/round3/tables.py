"""Round three, group 'tables': see tests/round3/__init__.py."""

from __future__ import annotations

from round3 import add  # noqa: F401

G = "tables"
