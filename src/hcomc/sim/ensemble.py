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

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from hcomc.sim.log import SimulationLog
from hcomc.sim.step.batch import (
    advance_batch,
    advance_batch_serial,
    set_flags,
    step_indices,
    thread_count,
    thread_pool,
)
from hcomc.sim.step.state import DONE, STOP_AT_KEYS
from hcomc.sim.typed_lists import TypedListCache

if TYPE_CHECKING:
    from numba.typed import List

_END = np.iinfo(np.int64).max  # "no goal": to the run's end


class EnsembleRun(Protocol):
    """What an ensemble needs of a run (:class:`~hcomc.sim.engine.Simulation` is one): its
    compiled state and generator, where it stands, and its Python side for a stop. Stated
    here, not imported, so that the engine can batch its runs through this module
    (:meth:`Simulation.run_together`) without an import cycle."""

    core: Any  # hcomc.sim.step.state.Core
    rng: Any  # its generator (numpy's, as the compiled loop draws from it)
    log: SimulationLog

    @property
    def key_groups(self) -> dict[int, Any]:
        """Its key groups by ramp vehicle (:attr:`Simulation.key_groups`)."""
        ...

    @property
    def listeners(self) -> Sequence[Any]:
        """Its step listeners (:mod:`hcomc.interface.listener`): a batch takes none."""
        ...

    @property
    def finished(self) -> bool: ...

    @property
    def stop_step(self) -> int: ...

    @property
    def logging(self) -> bool: ...

    def resume(self, reason: int) -> None: ...

    def flush_events(self) -> None: ...


_BATCH_LISTS = TypedListCache()  # the compiled loop's states and generators of the last batch


def _typed_lists(runs: list[EnsembleRun]) -> tuple[List, List]:
    """The compiled loop's lists of the runs' states and generators (kept from the last
    batch: see :class:`~hcomc.sim.typed_lists.TypedListCache`)."""
    cores, rngs = _BATCH_LISTS.lists(runs, lambda s: s.core, lambda s: s.rng)
    return cores, rngs


def run_ensemble(
    sims: Sequence[EnsembleRun],
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
    sims: Sequence[EnsembleRun],
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
    threads = thread_count(threads)
    runs = list(sims)
    if any(run.listeners for run in runs):
        raise ValueError("a run with step listeners advances alone (they act between its "
                         "steps, in Python): run it with its own run()")  # fmt: skip
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
    advance = advance_batch_serial if threads == 1 else advance_batch
    set_flags(batch.cores, STOP_AT_KEYS, keys.astype(np.int64))  # key groups found compiled
    try:
        with thread_pool(threads):
            reasons = np.empty(n, dtype=np.int64)
            while batch.going.any():
                stops = np.where(batch.going, np.minimum(batch.stop, goal), batch.step)
                advance(batch.cores, batch.rngs, stops, batch.logging, reasons)
                before = batch.going
                batch.resume(reasons)
                if progress is not None and (batch.going != before).any():
                    progress(n - int(batch.going.sum()), n)
    finally:
        set_flags(batch.cores, STOP_AT_KEYS, np.zeros(n, dtype=np.int64))
    if flush:
        for sim in runs:
            sim.flush_events()


class _Batch:
    """Where each run of a batch stands: its step, the stop of its stage, whether it logs and
    whether it must go on, as arrays, so that a batch step costs Python only for the runs
    that stopped for it (a decision event, a flush, the end of a stage)."""

    def __init__(self, runs: list[EnsembleRun], goal: np.ndarray, keys: np.ndarray) -> None:
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
        step_indices(self.cores, self.step)
        going = ~self.finished & (self.step < self.goal)
        for k in np.flatnonzero(going & self.keys).tolist():
            going[k] = not self.runs[k].key_groups
        self.going = going

    def resume(self, reasons: np.ndarray) -> None:
        """Hand each run that stopped for Python to :meth:`Simulation.resume` (a run that
        only reached its goal within its stage needs nothing)."""
        step_indices(self.cores, self.step)
        python = self.going & ((reasons != DONE) | (self.step >= self.stop))
        for k in np.flatnonzero(python).tolist():
            run = self.runs[k]
            run.resume(int(reasons[k]))
            self.stop[k], self.logging[k] = run.stop_step, run.logging
            self.finished[k] = run.finished
        self._update()


__all__ = ["EnsembleRun", "advance_ensemble", "run_ensemble"]
