"""Sweeps: density x penetration x configuration x seed grids, resumable, local or on Dask.

A sweep spec (TOML, validated like scenario configs) names a base scenario, the grid values of
the per-lane mean headways and the CAV penetration, the configurations, the number of seeds
and optionally a continuous ramp flow; every value the spec leaves out comes from the base,
and each result row starts with the values the run actually used (:data:`RESOLVED`). Every
run is identified by a key hashed from its place in the grid, its fully resolved config,
the hcomc version and the code that computes it; each finished run is written atomically as
``parts/<key>.parquet`` (one row) plus ``manifests/<key>.json``, so a killed sweep rerun
skips finished runs and loses nothing, and a rerun after the base or the code changed
recomputes instead of mixing.
Runs execute on local processes (a pool that dies is rebuilt and its unfinished runs
resubmitted) or, with a scheduler address, on a Dask cluster (whose workers' tasks are retried
by Dask when a worker dies). The final table is assembled from the parts in grid order, so it
is identical for any backend and worker count; run timings live in the manifests. The
store (:class:`RunStore`) takes any list of runs: benchmark comparisons keep theirs in one.

A corridor (:mod:`hcomc.corridor`: a preset such as ``corridor`` or a corridor file) may be
the base: its runs are :class:`~hcomc.experiments.corridor_runs.CorridorSpec` s, its grid is
``[corridor_grid]`` (dotted corridor keys, each with its list of values) and its rows hold
the corridor metrics (:mod:`hcomc.experiments.corridor_sweep`). A store holds runs of both
kinds side by side; each kind is batched and keyed on its own.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import tomllib
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import pandas as pd
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

import hcomc
from hcomc.config import ConfigError, ScenarioConfig, describe_error, load_config
from hcomc.control.registry import BUILTIN, controller_source
from hcomc.corridor import is_corridor_source
from hcomc.experiments.corridor_runs import (
    CorridorSpec,
    forget,
    key_material,
    reference_group,
    run_corridor_batch,
)
from hcomc.experiments.provenance import code_stamp
from hcomc.experiments.runner import (
    _SPAWN,
    CONFIGURATIONS,
    RunSpec,
    batches,
    batches_by_reference,
    configuration_label,
    run_batch,
)
from hcomc.experiments.tables import mean_ci
from hcomc.sim.manifest import atomic_paths, write_json_atomic

GRID_KEYS = ("mean_headway_main_1", "mean_headway_main_2", "cav_penetration")
RESOLVED = ("base", *GRID_KEYS, "ramp", "ramp_mean_headway", "duration")
"""Columns every result row starts with: the values the run actually used."""
TIMING = ("wall_s", "decision_ms")

AnySpec = RunSpec | CorridorSpec
"""A run of a scenario condition (the runner's) or of a corridor."""


class SweepGrid(BaseModel):
    """Grid values of the demand parameters; a key left out keeps the base's value."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    mean_headway_main_1: list[float] | None = Field(None, description="lane 1 mean headways [s]")
    mean_headway_main_2: list[float] | None = Field(None, description="lane 2 mean headways [s]")
    cav_penetration: list[float] | None = Field(None, description="CAV shares [-]")

    @field_validator(*GRID_KEYS)
    @classmethod
    def _non_empty(cls, values: list[float] | None) -> list[float] | None:
        if values is not None and not values:
            raise ValueError("must list at least one value (or leave the key out)")
        return values

    def cells(self) -> list[dict[str, float]]:
        """Every combination of the given keys, in grid order (one empty cell if none)."""
        keys = [k for k in GRID_KEYS if getattr(self, k) is not None]
        values = itertools.product(*(getattr(self, k) for k in keys))
        return [dict(zip(keys, combo, strict=True)) for combo in values]


class SweepSpec(BaseModel):
    """A sweep: base scenario, grid, configurations, seeds and ramp demand.

    Everything the spec leaves out (grid keys, ramp, ramp headway, duration) is the base's.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    name: str = Field("sweep", description="sweep name")
    base: str = Field("C1", description="preset or TOML file for everything not swept")
    configurations: list[str] = Field(
        ["FIFO", "Game", "HCOMC"],
        min_length=1,
        description="configuration labels (FIFO, Game, HCOMC, HCOMC-PSO, HCOMC-SA, FIFO-R, "
        "Game-R, HCOMC+) or controller names (a registered name, package.module:Class, "
        "path/to/file.py:Class)",
    )
    seeds: int = Field(3, ge=1, le=10_000, description="seeds 0 .. seeds-1 per cell")
    ramp: Literal["single", "flow"] | None = Field(None, description="one key merge or a flow")
    ramp_mean_headway: float | None = Field(None, gt=0, description="'flow': ramp headway [s]")
    duration: float | None = Field(None, gt=0, description="measured duration [s]")
    engine: Literal["hcomc", "sumo"] = Field(
        "hcomc", description="simulation engine: hcomc, or sumo (co-simulation, hcomc[sumo])"
    )
    grid: SweepGrid = Field(default_factory=SweepGrid)
    corridor_grid: dict[str, Any] = Field(
        default_factory=dict,
        description="grid values of a corridor base: dotted corridor keys (or nested tables), "
        'each with its list of values, e.g. "demand.main.cav_share" = [0.2, 0.8]',
    )

    @field_validator("configurations")
    @classmethod
    def _configurations(cls, names: list[str]) -> list[str]:
        return [configuration_label(name) for name in names]


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and validate a sweep spec, raising :class:`ConfigError` with a one-line message.

    A relative ``base`` path is looked up next to the spec first.
    """
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
        raise ConfigError(describe_error(exc, str(path), SweepSpec)) from None
    nearby = path.parent / spec.base
    if spec.base.endswith(".toml") and not Path(spec.base).is_file() and nearby.is_file():
        spec = spec.model_copy(update={"base": str(nearby)})
    expand(spec)  # every cell must be a valid scenario before anything runs
    return spec


def is_corridor_sweep(spec: SweepSpec) -> bool:
    """Whether the spec's base is a corridor (preset or corridor file)."""
    return is_corridor_source(spec.base)


def expand(spec: SweepSpec) -> list[AnySpec]:
    """Runs in grid order (cell, configuration, seed); validates every cell's scenario (or
    corridor: :func:`hcomc.experiments.corridor_sweep.expand_corridor`)."""
    _resolved.cache_clear()  # base files may have changed since the last expansion
    forget()
    if is_corridor_sweep(spec):
        from hcomc.experiments.corridor_sweep import expand_corridor

        return list(expand_corridor(spec))
    if spec.corridor_grid:
        raise ConfigError(
            f"key 'corridor_grid' applies to a corridor base; base '{spec.base}' is a scenario "
            "config; allowed: [grid] (mean_headway_main_1, mean_headway_main_2, cav_penetration)"
        )
    demand_extra = {
        k: v for k, v in (("ramp", spec.ramp), ("ramp_mean_headway", spec.ramp_mean_headway))
        if v is not None
    }  # fmt: skip
    runs: list[AnySpec] = []
    for cell in spec.grid.cells():
        overrides: dict[str, Any] = {"demand": {**cell, **demand_extra}}
        if spec.duration is not None:
            overrides["duration"] = spec.duration
        load_config(spec.base, **overrides)  # raises ConfigError naming the bad value
        for conf in spec.configurations:
            runs.extend(
                RunSpec(spec.base, conf, seed, overrides, engine=spec.engine)
                for seed in range(spec.seeds)
            )
    return runs


@functools.lru_cache(maxsize=4096)  # one load per cell and configuration, not per seed
def _resolved(condition: str, configuration: str, overrides: str) -> ScenarioConfig:
    run = RunSpec(condition, configuration, 0, json.loads(overrides))
    return load_config(condition, **run.config_overrides())


def resolved_config(run: RunSpec) -> ScenarioConfig:
    """The config ``run`` simulates (base + cell + its configuration's controller)."""
    return _resolved(run.condition, run.configuration, json.dumps(run.overrides, sort_keys=True))


def _identity(run: AnySpec) -> str:
    """What a run is in the grid (base, cell, configuration, seed), whatever its inputs say;
    a corridor's run is marked as such."""
    kind = ["corridor"] if isinstance(run, CorridorSpec) else []
    text = json.dumps(
        [*kind, run.condition, run.configuration, run.seed, run.overrides, run.engine],
        sort_keys=True,
    )
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def outside_source(controller: str) -> str:
    """SHA-256 of the file that defines a controller from outside hcomc ("" for hcomc's own,
    which the package version covers)."""
    if controller == "none" or controller in BUILTIN:
        return ""
    return controller_source(controller)["sha256"]


def run_key(run: AnySpec) -> str:
    """Stable key of a run's result: its identity, resolved config, hcomc version and code.

    A changed preset or base file, another package version, a changed source file of hcomc
    that can change a run (:func:`hcomc.experiments.provenance.code_stamp`) or of a
    controller from outside hcomc gives new keys, so a resumed sweep recomputes those runs
    instead of mixing stale results into the table. A corridor's run hashes the resolved
    corridor, and the scenario it becomes when it runs in the scenario engine
    (:func:`hcomc.experiments.corridor_runs.key_material`), in place of the config.
    """
    if isinstance(run, CorridorSpec):
        *material, controller = key_material(run)
    else:
        config = resolved_config(run)
        material, controller = [config.model_dump(mode="json")], config.control.controller
    text = json.dumps(
        [_identity(run), *material, hcomc.__version__, code_stamp(),
         outside_source(controller)],
        sort_keys=True,
    )  # fmt: skip
    return hashlib.sha1(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class SweepStatus:
    """What a (re)run of a list of runs into a store will do."""

    total: int
    done: int  # stored with the current config and version: skipped
    new: int  # never run
    changed: int  # stored under an older config or version: recomputed
    stale: int  # stored parts that no run of this list uses (kept, ignored)


@dataclass(frozen=True)
class RunStore:
    """A folder of finished runs, one per key (:func:`run_key`): ``parts/<key>.parquet``
    (the run's results row) and ``manifests/<key>.json`` (its manifest, timing and grid
    identity). A part is written last and atomically, so it exists only for a complete run;
    rerunning a list of runs into the store runs only those without a part."""

    root: Path

    @property
    def parts(self) -> Path:
        """The folder of results rows."""
        return self.root / "parts"

    @property
    def manifests(self) -> Path:
        """The folder of manifests."""
        return self.root / "manifests"

    def part(self, run: AnySpec) -> Path:
        """Where ``run``'s results row is (or will be) stored."""
        return self.parts / f"{run_key(run)}.parquet"

    def status(self, runs: Sequence[AnySpec]) -> SweepStatus:
        """Count the runs of ``runs`` already done here, new, and to recompute."""
        keys = {run_key(r) for r in runs}
        stored = {p.stem for p in self.parts.glob("*.parquet")}
        done = sum(run_key(r) in stored for r in runs)
        old = set()
        for key in stored - keys:
            manifest = self.manifests / f"{key}.json"
            if manifest.is_file():
                old.add(json.loads(manifest.read_text(encoding="utf-8")).get("sweep_identity"))
        changed = sum(run_key(r) not in stored and _identity(r) in old for r in runs)
        return SweepStatus(len(runs), done, len(runs) - done - changed, changed,
                           len(stored - keys))  # fmt: skip

    def run(
        self,
        runs: Sequence[AnySpec],
        frame: Callable[[int, dict[str, Any]], pd.DataFrame],
        *,
        workers: int = 1,
        scheduler: str | None = None,
        progress: Callable[[int, int], None] | None = None,
        max_pool_restarts: int = 3,
    ) -> None:
        """Run every run of ``runs`` that has no part yet and store it; ``frame(i, row)``
        turns run ``i``'s results row (timings removed, they go to the manifest) into the
        one-row table stored as its part."""
        self.parts.mkdir(parents=True, exist_ok=True)
        self.manifests.mkdir(parents=True, exist_ok=True)
        for stale in [*self.parts.glob(".*.tmp"), *self.manifests.glob(".*.tmp")]:
            stale.unlink(missing_ok=True)  # a temporary file of a killed run, never a result
        keys = [run_key(r) for r in runs]
        todo = [i for i, k in enumerate(keys) if not (self.parts / f"{k}.parquet").exists()]
        done = len(runs) - len(todo)
        if progress is not None:
            progress(done, len(runs))

        def store(i: int, result: tuple[dict[str, Any], dict[str, Any]]) -> None:
            nonlocal done
            row, manifest = result
            timing = {k: row.get(k) for k in TIMING}
            manifest = {**manifest, "timing": timing, "sweep_identity": _identity(runs[i])}
            write_json_atomic(self.manifests / f"{keys[i]}.json", manifest)
            clean = {k: v for k, v in row.items() if k not in TIMING}
            with atomic_paths(self.parts / f"{keys[i]}.parquet") as (tmp,):  # commits the run
                frame(i, clean).to_parquet(tmp, index=False)
            done += 1
            if progress is not None:
                progress(done, len(runs))

        if scheduler is not None:
            _run_dask(scheduler, runs, todo, store)
        else:
            _run_local(runs, todo, store, workers, max_pool_restarts)

    def read(self, runs: Sequence[AnySpec]) -> pd.DataFrame:
        """The stored rows of ``runs``, in their order (runs not stored are left out)."""
        paths = [self.part(r) for r in runs]
        frames = [pd.read_parquet(p) for p in paths if p.exists()]
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def sweep_status(spec: SweepSpec, out: Path) -> SweepStatus:
    """Count the runs of ``spec`` already done in ``out``, new, and to recompute."""
    return RunStore(out).status(expand(spec))


def _row(run: RunSpec, row: dict[str, Any]) -> pd.DataFrame:
    config = resolved_config(run)
    demand = config.demand
    used = {
        "base": run.condition,
        **{k: getattr(demand, k) for k in GRID_KEYS},
        "ramp": demand.ramp,
        "ramp_mean_headway": demand.ramp_mean_headway if demand.ramp == "flow" else float("nan"),
        "duration": config.duration,
    }
    clean = {k: v for k, v in row.items() if k not in TIMING}
    return pd.DataFrame([{**used, **clean}])


def _stored_row(spec: SweepSpec, run: AnySpec, row: dict[str, Any]) -> pd.DataFrame:
    """The one-row table stored for ``run`` of ``spec``."""
    if isinstance(run, CorridorSpec):
        from hcomc.experiments.corridor_sweep import corridor_row

        return corridor_row(spec, run, {k: v for k, v in row.items() if k not in TIMING})
    return _row(run, row)


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
    RunStore(out).run(
        runs, lambda i, row: _stored_row(spec, runs[i], row), workers=workers,
        scheduler=scheduler, progress=progress, max_pool_restarts=max_pool_restarts,
    )  # fmt: skip
    return assemble(spec, out)


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

    _run_local(runs, list(range(len(runs))), keep, workers, 0)
    return pd.DataFrame(rows)


BATCH_SIZE = 4
"""Runs simulated together as one ensemble (one task on a worker or a Dask cluster). A
killed sweep loses at most the batches that were running; small batches keep that small."""


def _chunks(runs: Sequence[AnySpec], todo: list[int]) -> list[list[int]]:
    """The runs still to do in batches of one kind, runs of one undisturbed run together; a
    run in the corridor engine is a batch of its own (it shares nothing with others)."""
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


def _store_batch(chunk, results, store) -> None:
    for i, result in zip(chunk, results, strict=True):
        store(i, result)


def _run_local(runs, todo, store, workers: int, restarts: int) -> None:
    if workers <= 1:
        for chunk in _chunks(runs, todo):
            _store_batch(chunk, _submit(_call, runs, chunk), store)
        return
    pending = _chunks(runs, todo)
    for _ in range(restarts + 1):
        finished: set[int] = set()
        try:
            with ProcessPoolExecutor(max_workers=workers, mp_context=_SPAWN) as pool:
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


def _run_dask(scheduler: str, runs, todo, store) -> None:
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


def assemble(spec: SweepSpec, out: Path) -> pd.DataFrame:
    """The results table from the stored parts, in grid order; writes sweep.* and summary."""
    table = RunStore(out).read(expand(spec))
    summ = pd.DataFrame()
    if len(table) and is_corridor_sweep(spec):
        from hcomc.experiments.corridor_sweep import corridor_summary

        summ = corridor_summary(spec, table)
    elif len(table):
        summ = summarise(table)
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


__all__ = [
    "CONFIGURATIONS",
    "RunStore",
    "SweepSpec",
    "SweepStatus",
    "assemble",
    "expand",
    "is_corridor_sweep",
    "load_sweep",
    "resolved_config",
    "run_rows",
    "run_sweep",
    "sweep_status",
]
