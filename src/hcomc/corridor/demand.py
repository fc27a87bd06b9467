"""A corridor's demand: a flow per origin over time, its CAV share, class mix and destinations,
and the vehicle classes with their car-following parameters.

An origin is ``main`` (the mainline's upstream end) or an on-ramp id. Its flow q(t) [veh/h]
is given by points (t [s], q [veh/h]); ``profile = "constant"`` holds each point's flow until
the next point, ``"linear"`` interpolates between points; after the last point the flow stays
at its value. A single number is a constant flow. :meth:`OriginDemand.intervals` turns either
into piecewise-constant intervals that carry exactly the profile's vehicles, which is what a
flow-based simulator (SUMO's ``<flow>``) can take.

Vehicle classes (``car``, ``truck`` or any other name) drive the Intelligent Driver Model
(Treiber, Hennecke & Helbing 2000) with their own length and parameters; a CAV of a class
uses the same model with the values of its ``cav`` table (by default a shorter time headway).
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from hcomc.corridor._base import Frozen, RuleError

__all__ = ["DEFAULT_CLASSES", "CAVOverrides", "OriginDemand", "VehicleClass"]

_SUM_TOLERANCE = 1e-6


class CAVOverrides(Frozen):
    """The CAV version of a class: the IDM values that differ from the human driver's
    (unset = the same as the class's)."""

    desired_speed: float | None = Field(None, gt=0, le=70, description="v0 [m/s]")
    time_headway: float | None = Field(None, gt=0, le=10, description="T [s]")
    min_gap: float | None = Field(None, ge=0, le=20, description="s0 [m]")
    max_accel: float | None = Field(None, gt=0, le=10, description="a [m/s^2]")
    comfort_decel: float | None = Field(None, gt=0, le=10, description="b [m/s^2]")


class VehicleClass(Frozen):
    """A vehicle class: body, top speed and IDM parameters of its human drivers."""

    length: float = Field(5.0, gt=1, le=30, description="vehicle length [m]")
    width: float = Field(1.8, gt=0.5, le=3, description="vehicle width [m]")
    max_speed: float = Field(50.0, gt=0, le=90, description="technical top speed [m/s]")
    desired_speed: float = Field(33.3, gt=0, le=70, description="v0, desired speed [m/s]")
    time_headway: float = Field(1.5, gt=0, le=10, description="T, safe time headway [s]")
    min_gap: float = Field(2.0, ge=0, le=20, description="s0, jam distance [m]")
    max_accel: float = Field(1.0, gt=0, le=10, description="a, maximum acceleration [m/s^2]")
    comfort_decel: float = Field(
        2.0, gt=0, le=10, description="b, comfortable deceleration [m/s^2]"
    )
    exponent: float = Field(4.0, gt=0, le=20, description="delta, acceleration exponent [-]")
    vclass: Literal["passenger", "truck", "trailer", "bus", "coach", "delivery"] = Field(
        "passenger", description="SUMO vehicle class (permissions and emission defaults)"
    )
    cav: CAVOverrides = Field(
        default_factory=CAVOverrides, description="IDM values of the class's CAVs"
    )

    @model_validator(mode="after")
    def _speeds(self) -> VehicleClass:
        for key, value in (("desired_speed", self.desired_speed),
                           ("cav.desired_speed", self.cav.desired_speed)):  # fmt: skip
            if value is not None and value > self.max_speed:
                raise RuleError(key, value, f"<= max_speed = {self.max_speed:g}")
        return self

    def idm(self, cav: bool) -> dict[str, float]:
        """The IDM parameters of this class's HDVs, or of its CAVs with ``cav``."""
        params = {
            "desired_speed": self.desired_speed,
            "time_headway": self.time_headway,
            "min_gap": self.min_gap,
            "max_accel": self.max_accel,
            "comfort_decel": self.comfort_decel,
            "exponent": self.exponent,
        }
        if cav:
            params.update({k: v for k, v in self.cav.model_dump().items() if v is not None})
        return params


DEFAULT_CLASSES: dict[str, dict[str, Any]] = {
    # the HDV values of hcomc's own engine (docs/models.md); CAVs as its CAV defaults
    "car": {"cav": {"time_headway": 1.0, "max_accel": 1.4}},
    # a heavy goods vehicle: articulated length, 90 km/h speed limiter, gentler
    # acceleration and braking, a longer headway
    "truck": {
        "length": 16.5,
        "width": 2.55,
        "max_speed": 25.0,
        "desired_speed": 25.0,
        "time_headway": 1.8,
        "min_gap": 3.0,
        "max_accel": 0.5,
        "comfort_decel": 1.5,
        "vclass": "truck",
        "cav": {"time_headway": 1.2},
    },
}
"""Built-in classes; a file's ``[vehicles.car]`` or ``[vehicles.truck]`` changes only the
keys it names."""


class OriginDemand(Frozen):
    """Demand entering at one origin (``main`` or an on-ramp id)."""

    flow: list[tuple[float, float]] = Field(
        description="profile points (t [s], flow [veh/h]), or one number: a constant flow"
    )
    profile: Literal["constant", "linear"] = Field(
        "constant",
        description="'constant': each point's flow holds until the next point; 'linear': "
        "interpolated between points",
    )
    cav_share: float = Field(0.0, ge=0, le=1, description="share of CAVs [-]")
    classes: dict[str, float] = Field(
        default_factory=lambda: {"car": 0.9, "truck": 0.1},
        description="share of each vehicle class [-], summing to 1",
    )
    destinations: dict[str, float] = Field(
        default_factory=lambda: {"exit": 1.0},
        description="share per destination [-] ('exit' or a downstream off-ramp id), summing to 1",
    )
    lane_flows: list[float] | None = Field(
        None,
        description="the mainline origin only: the flow of each mainline lane [veh/h], given "
        "instead of 'flow' (paper Table I sets a mean headway per lane); hcomc's scenario "
        "engine only",
    )
    release: float | None = Field(
        None,
        ge=0,
        le=3600,
        description="an on-ramp only: one vehicle enters at this time after the warm-up [s], "
        "instead of a flow (the paper's single merging vehicle); hcomc's scenario engine only",
    )

    @model_validator(mode="before")
    @classmethod
    def _flow_of_alternatives(cls, data: Any) -> Any:
        """Without ``flow``: the sum of ``lane_flows``, or 0 beside a ``release``."""
        if not isinstance(data, dict) or "flow" in data:
            return data
        lanes = data.get("lane_flows")
        if isinstance(lanes, list) and all(isinstance(q, int | float) for q in lanes):
            return {**data, "flow": float(sum(lanes))}
        if data.get("release") is not None:
            return {**data, "flow": 0.0}
        return data

    @field_validator("flow", mode="before")
    @classmethod
    def _constant(cls, value: Any) -> Any:
        if isinstance(value, int | float) and not isinstance(value, bool):
            return [(0.0, value)]
        return value

    @model_validator(mode="after")
    def _rules(self) -> OriginDemand:
        if not self.flow:
            raise RuleError("flow", self.flow, "at least one point (t [s], flow [veh/h])")
        if self.flow[0][0] != 0:
            raise RuleError("flow[0]", list(self.flow[0]), "a first point at t = 0")
        for k, (t, q) in enumerate(self.flow):
            if k and t <= self.flow[k - 1][0]:
                raise RuleError(
                    f"flow[{k}]", [t, q], f"t > {self.flow[k - 1][0]:g} (times strictly increasing)"
                )
            if not 0 <= q <= 20_000:
                raise RuleError(f"flow[{k}]", [t, q], "a flow 0 <= q <= 20000 veh/h")
        for key in ("classes", "destinations"):
            shares: dict[str, float] = getattr(self, key)
            for name, share in shares.items():
                if not 0 <= share <= 1:
                    raise RuleError(f"{key}.{name}", share, "a share in [0, 1]")
            total = sum(shares.values())
            if abs(total - 1) > _SUM_TOLERANCE:
                raise RuleError(key, shares, f"shares summing to 1 (they sum to {total:.6g})")
        self._check_alternatives()
        return self

    def _check_alternatives(self) -> None:
        """``lane_flows`` and ``release`` replace a constant ``flow``; they never contradict it."""
        if self.lane_flows is not None:
            for k, q in enumerate(self.lane_flows):
                if not 0 < q <= 20_000:
                    raise RuleError(f"lane_flows[{k}]", q, "a flow 0 < q <= 20000 veh/h")
            total = sum(self.lane_flows)
            if self.flow != [(0.0, total)]:
                raise RuleError(
                    "flow", [list(p) for p in self.flow],
                    f"no 'flow' beside lane_flows (or their sum, {total:g}, as one constant)",
                )  # fmt: skip
        if self.release is not None:
            if self.lane_flows is not None:
                raise RuleError("release", self.release, "no release beside lane_flows")
            if self.flow != [(0.0, 0.0)]:
                raise RuleError(
                    "flow", [list(p) for p in self.flow], "no 'flow' beside a release (or 0)"
                )

    def rate(self, t: float) -> float:
        """Flow q(t) [veh/h] at time t >= 0 [s]."""
        for a, b, qa, qb in self._segments(max(t, self.flow[-1][0]) + 1.0):
            if a <= t < b:
                return qa + (qb - qa) * (t - a) / (b - a)
        return self.flow[-1][1]

    def vehicles(self, t0: float, t1: float) -> float:
        """Expected number of vehicles entering in [t0, t1] [s]: the profile's integral."""
        total = 0.0
        for a, b, qa, qb in self._segments(max(t1, self.flow[-1][0]) + 1.0):
            lo, hi = max(a, t0), min(b, t1)
            if hi > lo:
                q_lo = qa + (qb - qa) * (lo - a) / (b - a)
                q_hi = qa + (qb - qa) * (hi - a) / (b - a)
                total += 0.5 * (q_lo + q_hi) * (hi - lo) / 3600.0
        return total

    def intervals(self, duration: float, step: float = 60.0) -> list[tuple[float, float, float]]:
        """Piecewise-constant intervals (begin [s], end [s], flow [veh/h]) covering
        [0, duration].

        A constant profile gives one interval per point; a linear one is cut into intervals
        of at most ``step`` seconds (and at every point), each with the mean flow over it, so
        every interval carries exactly the profile's number of vehicles.
        """
        out = []
        for a, b, qa, qb in self._segments(duration):
            pieces = 1 if qa == qb else max(1, math.ceil((b - a) / step - 1e-9))
            for j in range(pieces):
                t0, t1 = a + (b - a) * j / pieces, a + (b - a) * (j + 1) / pieces
                mean = qa + (qb - qa) * (j + 0.5) / pieces  # linear: mean = value at the middle
                out.append((t0, t1, mean))
        return out

    def _segments(self, end: float) -> list[tuple[float, float, float, float]]:
        """(a [s], b [s], q at a, q just before b [veh/h]) between the points, the last one
        running to ``end``; within each, q is linear (constant for a constant profile)."""
        out = []
        for k, (a, qa) in enumerate(self.flow):
            if a >= end:
                break
            last = k == len(self.flow) - 1
            b = end if last else min(self.flow[k + 1][0], end)
            qb = qa if last or self.profile == "constant" else self.flow[k + 1][1]
            if not last and b < self.flow[k + 1][0]:  # cut short by ``end``
                qb = qa + (qb - qa) * (b - a) / (self.flow[k + 1][0] - a)
            out.append((a, b, qa, qb))
        return out
