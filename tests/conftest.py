"""Test-session settings shared by every test module."""

import pytest
from threadpoolctl import threadpool_limits


@pytest.fixture(autouse=True, scope="session")
def one_blas_thread():
    """One BLAS thread per test worker, as in the pipeline's workers (study.pipeline.execute): the two xdist
    workers have a core each, and OpenBLAS's own threads would oversubscribe them."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield
