"""Local worker processes for runs: spawned afresh, and not waited for once their work is in.

A worker process's exit (its interpreter's teardown) takes about half a second. A pool used
as a plain ``with ProcessPoolExecutor(...)`` block makes its caller wait for it after the last
result is in; :func:`local_pool` lets the processes exit in the background while the caller
goes on (``hcomc reproduce`` computes its claims and report meanwhile).
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

__all__ = ["SPAWN", "local_pool"]

SPAWN = multiprocessing.get_context("spawn")
"""Worker processes start afresh: a fork would copy the parallel ensemble's thread pool."""


@contextmanager
def local_pool(workers: int) -> Iterator[ProcessPoolExecutor]:
    """A pool of ``workers`` spawned processes for the block's tasks.

    When the block ends normally, every result it waited for is in: the processes are told to
    exit and the caller goes on without waiting for them (the interpreter joins them at its
    own exit). When the block raises, the tasks not yet started are cancelled and the
    processes are awaited before the exception propagates."""
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=SPAWN)
    try:
        yield pool
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=False)
