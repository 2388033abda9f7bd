"""Test-session settings shared by every test module."""

import tomllib
from pathlib import Path

import pytest
from threadpoolctl import threadpool_limits

SLOW_TIER = Path(__file__).with_name("slow_tier.toml")


def slow_tier() -> set[str]:
    """The node ids tests/slow_tier.toml moves to the slow tier (make verify), each group with its reason."""
    with SLOW_TIER.open("rb") as f:
        return {test for group in tomllib.load(f)["group"] for test in group["tests"]}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Mark the tests of tests/slow_tier.toml ``slow`` before ``-k`` or ``-m`` select; a listed test missing from a
    file given whole (or in a folder given) is an error naming it, so the list cannot go stale silently."""
    listed = slow_tier()
    collected = {item.nodeid for item in items}
    for item in items:
        if item.nodeid in listed:
            item.add_marker(pytest.mark.slow)
    root = config.rootpath
    whole = {Path(a).resolve().relative_to(root).as_posix() for a in map(str, config.args)
             if "::" not in a and Path(a).resolve().is_relative_to(root)}
    files = {item.nodeid.split("::")[0] for item in items}
    stale = sorted(t for t in listed - collected if t.split("::")[0] in files
                   and any(w in (".", "") or t.startswith(w.rstrip("/") + "/") or t.split("::")[0] == w
                           for w in whole))
    if stale and not config.getoption("lf"):   # --lf collects a file's failed tests only
        raise pytest.UsageError(f"{SLOW_TIER.name} lists {stale[0]!r}, which is not a test (renamed or removed?)")


@pytest.fixture(autouse=True, scope="session")
def one_blas_thread():
    """One BLAS thread per test worker, as in the pipeline's workers (study.pipeline.execute): the two xdist
    workers have a core each, and OpenBLAS's own threads would oversubscribe them."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile`` in the order of tests/scheduling.py (long files first, the compilation beside work that
    needs none); any other ``--dist`` is xdist's own."""
    if config.getvalue("dist") != "loadfile":
        return None
    from scheduling import LeadFirstScheduling

    return LeadFirstScheduling(config, log)
