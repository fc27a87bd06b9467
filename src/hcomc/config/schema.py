"""The scenario schema: a frozen pydantic v2 model per config table, with units and
defaults in each field's description; unknown keys are rejected (``extra="forbid"``,
:class:`~hcomc.config.frozen_model.FrozenModel`).

:class:`ScenarioConfig` is the whole scenario and checks what spans its tables (the logging
interval against the step, the memory a run would need); its tables are defined by topic:
the vehicles' models (:mod:`hcomc.config.vehicle_tables`), the road and traffic
(:mod:`hcomc.config.traffic_tables`) and the merge control (:mod:`hcomc.config.control_table`).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator, model_validator

from hcomc.config.control_table import ControlParams
from hcomc.config.frozen_model import FrozenModel
from hcomc.config.impairment_tables import (
    MAX_FAULTS,
    ChannelParams,
    FaultParams,
    ShieldParams,
    fault_entries,
    nominal,
)
from hcomc.config.traffic_tables import DemandParams, PlatoonParams, RoadParams
from hcomc.config.vehicle_tables import CAVParams, HDVParams, LaneChangeParams

__all__ = ["MIN_STEP", "ConfigError", "ScenarioConfig"]

MIN_STEP = 1e-3
"""Shortest simulation step [s] of the engine."""


class ScenarioConfig(FrozenModel):
    """A complete, resolved scenario: road, demand, vehicle models and run control."""

    name: str = Field("custom", description="scenario name")
    description: str = Field("", description="free text")
    scenario: Literal["merge", "platoon"] = Field("merge", description="scenario type")
    seed: int = Field(0, ge=0, description="default random seed (the CLI --seed overrides it)")
    dt: float = Field(0.1, ge=MIN_STEP, le=1, description="simulation step [s]")
    duration: float = Field(90.0, gt=0, le=86_400, description="measured duration [s]")
    warmup: float = Field(30.0, ge=0, le=3600, description="unlogged warm-up before t = 0 [s]")
    log_interval: float = Field(0.1, gt=0, le=60, description="logging interval [s]")
    log_memory_limit: float = Field(
        8.0,
        gt=0,
        le=1024,
        description=(
            "a run whose log or perception history would need more memory than this is "
            "refused before anything is allocated, or stopped when its log must grow beyond "
            "it [GiB]"
        ),
    )
    road: RoadParams = Field(default_factory=RoadParams)
    demand: DemandParams = Field(default_factory=DemandParams)
    hdv: HDVParams = Field(default_factory=HDVParams)
    cav: CAVParams = Field(default_factory=CAVParams)
    lane_change: LaneChangeParams = Field(default_factory=LaneChangeParams)
    platoon: PlatoonParams = Field(default_factory=PlatoonParams)
    control: ControlParams = Field(default_factory=ControlParams)
    v2x: ChannelParams = Field(default_factory=ChannelParams)
    faults: tuple[FaultParams, ...] = Field(
        (), max_length=MAX_FAULTS,
        description="faults injected into the run ([[faults]] tables, or preset names such "
        "as 'brake-vmf'); none = the nominal run",
    )  # fmt: skip
    shield: ShieldParams = Field(default_factory=ShieldParams)

    _fault_entries = field_validator("faults", mode="before")(fault_entries)

    @property
    def nominal(self) -> bool:
        """Whether the run is nominal: an ideal V2X channel, no fault and no shield."""
        return nominal(self.v2x, self.faults, self.shield)

    @model_validator(mode="after")
    def _steps(self) -> ScenarioConfig:
        ratio = self.log_interval / self.dt
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"log_interval = {self.log_interval} must be a positive multiple of dt = {self.dt}"
            )
        return self

    @model_validator(mode="after")
    def _memory(self) -> ScenarioConfig:
        need = self.history_gib()
        if need > self.log_memory_limit:
            raise ValueError(
                f"the HDV perception history of this run would need {need:.3g} GiB "
                f"(dt = {self.dt} s, {self.expected_vehicles():.3g} vehicles expected), more "
                f"than log_memory_limit = {self.log_memory_limit} GiB; allowed: a larger dt, "
                "a shorter duration or sparser demand"
            )
        return self

    def expected_vehicles(self) -> float:
        """Vehicles a run is expected to release: its followers (platoon) or every lane's
        demand over warm-up and duration at its mean headway."""
        if self.scenario == "platoon":
            return self.platoon.followers + 1.0
        total = self.warmup + self.duration
        d = self.demand
        rate = 1.0 / d.mean_headway_main_1 + 1.0 / d.mean_headway_main_2
        rate += 1.0 / d.ramp_mean_headway if d.ramp == "flow" else 0.0
        return total * rate + 1.0

    def history_gib(self) -> float:
        """Memory of the perception ring buffer (x and v of every vehicle over the longest
        reaction delay, :class:`hcomc.sim.perception_state.Perception`) [GiB], estimated from
        :meth:`expected_vehicles` before anything is allocated."""
        h = self.hdv
        rows = max(h.reaction_time_gap, h.reaction_time_speed, h.reaction_time_approach)
        rows = rows / self.dt + 2.0
        return 2 * 8 * rows * self.expected_vehicles() / 2**30


class ConfigError(ValueError):
    """A config could not be read or validated; the message names key, value and rule."""
