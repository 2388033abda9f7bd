"""Round three, group 'a user's file': see tests/round3/__init__.py."""

from __future__ import annotations

from round3 import add  # noqa: F401

G = "a user's file"
