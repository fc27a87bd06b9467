"""Sweeps: density x penetration x configuration x seed grids, resumable, local or on Dask.

A sweep spec (TOML, validated like scenario configs) names a base scenario, the grid values of
the per-lane mean headways and the CAV penetration, the configurations, the number of seeds
and optionally a continuous ramp flow; every value the spec leaves out comes from the base,
and each result row starts with the values the run actually used (:data:`RESOLVED`). The
runs are kept in a resumable store keyed by their fully resolved inputs, version and code
(:mod:`hcomc.experiments.run_store`) and run in batches on local processes or a Dask cluster
(:mod:`hcomc.experiments.workers`). The final table is assembled from the stored parts in
grid order, so it is identical for any backend and worker count; run timings live in the
manifests.

A corridor (:mod:`hcomc.corridor`: a preset such as ``corridor`` or a corridor file) may be
the base: its runs are :class:`~hcomc.experiments.corridor.runs.CorridorSpec` s, its grid is
``[corridor_grid]`` (dotted corridor keys, each with its list of values) and its rows hold
the corridor metrics (:mod:`hcomc.experiments.corridor.sweep`). A store holds runs of both
kinds side by side; each kind is batched and keyed on its own.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd
from pydantic import ValidationError

from hcomc.config import ConfigError, describe_error, load_config
from hcomc.corridor import is_corridor_source
from hcomc.experiments.corridor.runs import (
    CorridorSpec,
    forget,
)
from hcomc.experiments.run_store import (
    TIMING,
    RunStore,
    SweepStatus,
    forget_resolved,
    resolved_config,
)
from hcomc.experiments.runner import CONFIGURATIONS, RunSpec
from hcomc.experiments.sweep_spec import GRID_KEYS, SweepSpec
from hcomc.experiments.tables import mean_ci
from hcomc.experiments.workers import AnySpec
from hcomc.sim.manifest import atomic_paths

RESOLVED = ("base", *GRID_KEYS, "ramp", "ramp_mean_headway", "duration")
"""Columns every result row starts with: the values the run actually used."""


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
    corridor: :func:`hcomc.experiments.corridor.sweep.expand_corridor`)."""
    forget_resolved()  # base files may have changed since the last expansion
    forget()
    if is_corridor_sweep(spec):
        from hcomc.experiments.corridor.sweep import expand_corridor

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
        from hcomc.experiments.corridor.sweep import corridor_row

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


def assemble(spec: SweepSpec, out: Path) -> pd.DataFrame:
    """The results table from the stored parts, in grid order; writes sweep.* and summary."""
    table = RunStore(out).read(expand(spec))
    summ = pd.DataFrame()
    if len(table) and is_corridor_sweep(spec):
        from hcomc.experiments.corridor.sweep import corridor_summary

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
    "assemble",
    "expand",
    "is_corridor_sweep",
    "load_sweep",
    "run_sweep",
    "sweep_status",
]
