"""A corridor's road: a mainline with on-ramps, off-ramps, lane drops and speed-limit zones.

Positions x [m] run along the mainline from its upstream end (x = 0) to ``length``; lanes are
counted from the right. An on-ramp joins from the right at ``x``, where its lanes become
acceleration lanes to the right of the mainline that end at ``x + accel_length``; an
off-ramp's deceleration lanes open on the right at ``x`` and leave the road at
``x + decel_length``. A lane drop changes the mainline lane count from its ``x`` on (the
leftmost lanes end or start, so lane k counted from the right keeps its place).

:func:`sections` cuts the road into intervals of constant layout: the one description both
the SUMO export and a simulator read, so the two cannot disagree on where lanes are.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise
from typing import Any, Literal

from pydantic import Field, ModelWrapValidatorHandler, model_validator

from hcomc.corridor._base import ID_PATTERN, RESERVED_IDS, Frozen, RuleError

__all__ = ["LaneDrop", "OffRamp", "OnRamp", "Road", "Section", "SpeedLimit", "sections"]

_EPS = 1e-6  # [m] positions closer than this are the same point


class OnRamp(Frozen):
    """An on-ramp joining the mainline from the right through an acceleration lane."""

    id: str = Field(pattern=ID_PATTERN, description="ramp id (origin name in [demand])")
    x: float = Field(ge=0, description="start of the acceleration lane on the mainline [m]")
    accel_length: float = Field(
        250.0, gt=0, le=5000, description="length of the acceleration lane [m]"
    )
    control_zone_length: float = Field(
        300.0, ge=0, le=5000, description="cooperative control zone on the ramp, upstream of x [m]"
    )
    ramp_length: float = Field(
        450.0, ge=50, le=10_000, description="ramp road before the acceleration lane [m]"
    )
    lanes: int = Field(1, ge=1, le=2, description="ramp lanes (= acceleration lanes)")

    @property
    def end(self) -> float:
        """End of the acceleration lane [m]."""
        return self.x + self.accel_length


class OffRamp(Frozen):
    """An off-ramp leaving the mainline to the right after a deceleration lane."""

    id: str = Field(pattern=ID_PATTERN, description="ramp id (destination name in [demand])")
    x: float = Field(ge=0, description="start of the deceleration lane on the mainline [m]")
    decel_length: float = Field(
        200.0, gt=0, le=5000, description="length of the deceleration lane [m]"
    )
    ramp_length: float = Field(
        300.0, ge=50, le=10_000, description="ramp road after the deceleration lane [m]"
    )
    lanes: int = Field(1, ge=1, le=2, description="ramp lanes (= deceleration lanes)")

    @property
    def end(self) -> float:
        """Where the ramp leaves the mainline (end of the deceleration lane) [m]."""
        return self.x + self.decel_length


class LaneDrop(Frozen):
    """A change of the mainline lane count: the leftmost lanes end (or new ones start)."""

    x: float = Field(gt=0, description="where the new lane count starts [m]")
    lanes: int = Field(ge=1, le=6, description="mainline lanes from x on")


class SpeedLimit(Frozen):
    """A zone [x0, x1] with its own speed limit (mainline and its ramp lanes)."""

    x0: float = Field(ge=0, description="start of the zone [m]")
    x1: float = Field(gt=0, description="end of the zone [m]")
    speed: float = Field(gt=0, le=70, description="speed limit in the zone [m/s]")


class Road(Frozen):
    """The mainline and everything attached to it; ramps and zones may be listed in any
    order (they are sorted by x)."""

    lanes: int = Field(2, ge=1, le=6, description="mainline lanes at x = 0")
    length: float = Field(1500.0, ge=100, le=1_000_000, description="mainline length [m]")
    speed_limit: float = Field(33.3, gt=0, le=70, description="speed limit outside zones [m/s]")
    lane_width: float = Field(3.75, gt=2, le=6, description="lane width [m]")
    on_ramps: list[OnRamp] = Field(default_factory=list, description="on-ramps")
    off_ramps: list[OffRamp] = Field(default_factory=list, description="off-ramps")
    lane_drops: list[LaneDrop] = Field(default_factory=list, description="lane-count changes")
    speed_limits: list[SpeedLimit] = Field(default_factory=list, description="speed zones")

    @model_validator(mode="wrap")
    @classmethod
    def _checked_and_sorted(cls, data: Any, handler: ModelWrapValidatorHandler[Road]) -> Road:
        road = handler(data)
        _check(road)  # indices in messages are the user's, so check before sorting
        return road.model_copy(
            update={
                "on_ramps": sorted(road.on_ramps, key=lambda r: r.x),
                "off_ramps": sorted(road.off_ramps, key=lambda r: r.x),
                "lane_drops": sorted(road.lane_drops, key=lambda d: d.x),
                "speed_limits": sorted(road.speed_limits, key=lambda z: z.x0),
            }
        )

    @property
    def ramps(self) -> list[OnRamp | OffRamp]:
        """On- and off-ramps, each sorted by x."""
        return [*self.on_ramps, *self.off_ramps]

    def lanes_at(self, x: float) -> int:
        """Mainline lane count at position x [m] (a drop at x applies from x on)."""
        count = self.lanes
        for drop in sorted(self.lane_drops, key=lambda d: d.x):
            if drop.x <= x + _EPS:
                count = drop.lanes
        return count

    def speed_at(self, x: float) -> float:
        """Speed limit [m/s] at position x [m] (a zone boundary belongs downstream)."""
        for zone in self.speed_limits:
            if zone.x0 - _EPS <= x < zone.x1 - _EPS:
                return zone.speed
        return self.speed_limit


def _check(road: Road) -> None:
    """Raise :class:`RuleError` for the first rule ``road`` breaks."""
    seen: dict[str, str] = {}
    ramps: list[tuple[str, OnRamp | OffRamp]] = [
        *((f"on_ramps[{i}]", r) for i, r in enumerate(road.on_ramps)),
        *((f"off_ramps[{i}]", r) for i, r in enumerate(road.off_ramps)),
    ]
    for key, ramp in ramps:
        if ramp.id in RESERVED_IDS or ramp.id.startswith("main"):
            raise RuleError(f"{key}.id", ramp.id, "an id not starting with 'main' nor 'exit'")
        if ramp.id in seen:
            raise RuleError(
                f"{key}.id", ramp.id, f"an id not used before (used by {seen[ramp.id]})"
            )
        seen[ramp.id] = key
        last = road.length - (ramp.end - ramp.x)
        if ramp.end >= road.length - _EPS:
            what = "acceleration" if isinstance(ramp, OnRamp) else "deceleration"
            raise RuleError(
                f"{key}.x", ramp.x, f"0 <= x < {last:g} (the {what} lane must end before the "
                f"road's end, road.length = {road.length:g})"
            )  # fmt: skip
        if isinstance(ramp, OnRamp) and ramp.control_zone_length > ramp.ramp_length:
            raise RuleError(
                f"{key}.control_zone_length", ramp.control_zone_length,
                f"<= ramp_length = {ramp.ramp_length:g} (the control zone lies on the ramp)",
            )  # fmt: skip
    areas = sorted(
        ((ramp.x, ramp.end, key, ramp) for key, ramp in ramps), key=lambda a: (a[0], a[1])
    )
    for (_, up_end, up_key, up), (x, _, key, _) in pairwise(areas):
        if x < up_end - _EPS:
            raise RuleError(
                f"{key}.x", x, f"x >= {up_end:g}: its ramp lanes would overlap those of "
                f"{up_key} ('{up.id}', {up.x:g} to {up_end:g} m)"
            )  # fmt: skip
    _check_drops(road, areas)
    _check_zones(road)


def _check_drops(road: Road, areas: list[tuple[float, float, str, Any]]) -> None:
    count, previous = road.lanes, -1.0
    for i, drop in sorted(enumerate(road.lane_drops), key=lambda p: p[1].x):
        key = f"lane_drops[{i}]"
        if drop.x >= road.length - _EPS:
            raise RuleError(f"{key}.x", drop.x, f"0 < x < road.length = {road.length:g}")
        if abs(drop.x - previous) < _EPS:
            raise RuleError(f"{key}.x", drop.x, "one lane drop per position")
        for x0, x1, ramp_key, ramp in areas:
            if x0 + _EPS < drop.x < x1 - _EPS:
                raise RuleError(
                    f"{key}.x", drop.x, f"a position outside {ramp_key} ('{ramp.id}', "
                    f"{x0:g} to {x1:g} m): ramp lanes and lane drops may not overlap"
                )  # fmt: skip
        if drop.lanes == count:
            raise RuleError(
                f"{key}.lanes", drop.lanes, f"a lane count other than {count} (the count upstream)"
            )
        count, previous = drop.lanes, drop.x


def _check_zones(road: Road) -> None:
    zones = sorted(enumerate(road.speed_limits), key=lambda p: p[1].x0)
    for i, zone in zones:
        if zone.x1 <= zone.x0 or zone.x1 > road.length + _EPS:
            raise RuleError(
                f"speed_limits[{i}].x1", zone.x1,
                f"x0 = {zone.x0:g} < x1 <= road.length = {road.length:g}",
            )  # fmt: skip
    for (j, up), (i, zone) in pairwise(zones):
        if zone.x0 < up.x1 - _EPS:
            raise RuleError(
                f"speed_limits[{i}].x0", zone.x0,
                f"x0 >= {up.x1:g}: zones may not overlap (speed_limits[{j}] is "
                f"{up.x0:g} to {up.x1:g} m)",
            )  # fmt: skip


@dataclass(frozen=True, slots=True)
class Section:
    """A stretch [x0, x1] of constant layout.

    ``lanes`` mainline lanes, plus ``ramp_lanes`` extra lanes on their right that belong to
    ramp ``ramp``: acceleration lanes (``kind = "accel"``, they end at the on-ramp's end) or
    deceleration lanes (``kind = "decel"``, they leave the road at the off-ramp's end).
    """

    x0: float  # [m]
    x1: float  # [m]
    lanes: int
    ramp_lanes: int
    ramp: str | None
    kind: Literal["main", "accel", "decel"]
    speed_limit: float  # [m/s]

    @property
    def length(self) -> float:
        """Section length [m]."""
        return self.x1 - self.x0

    @property
    def total_lanes(self) -> int:
        """Mainline plus ramp lanes."""
        return self.lanes + self.ramp_lanes


def sections(road: Road) -> tuple[Section, ...]:
    """The road cut at every ramp end, lane drop and speed-zone boundary, upstream first."""
    cuts = {0.0, road.length}
    for ramp in road.ramps:
        cuts |= {ramp.x, ramp.end}
    cuts |= {d.x for d in road.lane_drops}
    for zone in road.speed_limits:
        cuts |= {zone.x0, min(zone.x1, road.length)}
    xs: list[float] = []
    for x in sorted(cuts):
        if not xs or x - xs[-1] > _EPS:
            xs.append(x)
    out = []
    for x0, x1 in pairwise(xs):
        mid = 0.5 * (x0 + x1)
        ramp_lanes, ramp_id = 0, None
        kind: Literal["main", "accel", "decel"] = "main"
        for ramp in road.ramps:
            if ramp.x < mid < ramp.end:
                ramp_lanes, ramp_id = ramp.lanes, ramp.id
                kind = "accel" if isinstance(ramp, OnRamp) else "decel"
        out.append(
            Section(x0, x1, road.lanes_at(mid), ramp_lanes, ramp_id, kind, road.speed_at(mid))
        )
    return tuple(out)
