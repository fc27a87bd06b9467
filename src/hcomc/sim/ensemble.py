"""Ensembles: many runs advanced together, in one process, parallel over cores.

Every run keeps its own state (:class:`hcomc.sim.step.state.Core`) and log; one compiled call
advances all of them, each run on one core (``numba.prange``), until each stops where it needs
Python (a decision event, an event-buffer flush, new random innovations, the end of a stage).
The Python side of each stopped run is then done in turn and the batch continues. A run's
result depends only on its own state, so an ensemble gives bit-identical results to running
each run alone, whatever the number of threads.

Use :func:`run_ensemble` on :class:`~hcomc.sim.engine.Simulation` objects::

    sims = [Simulation(config, seed) for seed in range(100)]
    logs = run_ensemble(sims)
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Sequence
from typing import Any

import numba
import numpy as np
from numba import prange
from numba.typed import List

from hcomc._jit import kernel
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog
from hcomc.sim.step.loop import run_steps
from hcomc.sim.step.state import DONE, STEP, CoreArrays


@kernel(parallel=True)
def _advance_batch(
    cores: list[CoreArrays], rngs: list[np.random.Generator], stops: np.ndarray,
    logging: np.ndarray, reasons: np.ndarray,
) -> None:  # fmt: skip
    """Advance every run to its stop (or until it needs Python), one thread per run."""
    for j in prange(len(cores)):
        k = np.int64(j)
        reasons[k] = run_steps(cores[k], stops[k], logging[k], rngs[k])


@kernel
def _advance_batch_serial(
    cores: list[CoreArrays], rngs: list[np.random.Generator], stops: np.ndarray,
    logging: np.ndarray, reasons: np.ndarray,
) -> None:  # fmt: skip
    """The same loop on the calling thread: no thread pool (safe in forked worker processes).

    A function of its own, not ``kernel(_advance_batch.py_func)``: numba's cache
    keys an entry by the function and its signature, not by ``parallel``, so one function
    compiled both ways loads whichever was cached first for both (the parallel ensemble then
    ran on one thread, or forked workers started a thread pool).
    """
    for k in range(len(cores)):
        reasons[k] = run_steps(cores[k], stops[k], logging[k], rngs[k])


_END = np.iinfo(np.int64).max  # "no goal": to the run's end


class TypedListCache:
    """Compiled (numba typed) lists of values taken from the same places across calls.

    Called again, only the places whose key changed are converted again, and a longer or
    shorter list of keys appends or drops places at the end, since each entry costs
    microseconds to convert (a learning environment passes its episodes' runs in the same
    places every step, with a few new episodes and a varying tail of twins). Keys are held
    weakly; the lists hold the values until the next call or :meth:`clear`. The lists are
    built and changed by cached compiled functions (:func:`_list_of` …): numba's own
    Python-side list methods compile anew in every process, about a second each.
    """

    def __init__(self) -> None:
        self._keys: list[weakref.ref[Any]] = []
        self._lists: tuple[List, ...] = ()

    def lists(self, keys: Sequence[Any], *columns: Callable[[Any], Any]) -> tuple[List, ...]:
        """One list per column function, entry k being ``column(keys[k])``."""
        if len(self._lists) != len(columns) or not self._keys or not keys:
            self._lists = tuple(_typed_list([column(key) for key in keys]) for column in columns)
            self._keys = [weakref.ref(key) for key in keys]
            return self._lists
        kept = min(len(keys), len(self._keys))
        for k in range(kept):
            key = keys[k]
            if self._keys[k]() is not key:
                self._keys[k] = weakref.ref(key)
                for values, column in zip(self._lists, columns, strict=True):
                    _list_set(values, k, column(key))
        for values, column in zip(self._lists, columns, strict=True):
            for _ in range(len(self._keys) - len(keys)):
                _list_pop(values)
            for key in keys[kept:]:
                _list_append(values, column(key))
        self._keys = self._keys[: len(keys)] + [weakref.ref(key) for key in keys[kept:]]
        return self._lists

    def clear(self) -> None:
        """Drop the lists (and the values they hold)."""
        self._keys, self._lists = [], ()


def _typed_list(values: list[Any]) -> List:
    """A compiled list of ``values`` (all of one type)."""
    if not values:
        return List()
    out = _list_of(values[0])
    for value in values[1:]:
        _list_append(out, value)
    return out


@kernel
def _list_of(first: Any) -> Any:
    """A compiled list holding ``first``, typed by it."""
    values = List()
    values.append(first)
    return values


@kernel
def _list_append(values: Any, item: Any) -> None:
    """Append ``item`` to a compiled list."""
    values.append(item)


@kernel
def _list_set(values: Any, k: int, item: Any) -> None:
    """Replace entry k of a compiled list."""
    values[k] = item


@kernel
def _list_pop(values: Any) -> None:
    """Drop the last entry of a compiled list."""
    values.pop()


_BATCH_LISTS = TypedListCache()  # the compiled loop's states and generators of the last batch


def _typed_lists(runs: list[Simulation]) -> tuple[List, List]:
    """The compiled loop's lists of the runs' states and generators (kept from the last
    batch: see :class:`TypedListCache`)."""
    cores, rngs = _BATCH_LISTS.lists(runs, lambda s: s.core, lambda s: s.rng)
    return cores, rngs


def run_ensemble(
    sims: Sequence[Simulation],
    *,
    threads: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> list[SimulationLog]:
    """Run every simulation to its end as one batch; their logs, in order.

    ``threads`` bounds the cores used (default: numba's, i.e. all; 1 runs the batch on the
    calling thread, which forked worker processes need); ``progress(done, total)`` is called
    as runs finish.
    """
    advance_ensemble(sims, None, threads=threads, progress=progress)
    _BATCH_LISTS.clear()  # a finished batch's states need not outlive it
    return [s.log for s in sims]


def advance_ensemble(
    sims: Sequence[Simulation],
    steps: Sequence[int] | None,
    *,
    until_key_vehicles: Sequence[bool] | None = None,
    threads: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    flush: bool = True,
) -> None:
    """Advance every simulation to its step in ``steps`` (warm-up included; None: to its end)
    as one batch: what :meth:`Simulation.run_to` does for one run (``until_key_vehicles``:
    its flag, per run).

    Learning environments use it to advance many episodes by one action period at once;
    ``flush=False`` leaves the events of the last compiled stretch in the runs' buffers (they
    reach the log at the next :meth:`Simulation.flush_events`, ``run_to`` or the run's end).
    """
    most = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    threads = most if threads is None else max(1, min(threads, most))
    runs = list(sims)
    n = len(runs)
    if n == 0:
        return
    goal = np.full(n, _END, dtype=np.int64) if steps is None else np.array(steps, dtype=np.int64)
    keys = np.zeros(n, dtype=bool)
    if until_key_vehicles is not None:
        keys[:] = until_key_vehicles
    batch = _Batch(runs, goal, keys)
    if not batch.going.any():
        return
    advance = _advance_batch_serial if threads == 1 else _advance_batch
    previous = threads
    if threads > 1:  # the thread pool is touched only when used (a forked child must not)
        previous = numba.get_num_threads()
        numba.set_num_threads(threads)
    chunks = numba.set_parallel_chunksize(1) if threads > 1 else 0  # runs differ in length
    try:
        reasons = np.empty(n, dtype=np.int64)
        while batch.going.any():
            stops = np.where(batch.going, np.minimum(batch.stop, goal), batch.step)
            advance(batch.cores, batch.rngs, stops, batch.logging, reasons)
            before = batch.going
            batch.resume(reasons)
            if progress is not None and (batch.going != before).any():
                progress(n - int(batch.going.sum()), n)
        if flush:
            for sim in runs:
                sim.flush_events()
    finally:
        if threads > 1:
            numba.set_parallel_chunksize(chunks)
            numba.set_num_threads(previous)


@kernel
def _step_indices(cores: list[CoreArrays], out: np.ndarray) -> None:
    """Every run's step counter (what :attr:`Simulation.step_index` reads, for all at once)."""
    for k in range(len(cores)):
        out[k] = cores[k].counters[STEP]


class _Batch:
    """Where each run of a batch stands: its step, the stop of its stage, whether it logs and
    whether it must go on, as arrays, so that a batch step costs Python only for the runs
    that stopped for it (a decision event, a flush, the end of a stage)."""

    def __init__(self, runs: list[Simulation], goal: np.ndarray, keys: np.ndarray) -> None:
        self.runs, self.goal, self.keys = runs, goal, keys
        self.cores, self.rngs = _typed_lists(runs)  # one batch, the same places
        n = len(runs)
        self.step = np.empty(n, dtype=np.int64)
        self.stop = np.array([r.stop_step for r in runs], dtype=np.int64)
        self.logging = np.array([r.logging for r in runs], dtype=np.bool_)
        self.finished = np.array([r.finished for r in runs], dtype=np.bool_)
        self.going = np.zeros(n, dtype=np.bool_)
        self._update()

    def _update(self) -> None:
        """``going``: not finished, short of its goal, and (with ``keys``) no key vehicles yet
        (what :meth:`Simulation.reached` says, run by run)."""
        _step_indices(self.cores, self.step)
        going = ~self.finished & (self.step < self.goal)
        for k in np.flatnonzero(going & self.keys).tolist():
            going[k] = not self.runs[k].key_groups
        self.going = going

    def resume(self, reasons: np.ndarray) -> None:
        """Hand each run that stopped for Python to :meth:`Simulation.resume` (a run that
        only reached its goal within its stage needs nothing)."""
        _step_indices(self.cores, self.step)
        python = self.going & ((reasons != DONE) | (self.step >= self.stop))
        for k in np.flatnonzero(python).tolist():
            run = self.runs[k]
            run.resume(int(reasons[k]))
            self.stop[k], self.logging[k] = run.stop_step, run.logging
            self.finished[k] = run.finished
        self._update()


__all__ = ["TypedListCache", "advance_ensemble", "run_ensemble"]
