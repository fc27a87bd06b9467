"""A sweep's spec: base scenario or corridor, grid, configurations, seeds and ramp demand.

The validated form of a sweep spec file (:func:`hcomc.experiments.sweep.load_sweep` reads
one), shared by the scenario sweeps of :mod:`hcomc.experiments.sweep` and the corridor sweeps
of :mod:`hcomc.experiments.corridor.sweep`, which both expand it into runs.
"""

from __future__ import annotations

import itertools
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from hcomc.experiments.runner import configuration_label

__all__ = ["GRID_KEYS", "SweepGrid", "SweepSpec"]

GRID_KEYS = ("mean_headway_main_1", "mean_headway_main_2", "cav_penetration")
"""The demand parameters a scenario sweep's grid may set, in grid order."""


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
        "Game-R, HCOMC-R, HCOMC+, HCOMC-eq) or controller names (a registered name, "
        "package.module:Class, path/to/file.py:Class)",
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
