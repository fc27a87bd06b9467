"""The local worker pool: results in, processes let go; on an error, the rest cancelled."""

from __future__ import annotations

import math
import time
from concurrent.futures import Future
from typing import Any

import pytest

from hcomc.experiments.pool import local_pool


def test_a_finished_block_has_every_result_and_takes_no_more_tasks() -> None:
    with local_pool(2) as pool:
        futures = [pool.submit(math.factorial, n) for n in range(8)]
        results = [f.result() for f in futures]
    assert results == [math.factorial(n) for n in range(8)]
    with pytest.raises(RuntimeError, match="shutdown"):
        pool.submit(math.factorial, 3)


def _fail_after_the_first(futures: list[Future[None]], processes: list[Any]) -> None:
    """Ten tasks of 0.2 s on one process; the block raises once the first is done."""
    with local_pool(1) as pool:
        futures += [pool.submit(time.sleep, 0.2) for _ in range(10)]
        futures[0].result()
        processes += pool._processes.values()
        raise KeyError("a run failed")


def test_an_error_in_the_block_cancels_the_waiting_tasks_and_awaits_the_processes() -> None:
    futures: list[Future[None]] = []
    processes: list[Any] = []
    with pytest.raises(KeyError, match="a run failed"):
        _fail_after_the_first(futures, processes)
    # one process takes the tasks in order, at most two queued ahead of the one running
    assert sum(f.cancelled() for f in futures) >= 6
    assert all(f.done() for f in futures)
    assert len(processes) == 1
    assert not processes[0].is_alive()
