"""Sweeps whose base is a corridor: a grid of dotted corridor keys x configuration x seed.

A sweep spec (:class:`hcomc.experiments.sweep_spec.SweepSpec`) whose ``base`` is a corridor preset
or file sweeps ``[corridor_grid]``: dotted corridor keys (as ``--set`` takes them, e.g.
``"demand.main.cav_share" = [0.2, 0.8]``, or as nested tables), each with its list of
values; every combination is a cell. ``duration`` sets ``corridor.duration``; the scenario
keys (``[grid]``, ``ramp``, ``ramp_mean_headway``) are refused, since a corridor has no such
keys. Each row starts with ``base``, the cell's values (a value that is not a number, string
or boolean as JSON) and the duration the run used; the summary gives per cell and
configuration the mean and 95 % CI of every metric present.
"""

from __future__ import annotations

import itertools
import json
from typing import Any

import pandas as pd

from hcomc.config import ConfigError
from hcomc.experiments.corridor.metrics import CORRIDOR_METRICS
from hcomc.experiments.corridor.runs import CorridorSpec, check, resolve
from hcomc.experiments.sweep_spec import SweepSpec
from hcomc.experiments.tables import mean_ci

_EXAMPLE = '[corridor_grid] with dotted corridor keys, e.g. "demand.main.cav_share" = [0.2, 0.8]'


def grid_keys(spec: SweepSpec) -> dict[str, list[Any]]:
    """The spec's ``[corridor_grid]`` as dotted key -> values (nested tables flattened);
    ConfigError for a key without a non-empty list of values."""
    flat: dict[str, list[Any]] = {}

    def walk(table: dict[str, Any], prefix: str) -> None:
        for key, value in table.items():
            if isinstance(value, dict):
                walk(value, f"{prefix}{key}.")
            elif isinstance(value, list) and value:
                flat[f"{prefix}{key}"] = value
            else:
                raise ConfigError(
                    f"key 'corridor_grid.{prefix}{key}' = {value!r}: allowed: a non-empty list "
                    "of values"
                )

    walk(spec.corridor_grid, "")
    return flat


def cells(spec: SweepSpec) -> list[dict[str, Any]]:
    """Every combination of the grid's values, in grid order (one empty cell if none)."""
    keys = grid_keys(spec)
    return [dict(zip(keys, combo, strict=True)) for combo in itertools.product(*keys.values())]


def _refuse_scenario_keys(spec: SweepSpec) -> None:
    given = [f"grid.{k}" for k, v in spec.grid.model_dump().items() if v is not None]
    given += [k for k in ("ramp", "ramp_mean_headway") if getattr(spec, k) is not None]
    if given:
        raise ConfigError(
            f"key '{given[0]}' applies to a scenario base; base '{spec.base}' is a corridor; "
            f"allowed: {_EXAMPLE}"
        )


def expand_corridor(spec: SweepSpec) -> list[CorridorSpec]:
    """Runs in grid order (cell, configuration, seed); every cell's corridor, controller and
    engine are checked before anything runs (ConfigError naming the key)."""
    _refuse_scenario_keys(spec)
    runs: list[CorridorSpec] = []
    for cell in cells(spec):
        overrides = dict(cell)
        if spec.duration is not None:
            overrides["corridor.duration"] = spec.duration
        for conf in spec.configurations:
            check(CorridorSpec(spec.base, conf, 0, overrides, spec.engine))
            runs.extend(
                CorridorSpec(spec.base, conf, seed, overrides, spec.engine)
                for seed in range(spec.seeds)
            )
    return runs


def _shown(value: Any) -> Any:
    """A grid value as a table cell: numbers, strings and booleans as they are, else JSON."""
    return value if isinstance(value, int | float | str | bool) else json.dumps(value)


def corridor_row(spec: SweepSpec, run: CorridorSpec, row: dict[str, Any]) -> pd.DataFrame:
    """The one-row table stored for ``run``: base, the cell's values, duration, then the
    run's row."""
    used = {
        "base": run.condition,
        **{key: _shown(run.overrides[key]) for key in grid_keys(spec)},
        "duration": resolve(run).corridor.corridor.duration,
    }
    return pd.DataFrame([{**used, **row}])


def corridor_summary(spec: SweepSpec, table: pd.DataFrame) -> pd.DataFrame:
    """Per cell and configuration: runs, and the mean and 95 % CI half-width of every metric
    in the table (the corridor metrics, or the paper's for a paper-layout corridor)."""
    from hcomc.metrics import METRICS

    names = (*CORRIDOR_METRICS, *METRICS, "throughput", "ramp_delay")
    metrics = [m for m in dict.fromkeys(names) if m in table]
    keys = [*grid_keys(spec), "configuration"]
    records = []
    for key, part in table.groupby(keys, sort=False):
        rec = dict(zip(keys, key, strict=True))
        rec["n"] = len(part)
        for m in metrics:
            rec[m], rec[f"{m}_ci"], _ = mean_ci(part[m])
        records.append(rec)
    return pd.DataFrame(records)


__all__ = ["cells", "corridor_row", "corridor_summary", "expand_corridor", "grid_keys"]
