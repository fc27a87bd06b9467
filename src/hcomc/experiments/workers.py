"""Running lists of runs: in batches, on local processes or a Dask cluster.

Runs of scenario conditions that share an undisturbed run are simulated together as one
ensemble (a batch of up to :data:`BATCH_SIZE`); a corridor corridor run is a
batch of its own. Local processes run the batches in a pool that, if a worker dies, is
rebuilt and given the unfinished batches again; a Dask cluster retries a dead worker's
tasks itself. Each finished run is handed to a ``store(i, (row, manifest))`` callback.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Any

import pandas as pd

from hcomc.config import ConfigError
from hcomc.experiments.corridor.runs import CorridorSpec, reference_group, run_corridor_batch
from hcomc.experiments.pool import local_pool
from hcomc.experiments.runner import RunSpec, batches, batches_by_reference, run_batch

__all__ = ["BATCH_SIZE", "AnySpec", "connect", "run_dask", "run_local", "run_rows"]

AnySpec = RunSpec | CorridorSpec
"""A run of a scenario condition (the runner's) or of a corridor."""

Store = Callable[[int, Any], None]
"""The callback a finished run is handed to: ``store(i, (row, manifest))``."""


def run_rows(
    runs: Sequence[AnySpec],
    *,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
) -> pd.DataFrame:
    """Run every run without a store (``hcomc run``) and return their rows in run order,
    batched and spread over ``workers`` processes as a sweep's."""
    rows: list[dict[str, Any] | None] = [None] * len(runs)
    done = 0

    def keep(i: int, result: tuple[dict[str, Any], dict[str, Any]]) -> None:
        nonlocal done
        rows[i] = result[0]
        done += 1
        if progress is not None:
            progress(done, len(runs))

    run_local(runs, list(range(len(runs))), keep, workers, 0)
    return pd.DataFrame(rows)


BATCH_SIZE = 4
"""Runs simulated together as one ensemble (one task on a worker or a Dask cluster). A
killed sweep loses at most the batches that were running; small batches keep that small."""


def _chunks(runs: Sequence[AnySpec], todo: list[int]) -> list[list[int]]:
    """The runs still to do in batches of one kind, runs of one undisturbed run together; a
    corridor run is a batch of its own (it shares nothing with others)."""
    ours = {i: run for i in todo if isinstance(run := runs[i], RunSpec)}
    chunks = batches_by_reference(list(ours.values()), BATCH_SIZE)
    found = [[list(ours)[k] for k in chunk] for chunk in chunks]
    corridor = {i: run for i in todo if isinstance(run := runs[i], CorridorSpec)}
    order = sorted(corridor, key=lambda i: reference_group(corridor[i]))
    paper = [i for i in order if reference_group(corridor[i])[0] == "scenario"]
    found += [[paper[k] for k in chunk] for chunk in batches(len(paper), BATCH_SIZE)]
    return found + [[i] for i in order if reference_group(corridor[i])[0] != "scenario"]


def _batch_function(run: AnySpec) -> Callable[..., list[tuple[dict[str, Any], dict[str, Any]]]]:
    """What simulates a batch of runs of ``run``'s kind (picklable, for worker processes)."""
    return run_corridor_batch if isinstance(run, CorridorSpec) else run_batch


def _submit(submit: Callable[..., Any], runs: Sequence[AnySpec], chunk: list[int],
            **options: Any) -> Any:  # fmt: skip
    """``submit(batch function, runs of the chunk, **options)``: one chunk's batch handed to
    a pool's or a Dask client's ``submit``, or called here (``submit`` = :func:`_call`)."""
    return submit(_batch_function(runs[chunk[0]]), [runs[i] for i in chunk], **options)


def _call(function: Callable[..., Any], *args: Any, **options: Any) -> Any:
    return function(*args, **options)


def _store_batch(chunk: list[int], results: list[Any], store: Store) -> None:
    for i, result in zip(chunk, results, strict=True):
        store(i, result)


def run_local(
    runs: Sequence[Any], todo: list[int], store: Store, workers: int, restarts: int
) -> None:
    if workers <= 1:
        for chunk in _chunks(runs, todo):
            _store_batch(chunk, _submit(_call, runs, chunk), store)
        return
    pending = _chunks(runs, todo)
    for _ in range(restarts + 1):
        finished: set[int] = set()
        try:
            with local_pool(workers) as pool:
                futures = {
                    _submit(pool.submit, runs, chunk, threads=1): k
                    for k, chunk in enumerate(pending)
                }
                for future in as_completed(futures):
                    k = futures[future]
                    _store_batch(pending[k], future.result(), store)
                    finished.add(k)
            return
        except BrokenProcessPool:  # a worker died: rebuild the pool, resubmit the rest
            pending = [chunk for k, chunk in enumerate(pending) if k not in finished]
            continue
    left = sum(len(chunk) for chunk in pending)
    raise RuntimeError(f"the process pool broke {restarts + 1} times; {left} runs left")


def connect(scheduler: str) -> Any:
    """A Dask client for ``scheduler`` or :class:`ConfigError` if it cannot be reached."""
    try:
        from distributed import Client
    except ImportError:
        raise ConfigError(
            "option '--scheduler' needs dask.distributed; install it with pip install 'hcomc[dask]'"
        ) from None
    try:
        return Client(scheduler, timeout=5)
    except (OSError, TimeoutError) as exc:
        raise ConfigError(
            f"option '--scheduler' = '{scheduler}': no Dask scheduler reachable ({exc})"
        ) from None


def run_dask(scheduler: str, runs: Sequence[Any], todo: list[int], store: Store) -> None:
    from distributed import as_completed as dask_completed

    client = connect(scheduler)
    try:
        chunks = _chunks(runs, todo)
        futures = {
            _submit(client.submit, runs, chunk, pure=False, retries=2): k
            for k, chunk in enumerate(chunks)
        }
        for future in dask_completed(list(futures)):
            _store_batch(chunks[futures[future]], future.result(), store)
    finally:
        client.close()
