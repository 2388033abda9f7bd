"""Round three, group 'defaults and silent physics': see tests/round3/__init__.py."""

from __future__ import annotations

from round3 import add  # noqa: F401

G = "defaults and silent physics"
