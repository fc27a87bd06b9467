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

from collections.abc import Callable, Sequence

import numba
import numpy as np
from numba import njit, prange
from numba.typed import List

from hcomc.sim.core import run_steps
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog


@njit(cache=True, parallel=True)
def _advance_batch(cores, logs, stops, logging, reasons):
    """Advance every run to its stop (or until it needs Python), one thread per run."""
    for j in prange(len(cores)):
        k = np.int64(j)
        la = logs[k]
        reasons[k] = run_steps(
            cores[k], stops[k], logging[k], la[0], la[1], la[2], la[3], la[4], la[5], la[6], la[7]
        )


# the same loop on one thread: no thread pool (safe in forked worker processes)
_advance_batch_serial = njit(cache=True)(_advance_batch.py_func)


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
    most = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    threads = most if threads is None else max(1, min(threads, most))
    advance = _advance_batch_serial if threads == 1 else _advance_batch
    previous = threads
    if threads > 1:  # the thread pool is touched only when used (a forked child must not)
        previous = numba.get_num_threads()
        numba.set_num_threads(threads)
    try:
        pending = [s for s in sims if not s.finished]
        while pending:
            cores = List([s.core for s in pending])
            logs = List([s.log_arrays for s in pending])
            members = len(pending)
            while len(pending) == members:
                stops = np.array([s.stop_step for s in pending], dtype=np.int64)
                logging = np.array([s.logging for s in pending], dtype=np.bool_)
                reasons = np.empty(len(pending), dtype=np.int64)
                advance(cores, logs, stops, logging, reasons)
                for sim, reason in zip(pending, reasons.tolist(), strict=True):
                    sim.resume(reason)
                if any(s.finished for s in pending):
                    pending = [s for s in pending if not s.finished]
                    if progress is not None:
                        progress(len(sims) - len(pending), len(sims))
    finally:
        if threads > 1:
            numba.set_num_threads(previous)
    return [s.log for s in sims]


__all__ = ["run_ensemble"]
