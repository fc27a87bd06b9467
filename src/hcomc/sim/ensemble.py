"""Ensembles: many runs advanced together, in one process, parallel over cores.

Every run keeps its own state (:class:`hcomc.sim.core_state.Core`) and log; one compiled call
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

import numba
import numpy as np
from numba import njit, prange
from numba.typed import List

from hcomc.sim.core import run_steps
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog


@njit(cache=True, parallel=True)
def _advance_batch(cores, rngs, stops, logging, reasons):
    """Advance every run to its stop (or until it needs Python), one thread per run."""
    for j in prange(len(cores)):
        k = np.int64(j)
        reasons[k] = run_steps(cores[k], stops[k], logging[k], rngs[k])


# the same loop on one thread: no thread pool (safe in forked worker processes)
_advance_batch_serial = njit(cache=True)(_advance_batch.py_func)


_LAST: list[tuple[list[weakref.ref[Simulation]], List, List]] = []


def _typed_lists(runs: list[Simulation]) -> tuple[List, List]:
    """The compiled loop's lists of the runs' states and generators. The last batch's lists
    are kept and only the places whose run changed are replaced (a learning environment
    passes the same runs in the same places every step, with a few new episodes), since
    each entry costs microseconds to convert. They hold the last batch's states until the
    next batch (or the end of :func:`run_ensemble`)."""
    if _LAST and len(_LAST[0][0]) == len(runs):
        refs, cores, rngs = _LAST[0]
        for k, run in enumerate(runs):
            if refs[k]() is not run:
                refs[k], cores[k], rngs[k] = weakref.ref(run), run.core, run.rng
        return cores, rngs
    cores = List([s.core for s in runs])
    rngs = List([s.rng for s in runs])
    _LAST[:] = [([weakref.ref(s) for s in runs], cores, rngs)]
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
    _LAST.clear()  # a finished batch's states need not outlive it
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
    advance = _advance_batch_serial if threads == 1 else _advance_batch
    end = np.iinfo(np.int64).max
    goal = [end] * len(sims) if steps is None else [int(s) for s in steps]
    keys = [False] * len(sims) if until_key_vehicles is None else list(until_key_vehicles)

    def due(k: int) -> bool:
        return not sims[k].reached(goal[k], until_key_vehicles=keys[k])

    if not any(due(k) for k in range(len(sims))):
        return
    previous = threads
    if threads > 1:  # the thread pool is touched only when used (a forked child must not)
        previous = numba.get_num_threads()
        numba.set_num_threads(threads)
    try:
        runs = list(sims)
        cores, rngs = _typed_lists(runs)  # one batch, the same places: a done run stands still
        reasons = np.empty(len(runs), dtype=np.int64)
        going = [due(k) for k in range(len(runs))]
        while any(going):
            stops = np.array(
                [min(r.stop_step, goal[k]) if g else r.step_index
                 for k, (r, g) in enumerate(zip(runs, going, strict=True))], dtype=np.int64,
            )  # fmt: skip
            logging = np.array([r.logging for r in runs], dtype=np.bool_)
            advance(cores, rngs, stops, logging, reasons)
            for r, reason, g in zip(runs, reasons.tolist(), going, strict=True):
                if g:
                    r.resume(reason)
            still = [due(k) for k in range(len(runs))]
            if progress is not None and still != going:
                progress(len(sims) - sum(still), len(sims))
            going = still
        if flush:
            for sim in sims:
                sim.flush_events()
    finally:
        if threads > 1:
            numba.set_num_threads(previous)


__all__ = ["advance_ensemble", "run_ensemble"]
