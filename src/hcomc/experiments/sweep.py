"""Sweeps: density x penetration x configuration x seed grids, resumable, local or on Dask.

A sweep spec (TOML, validated like scenario configs) names a base scenario, the grid values of
the per-lane mean headways and the CAV penetration, the configurations, the number of seeds
and optionally a continuous ramp flow. Every run is identified by a key hashed from its full
specification; each finished run is written atomically as ``parts/<key>.parquet`` (one row)
plus ``manifests/<key>.json``, so a killed sweep rerun skips finished runs and loses nothing.
Runs execute on local processes (a pool that dies is rebuilt and its unfinished runs
resubmitted) or, with a scheduler address, on a Dask cluster (whose workers' tasks are retried
by Dask when a worker dies). The final table is assembled from the parts in grid order, so it
is identical for any backend and worker count; run timings live in the manifests.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import tomllib
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any, Literal

import pandas as pd
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from hcomc.config import ConfigError, describe_error, load_config
from hcomc.experiments.runner import CONFIGURATIONS, RunSpec, run_one
from hcomc.experiments.tables import mean_ci
from hcomc.sim.manifest import atomic_paths, write_json_atomic

GRID_KEYS = ("mean_headway_main_1", "mean_headway_main_2", "cav_penetration")
TIMING = ("wall_s", "decision_ms")
Configuration = Literal["FIFO", "Game", "HCOMC", "HCOMC-PSO", "HCOMC-SA"]


class SweepGrid(BaseModel):
    """Grid values (each a non-empty list) of the demand parameters."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    mean_headway_main_1: list[float] = Field([5.0], description="lane 1 mean headways [s]")
    mean_headway_main_2: list[float] = Field([5.0], description="lane 2 mean headways [s]")
    cav_penetration: list[float] = Field([0.9], description="CAV shares [-]")

    @field_validator(*GRID_KEYS)
    @classmethod
    def _non_empty(cls, values: list[float]) -> list[float]:
        if not values:
            raise ValueError("must list at least one value")
        return values


class SweepSpec(BaseModel):
    """A sweep: base scenario, grid, configurations, seeds and ramp demand."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    name: str = Field("sweep", description="sweep name")
    base: str = Field("C1", description="preset or TOML file for everything not swept")
    configurations: list[Configuration] = Field(["FIFO", "Game", "HCOMC"], min_length=1)
    seeds: int = Field(3, ge=1, le=10_000, description="seeds 0 .. seeds-1 per cell")
    ramp: Literal["single", "flow"] = Field("single", description="one key merge or a flow")
    ramp_mean_headway: float | None = Field(None, gt=0, description="'flow': ramp headway [s]")
    duration: float | None = Field(None, gt=0, description="measured duration [s]")
    grid: SweepGrid = Field(default_factory=SweepGrid)


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and validate a sweep spec, raising :class:`ConfigError` with a one-line message."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"sweep spec '{path}' does not exist")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: invalid TOML: {exc}") from None
    try:
        spec = SweepSpec.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(describe_error(exc, str(path))) from None
    expand(spec)  # every cell must be a valid scenario before anything runs
    return spec


def expand(spec: SweepSpec) -> list[RunSpec]:
    """Runs in grid order (cell, configuration, seed); validates every cell's scenario."""
    demand_extra: dict[str, Any] = {"ramp": spec.ramp}
    if spec.ramp_mean_headway is not None:
        demand_extra["ramp_mean_headway"] = spec.ramp_mean_headway
    runs = []
    for cell in itertools.product(*(getattr(spec.grid, k) for k in GRID_KEYS)):
        overrides: dict[str, Any] = {"demand": {**dict(zip(GRID_KEYS, cell, strict=True)),
                                                **demand_extra}}  # fmt: skip
        if spec.duration is not None:
            overrides["duration"] = spec.duration
        load_config(spec.base, **overrides)  # raises ConfigError naming the bad value
        for conf in spec.configurations:
            runs.extend(RunSpec(spec.base, conf, seed, overrides) for seed in range(spec.seeds))
    return runs


def run_key(run: RunSpec) -> str:
    """Stable identity of a run (hash of its full specification)."""
    text = json.dumps([run.condition, run.configuration, run.seed, run.overrides], sort_keys=True)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def _row(run: RunSpec, row: dict[str, Any]) -> pd.DataFrame:
    cell = {k: run.overrides["demand"][k] for k in GRID_KEYS}
    clean = {k: v for k, v in row.items() if k not in TIMING}
    return pd.DataFrame([{**cell, **clean}])


def run_sweep(
    spec: SweepSpec,
    out: Path,
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    max_pool_restarts: int = 3,
) -> pd.DataFrame:
    """Run every unfinished run of ``spec`` into ``out`` and return the assembled table."""
    runs = expand(spec)
    parts, manifests = out / "parts", out / "manifests"
    parts.mkdir(parents=True, exist_ok=True)
    manifests.mkdir(parents=True, exist_ok=True)
    keys = [run_key(r) for r in runs]
    todo = [i for i, k in enumerate(keys) if not (parts / f"{k}.parquet").exists()]
    done = len(runs) - len(todo)
    if progress is not None:
        progress(done, len(runs))

    def store(i: int, result: tuple[dict[str, Any], dict[str, Any]]) -> None:
        nonlocal done
        row, manifest = result
        manifest = {**manifest, "timing": {k: row.get(k) for k in TIMING}}
        write_json_atomic(manifests / f"{keys[i]}.json", manifest)
        with atomic_paths(parts / f"{keys[i]}.parquet") as (tmp,):  # the part commits the run
            _row(runs[i], row).to_parquet(tmp, index=False)
        done += 1
        if progress is not None:
            progress(done, len(runs))

    if scheduler is not None:
        _run_dask(scheduler, runs, todo, store)
    else:
        _run_local(runs, todo, store, workers, max_pool_restarts)
    return assemble(spec, out)


def _run_local(runs, todo, store, workers: int, restarts: int) -> None:
    if workers <= 1:
        for i in todo:
            store(i, run_one(runs[i]))
        return
    pending = list(todo)
    for _ in range(restarts + 1):
        try:
            with ProcessPoolExecutor(max_workers=workers) as pool:
                futures = {pool.submit(run_one, runs[i]): i for i in pending}
                for future in as_completed(futures):
                    i = futures[future]
                    store(i, future.result())
                    pending.remove(i)
            return
        except BrokenProcessPool:  # a worker died: rebuild the pool, resubmit the rest
            continue
    raise RuntimeError(f"the process pool broke {restarts + 1} times; {len(pending)} runs left")


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


def _run_dask(scheduler: str, runs, todo, store) -> None:
    from distributed import as_completed as dask_completed

    client = connect(scheduler)
    try:
        futures = {client.submit(run_one, runs[i], pure=False, retries=2): i for i in todo}
        for future in dask_completed(list(futures)):
            store(futures[future], future.result())
    finally:
        client.close()


def assemble(spec: SweepSpec, out: Path) -> pd.DataFrame:
    """The results table from the stored parts, in grid order; writes sweep.* and summary."""
    runs = expand(spec)
    frames = [pd.read_parquet(out / "parts" / f"{run_key(r)}.parquet") for r in runs
              if (out / "parts" / f"{run_key(r)}.parquet").exists()]  # fmt: skip
    table = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    summ = summarise(table) if len(table) else pd.DataFrame()
    with atomic_paths(out / "sweep.csv", out / "sweep.parquet", out / "summary.csv") as tmp:
        table.to_csv(tmp[0], index=False)
        table.to_parquet(tmp[1], index=False)
        summ.to_csv(tmp[2], index=False)
    return table


def summarise(table: pd.DataFrame) -> pd.DataFrame:
    """Per grid cell and configuration: mean and 95 % CI half-width of every metric."""
    from hcomc.metrics import METRICS

    metrics = [m for m in (*METRICS, "throughput", "ramp_delay") if m in table]
    records = []
    for key, part in table.groupby([*GRID_KEYS, "configuration"], sort=False):
        rec = dict(zip([*GRID_KEYS, "configuration"], key, strict=True))
        rec["n"] = len(part)
        for m in metrics:
            rec[m], rec[f"{m}_ci"], _ = mean_ci(part[m])
        records.append(rec)
    return pd.DataFrame(records)


__all__ = ["CONFIGURATIONS", "SweepSpec", "assemble", "expand", "load_sweep", "run_sweep"]
