"""Where cases run: a local process pool, this process (one worker), or a Dask cluster."""

from __future__ import annotations

import contextlib
import numbers
import os
import socket
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from typing import Iterator


class InlineExecutor(Executor):
    """Runs each submitted call at once in this process (workers=1: simple tracebacks, no pickling)."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        future: Future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller through the future
            if isinstance(exc, KeyboardInterrupt):
                raise
            future.set_exception(exc)
        return future


@contextlib.contextmanager
def make_executor(workers: int = 2, scheduler: str | None = None) -> Iterator[Executor]:
    """A local process pool with ``workers`` processes, or the Dask cluster at ``scheduler``.

    ``scheduler`` is a Dask scheduler address ('tcp://host:8786') or a ``distributed.Client``.
    """
    if scheduler is not None:
        try:
            from distributed import Client
        except ImportError as exc:  # the extra is optional; say how to get it
            raise RuntimeError("--scheduler needs Dask: pip install 'dask[distributed]'") from exc
        try:
            if not isinstance(scheduler, Client):
                _probe(scheduler)
            client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
        except OSError as exc:  # unreachable or refusing: name the address, no traceback
            raise OSError(f"scheduler {scheduler!r} cannot be reached: {exc}") from None
        try:
            yield client.get_executor(pure=False)
        finally:
            if client is not scheduler:
                client.close()
        return
    if isinstance(workers, bool) or not isinstance(workers, numbers.Integral) or workers < 1:
        raise ValueError(f"workers = {workers!r} must be an integer >= 1")
    workers = int(workers)   # numpy's integers too
    if workers == 1:
        yield InlineExecutor()
        return
    with ProcessPoolExecutor(max_workers=workers) as pool:
        yield pool


def _probe(address: str) -> None:
    """OSError at once if nothing listens at a 'tcp://host:port' address.

    Dask's Client retries a refused connection until its connect timeout (30 s by default); one TCP
    connection attempt, bounded by ``scheduler_probe_timeout`` (reference/tolerances.toml), tells a
    refusing or unroutable address apart first. Other address forms are left to Dask.
    """
    from urllib.parse import urlsplit

    from study.reference_data import tolerance

    parts = urlsplit(address)
    if parts.scheme != "tcp" or parts.hostname is None or parts.port is None:
        return
    with socket.create_connection((parts.hostname, parts.port), timeout=tolerance("scheduler_probe_timeout")):
        pass


def environment_workers() -> int:
    """Default worker count: $STUDY_WORKERS, else the number of CPUs this process may use."""
    env = os.environ.get("STUDY_WORKERS")
    if env:
        if not env.isdigit() or int(env) < 1:
            raise ValueError(f"STUDY_WORKERS = {env!r} must be a positive integer")
        return int(env)
    return max(len(os.sched_getaffinity(0)), 1)
