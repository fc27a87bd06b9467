"""A whole corridor: run settings, road, demand, vehicle classes and detector layout.

This is what a corridor file holds (tables ``[corridor]``, ``[road]``, ``[demand.<origin>]``,
``[vehicles.<class>]``, ``[detectors]``) and what :func:`hcomc.corridor.loading.load_corridor`
returns. The rules that tie the tables together live here: origins are ``main`` or on-ramp
ids, destinations lie downstream of their origin, class names exist. Profile points after
the duration are allowed (a shorter run, ``--duration``, simply ends before them).
"""

from __future__ import annotations

import re
from typing import Annotated, Any

from pydantic import Field, field_validator, model_validator

from hcomc.config import MIN_STEP, ControlParams, LaneChangeParams, merge_tables
from hcomc.config.impairment_tables import (
    MAX_FAULTS,
    ChannelParams,
    FaultParams,
    ShieldParams,
    fault_entries,
)
from hcomc.corridor._base import NO_VALUE, Frozen, RuleError
from hcomc.corridor.demand import DEFAULT_CLASSES, OriginDemand, VehicleClass
from hcomc.corridor.road import Road, sections

__all__ = [
    "MAX_DURATION",
    "Corridor",
    "DetectorSettings",
    "LaneChanges",
    "MergeEvents",
    "RouteRules",
    "RunSettings",
    "detector_positions",
]

_EPS = 1e-6
_CLASS_NAME = r"[A-Za-z][A-Za-z0-9_-]*"  # part of SUMO vType ids


MAX_DURATION = 86_400.0
"""Longest corridor run [s]: a day."""


class RunSettings(Frozen):
    """The ``[corridor]`` table: name, duration and simulation settings."""

    name: str = Field("corridor", pattern=r"^[\w.-]+$", description="corridor name")
    description: str = Field("", description="free text")
    duration: float = Field(3600.0, gt=0, le=MAX_DURATION, description="simulated time [s]")
    warmup: float = Field(
        0.0, ge=0, le=3600,
        description="simulated before 'duration' and not measured (the paper's conditions "
        "start from developed traffic) [s]; hcomc's scenario engine only",
    )  # fmt: skip
    seed: int = Field(0, ge=0, description="random seed (vehicle classes, SUMO's randomness)")
    step_length: float = Field(0.1, ge=MIN_STEP, le=1, description="simulation step [s]")
    lane_change_duration: float = Field(
        3.0, ge=0, le=15, description="duration of a lane change [s]; 0 = instantaneous"
    )


class DetectorSettings(Frozen):
    """Induction loops across every mainline lane (counts, speeds, occupancy per period)."""

    spacing: float = Field(
        1000.0,
        ge=0,
        description="one cross-section every this many metres from x = 0; 0 = none [m]",
    )
    around_ramps: bool = Field(
        True, description="also one cross-section just upstream and downstream of each ramp"
    )
    ramp_offset: float = Field(
        50.0, gt=0, le=1000, description="distance of those from the ramp's lanes [m]"
    )
    positions: list[float] = Field(
        default_factory=list, description="further cross-sections at these x [m]"
    )
    period: float = Field(60.0, gt=0, le=3600, description="aggregation period [s]")
    cell_length: float = Field(
        100.0, ge=10, le=10_000,
        description="length of the space-time grid's cells (Edie's measures) [m]; their "
        "duration is the period",
    )  # fmt: skip


_MOBIL = LaneChangeParams.model_fields


class LaneChanges(Frozen):
    """The ``[lane_change]`` table: MOBIL's discretionary changes (Kesting, Treiber & Helbing
    2007) and the gap acceptance of mandatory ones, with hcomc's defaults for them."""

    politeness: Annotated[float, _MOBIL["politeness"]]
    threshold: Annotated[float, _MOBIL["threshold"]]
    keep_right_bias: Annotated[float, _MOBIL["keep_right_bias"]]
    safe_decel: Annotated[float, _MOBIL["safe_decel"]]
    min_gap: Annotated[float, _MOBIL["min_gap"]]
    decision_interval: Annotated[float, _MOBIL["decision_interval"]]
    emergency_decel: Annotated[float, _MOBIL["emergency_decel"]]


class RouteRules(Frozen):
    """The ``[routes]`` table: when a vehicle starts the changes its route needs.

    On the ``corridor`` preset's hour, with 400 m per change 103 of the vehicles bound for an
    off-ramp missed it (the changes came too late in dense traffic), with 700 m 25, with
    1000 m 5."""

    exit_lookahead: Annotated[float, _MOBIL["exit_lookahead"]]
    urgent_distance: Annotated[float, _MOBIL["urgent_distance"]]


class MergeEvents(Frozen):
    """The ``[merges]`` table: how a merge event is measured.

    An event begins when a ramp vehicle (VR) enters its on-ramp's control zone, with the key
    vehicles of paper Section II-A identified then (with or without a controller, so runs
    compare the same vehicles), and its window ends ``window_after`` seconds after VR's merge
    is complete (or when VR leaves the road, or the run ends)."""

    window_after: float = Field(
        10.0, ge=0, le=120,
        description="a merge event's window ends this long after VR's merge is complete [s]",
    )  # fmt: skip


class Corridor(Frozen):
    """A corridor: road and demand that a simulator (for now SUMO) runs."""

    corridor: RunSettings = Field(default_factory=RunSettings)
    road: Road = Field(default_factory=Road)
    demand: dict[str, OriginDemand] = Field(description="demand per origin (main, on-ramp ids)")
    vehicles: dict[str, VehicleClass] = Field(default_factory=dict)
    detectors: DetectorSettings = Field(default_factory=DetectorSettings)
    lane_change: LaneChanges = Field(default_factory=lambda: LaneChanges.model_validate({}))
    routes: RouteRules = Field(default_factory=lambda: RouteRules.model_validate({}))
    control: ControlParams = Field(
        default_factory=lambda: ControlParams.model_validate({}),
        description="the merge controller at every on-ramp and its settings (as a "
        "scenario's [control] table)",
    )
    merges: MergeEvents = Field(default_factory=MergeEvents)
    v2x: ChannelParams = Field(default_factory=ChannelParams)
    faults: tuple[FaultParams, ...] = Field(
        (), max_length=MAX_FAULTS,
        description="faults injected into the run (as a scenario's [[faults]])",
    )  # fmt: skip
    shield: ShieldParams = Field(default_factory=ShieldParams)

    _fault_entries = field_validator("faults", mode="before")(fault_entries)

    def impairment_tables(self) -> dict[str, Any]:
        """The ``[v2x]``, ``[[faults]]`` and ``[shield]`` tables, as a scenario takes them."""
        return {
            "v2x": self.v2x.model_dump(), "faults": [f.model_dump() for f in self.faults],
            "shield": self.shield.model_dump(),
        }  # fmt: skip

    @model_validator(mode="before")
    @classmethod
    def _default_classes(cls, data: Any) -> Any:
        """The built-in classes under whatever the file sets (key by key)."""
        if not isinstance(data, dict):
            return data
        given = data.get("vehicles", {})
        if not isinstance(given, dict):
            return data
        merged = {name: _merged(base, given.get(name)) for name, base in DEFAULT_CLASSES.items()}
        merged.update({k: v for k, v in given.items() if k not in DEFAULT_CLASSES})
        return {**data, "vehicles": merged}

    @model_validator(mode="after")
    def _consistent(self) -> Corridor:
        for name in self.vehicles:
            if not re.fullmatch(_CLASS_NAME, name):
                raise RuleError(
                    f"vehicles.{name}", NO_VALUE, "a letter, then letters, digits, '_' or '-'",
                    "not a class name",
                )  # fmt: skip
        _check_demand(self)
        first = sections(self.road)[0]
        longest = max(self.vehicles.items(), key=lambda item: item[1].length)
        if first.length < longest[1].length:
            raise RuleError(
                "road", NO_VALUE, f"ramps, lane drops and zones at x >= {longest[1].length:g} "
                "or at 0 (mainline vehicles enter on the first section)",
                f"the first section is {first.length:g} m long, shorter than class "
                f"'{longest[0]}' ({longest[1].length:g} m)",
            )  # fmt: skip
        for k, x in enumerate(self.detectors.positions):
            if not 0 < x < self.road.length:
                raise RuleError(
                    f"detectors.positions[{k}]", x, f"0 < x < road.length = {self.road.length:g}"
                )
        return self

    @property
    def name(self) -> str:
        """The corridor's name."""
        return self.corridor.name

    def origin_x(self, origin: str) -> float:
        """Where an origin's vehicles reach the mainline [m] (0 for ``main``)."""
        return next((r.x for r in self.road.on_ramps if r.id == origin), 0.0)


def _merged(base: dict[str, Any], update: Any) -> Any:
    """A class's table ``update`` over the built-in ``base`` (None: the base; not a table:
    left for validation to report)."""
    if not isinstance(update, dict):
        return base if update is None else update
    return merge_tables(base, update)


def _check_demand(c: Corridor) -> None:
    on_ids = [r.id for r in c.road.on_ramps]
    if not c.demand:
        raise RuleError("demand", {}, f"at least one origin: {', '.join(['main', *on_ids])}")
    for origin, demand in c.demand.items():
        key = f"demand.{origin}"
        if origin != "main" and origin not in on_ids:
            raise RuleError(
                key, NO_VALUE, ", ".join(["main", *on_ids]), "no such origin (main or an on-ramp)"
            )
        _check_origin_kind(c, origin, demand)
        for name in demand.classes:
            if name not in c.vehicles:
                raise RuleError(
                    f"{key}.classes.{name}", NO_VALUE, ", ".join(c.vehicles), "no such class"
                )
        start = next((r.end for r in c.road.on_ramps if r.id == origin), 0.0)
        downstream = [r.id for r in c.road.off_ramps if r.x >= start - _EPS]
        allowed = ", ".join(["exit", *downstream])
        for dest in demand.destinations:
            if dest == "exit" or dest in downstream:
                continue
            upstream = next((r for r in c.road.off_ramps if r.id == dest), None)
            problem = (
                "no such destination"
                if upstream is None
                else f"off-ramp '{dest}' (at {upstream.x:g} m) is not downstream of the origin "
                f"(on the mainline from {start:g} m)"
            )
            raise RuleError(f"{key}.destinations.{dest}", NO_VALUE, allowed, problem)


def _check_origin_kind(c: Corridor, origin: str, demand: OriginDemand) -> None:
    """Lane flows belong to the mainline (one per lane), a single release to an on-ramp."""
    key = f"demand.{origin}"
    lanes = demand.lane_flows
    if lanes is not None and origin != "main":
        raise RuleError(f"{key}.lane_flows", lanes, "lane flows at the origin main only")
    if lanes is not None and len(lanes) != c.road.lanes:
        raise RuleError(f"{key}.lane_flows", lanes, f"one flow per lane: {c.road.lanes}")
    if demand.release is not None and origin == "main":
        raise RuleError(f"{key}.release", demand.release, "a release at an on-ramp only")


def detector_positions(c: Corridor) -> list[float]:
    """Cross-sections x [m] of the induction loops, sorted, inside (0, road.length)."""
    d, road = c.detectors, c.road
    xs = list(d.positions)
    if d.spacing > 0:
        xs += [k * d.spacing for k in range(1, int(road.length / d.spacing) + 1)]
    if d.around_ramps:
        for ramp in road.ramps:
            xs += [ramp.x - d.ramp_offset, ramp.end + d.ramp_offset]
    out: list[float] = []
    for x in sorted(x for x in xs if 0 < x < road.length - _EPS):
        if not out or x - out[-1] > 0.5:
            out.append(round(x, 3))
    return out
