"""A private cache root whose generated code and compiled kernels are the usual cache's (both are checked on load):
a test that needs its own cache root (its saved runs, its own folder) does not generate and compile again."""

from __future__ import annotations

from pathlib import Path


def linked_cache(root: Path) -> Path:
    """``root`` made, with ``codegen`` and ``numba`` linked to the usual cache's; returns ``root``."""
    from study.model.compile import cache_dir

    shared = cache_dir()
    root.mkdir(parents=True)
    for name in ("codegen", "numba"):
        (shared / name).mkdir(parents=True, exist_ok=True)
        (root / name).symlink_to(shared / name)
    return root
