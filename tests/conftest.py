"""Test-session settings shared by every test module."""

import pytest
from threadpoolctl import threadpool_limits


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
