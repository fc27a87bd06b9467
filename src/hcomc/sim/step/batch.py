"""Many runs advanced in one compiled call: the loop of :mod:`hcomc.sim.step.loop` over a
batch of run states, each run on one core (``numba.prange``) or all on the calling thread,
and the thread pool that call runs on.

The ensemble (:mod:`hcomc.sim.ensemble`) drives these from Python: it hands every run that
stopped for Python (a decision event, an event-buffer flush, new random innovations, the end
of a stage) to its :class:`~hcomc.sim.engine.Simulation` and calls them again.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numba
import numpy as np
from numba import prange

from hcomc._jit import kernel
from hcomc.sim.step.loop import run_steps
from hcomc.sim.step.state import STEP, CoreArrays

__all__ = [
    "advance_batch",
    "advance_batch_serial",
    "set_flags",
    "step_indices",
    "thread_count",
    "thread_pool",
]


@kernel(parallel=True)
def advance_batch(
    cores: list[CoreArrays], rngs: list[np.random.Generator], stops: np.ndarray,
    logging: np.ndarray, reasons: np.ndarray,
) -> None:  # fmt: skip
    """Advance every run to its stop (or until it needs Python), one thread per run."""
    for j in prange(len(cores)):
        k = np.int64(j)
        reasons[k] = run_steps(cores[k], stops[k], logging[k], rngs[k])


@kernel
def advance_batch_serial(
    cores: list[CoreArrays], rngs: list[np.random.Generator], stops: np.ndarray,
    logging: np.ndarray, reasons: np.ndarray,
) -> None:  # fmt: skip
    """The same loop on the calling thread: no thread pool (safe in forked worker processes).

    A function of its own, not ``kernel(advance_batch.py_func)``: numba's cache
    keys an entry by the function and its signature, not by ``parallel``, so one function
    compiled both ways loads whichever was cached first for both (the parallel ensemble then
    ran on one thread, or forked workers started a thread pool).
    """
    for k in range(len(cores)):
        reasons[k] = run_steps(cores[k], stops[k], logging[k], rngs[k])


@kernel
def set_flags(cores: list[CoreArrays], flag: int, values: np.ndarray) -> None:
    """Set flag ``flag`` of every run to its entry of ``values``."""
    for k in range(len(cores)):
        cores[k].flags[flag] = values[k]


@kernel
def step_indices(cores: list[CoreArrays], out: np.ndarray) -> None:
    """Every run's step counter (what :attr:`Simulation.step_index` reads, for all at once)."""
    for k in range(len(cores)):
        out[k] = cores[k].counters[STEP]


def thread_count(threads: int | None) -> int:
    """The threads a batch runs on: ``threads`` bounded by numba's (None: all of numba's)."""
    most = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    return most if threads is None else max(1, min(threads, most))


@contextmanager
def thread_pool(threads: int) -> Iterator[None]:
    """numba's thread pool set to ``threads`` threads, handing out one run at a time (runs
    differ in length), while the block runs; for one thread it is not touched (a forked
    child must not)."""
    if threads <= 1:
        yield
        return
    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    chunks = numba.set_parallel_chunksize(1)
    try:
        yield
    finally:
        numba.set_parallel_chunksize(chunks)
        numba.set_num_threads(previous)
