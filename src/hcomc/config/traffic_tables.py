"""The traffic tables of a scenario: the road, the demand on it, and the platoon scenario.

``[road]`` is the two-lane highway with its on-ramp (paper Section II-A), ``[demand]`` the
vehicles released onto it (Table I), ``[platoon]`` the scripted-leader platoon of the
car-following studies. Units and defaults are in each field's description.
"""

from __future__ import annotations

from itertools import pairwise
from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from hcomc.config.frozen_model import FrozenModel

__all__ = ["DemandParams", "PlatoonParams", "RoadParams"]

MIN_HEADWAY = 0.1
"""Shortest headway between two vehicles entering one lane [s]."""


class RoadParams(FrozenModel):
    """Two-lane highway with an on-ramp and acceleration lane (paper Section II-A).

    Lane 2 (outer) has its centre at y = +W, lane 1 at y = 0, the ramp and acceleration lane
    at y = -W. The ramp runs parallel to lane 1 from ``ramp_start``; merging is allowed on
    the acceleration lane ``[accel_lane_start, accel_lane_end]``, which ends there.
    """

    length: float = Field(1500.0, gt=100, le=1_000_000, description="mainline length [m]")
    lane_width: float = Field(3.75, gt=2, le=6, description="W, lane width [m]")
    accel_lane_start: float = Field(700.0, ge=0, description="start of the acceleration lane [m]")
    accel_lane_end: float = Field(950.0, gt=0, description="end of the acceleration lane [m]")
    ramp_start: float = Field(250.0, ge=0, description="where ramp vehicles enter [m]")
    control_zone_length: float = Field(
        300.0, ge=0, description="cooperative control zone upstream of the acceleration lane [m]"
    )
    vehicle_length: float = Field(5.0, gt=1, le=25, description="vehicle length [m]")
    vehicle_width: float = Field(1.8, gt=0.5, le=3, description="vehicle width [m]")

    @model_validator(mode="after")
    def _ordered(self) -> RoadParams:
        if not self.ramp_start < self.accel_lane_start < self.accel_lane_end < self.length:
            raise ValueError(
                "need ramp_start < accel_lane_start < accel_lane_end < length, got "
                f"{self.ramp_start} < {self.accel_lane_start} < {self.accel_lane_end} "
                f"< {self.length}"
            )
        return self

    @property
    def control_zone_start(self) -> float:
        """Upstream end of the cooperative control zone [m]."""
        return max(0.0, self.accel_lane_start - self.control_zone_length)


class DemandParams(FrozenModel):
    """Traffic demand: headways per lane, CAV share, insertion speeds (paper Table I).

    ``pattern = "random"``: headways are ``min_headway + Exp(mean - min_headway)``, so the
    mean is exactly the condition's average time headway, and each vehicle is a CAV with
    probability ``cav_penetration``. ``pattern = "uniform"`` (the deterministic paper
    scenario): every headway equals the mean and CAVs are spread evenly with the exact
    share. The ramp either releases one key merging vehicle (``ramp = "single"``, the
    paper's setting) or a continuous flow. Mainline vehicles enter at ``main_speed``: a
    fixed speed [m/s], or ``"equilibrium"``, the lane's IDM steady-state speed for its
    mean headway (see :mod:`hcomc.sim.demand`).
    """

    mean_headway_main_1: float = Field(5.0, gt=0, le=3600, description="lane 1 mean headway [s]")
    mean_headway_main_2: float = Field(5.0, gt=0, le=3600, description="lane 2 mean headway [s]")
    min_headway: float = Field(
        1.0, ge=MIN_HEADWAY, le=60, description="minimum (shift) headway [s]"
    )
    cav_penetration: float = Field(0.9, ge=0, le=1, description="share of CAVs [-]")
    main_speed: float | Literal["equilibrium"] = Field(
        "equilibrium",
        description="mainline insertion speed: a fixed speed [m/s] (0 < v <= 70) or "
        "'equilibrium' (each lane's IDM steady state for its mean headway)",
    )
    pattern: Literal["random", "uniform"] = Field(
        "random",
        description="'random' = shifted exponential headways and random CAV assignment; "
        "'uniform' = every headway equal to the mean, CAVs spread evenly (no randomness)",
    )
    ramp: Literal["single", "flow", "none"] = Field(
        "single", description="'single' key merge, 'flow' continuous ramp demand, 'none'"
    )
    ramp_entry_time: float = Field(
        5.0, ge=0, description="'single': release time after warm-up [s]"
    )
    ramp_mean_headway: float = Field(20.0, gt=0, le=3600, description="'flow': ramp headway [s]")
    ramp_speed: float = Field(22.0, gt=0, le=70, description="insertion speed, ramp [m/s]")

    @field_validator("main_speed", mode="before")
    @classmethod
    def _main_speed(cls, value: Any) -> Any:
        if value == "equilibrium":
            return value
        if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value <= 70:
            raise ValueError("allowed: a speed in (0, 70] m/s or 'equilibrium'")
        return value

    @model_validator(mode="after")
    def _headways(self) -> DemandParams:
        for key in ("mean_headway_main_1", "mean_headway_main_2", "ramp_mean_headway"):
            value = getattr(self, key)
            if value <= self.min_headway:
                raise ValueError(
                    f"{key} = {value} must be greater than min_headway = {self.min_headway}"
                )
        return self


class PlatoonParams(FrozenModel):
    """Scripted-leader platoon on one lane (car-following and string-stability studies).

    The leader follows the piecewise-linear speed profile through ``profile`` points
    ``[[t0, v0], [t1, v1], ...]`` (time [s], speed [m/s]); K followers of one kind start at
    their equilibrium gap behind it.
    """

    followers: int = Field(10, ge=1, le=100_000, description="K, number of followers")
    kind: Literal["hdv", "cav"] = Field("hdv", description="follower kind")
    initial_speed: float = Field(25.0, ge=0, le=70, description="initial speed [m/s]")
    profile: list[tuple[float, float]] = Field(
        default_factory=lambda: [
            (0.0, 25.0),
            (10.0, 25.0),
            (15.0, 15.0),
            (40.0, 15.0),
            (50.0, 25.0),
        ],
        max_length=10_000,
        description="leader speed profile points (t [s], v [m/s]), linear in between",
    )

    @model_validator(mode="after")
    def _profile(self) -> PlatoonParams:
        times = [p[0] for p in self.profile]
        if len(times) < 1 or any(b <= a for a, b in pairwise(times)):
            raise ValueError(f"profile times must be strictly increasing, got {times}")
        if any(p[1] < 0 for p in self.profile):
            raise ValueError("profile speeds must be >= 0")
        return self
