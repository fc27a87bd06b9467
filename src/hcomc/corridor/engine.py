"""The corridors hcomc's own engine runs: those with the paper's layout, as a scenario config.

hcomc's engine simulates the paper's road (Section II-A): two mainline lanes, one single-lane
on-ramp with its acceleration lane, no off-ramps, constant demand. A corridor of that layout
(the ``paper`` preset, or a file based on it) becomes a :class:`~hcomc.config.ScenarioConfig`
with :func:`scenario_of` — so the same description runs in our engine and, exported, in SUMO.
Any other corridor is refused with the key that does not fit; it runs in SUMO.

The translation: road geometry one to one (the ramp enters at ``x - ramp_length``); the
mainline flow split equally over the two lanes as mean headways (``2 · 3600 / flow`` s per
lane), or each lane's own flow (``lane_flows``: paper Table I's headway per lane); the ramp
flow as a continuous ramp demand (``3600 / flow`` s), or one vehicle released at
``release`` s (the paper's single merging vehicle); headways to the nanosecond; one CAV
share; the one vehicle class's length and IDM parameters for the HDVs, with its CAV values
for the CAVs (the engine's HDVs keep their reaction delays and estimation errors, paper
Eq. 2, which SUMO's IDM does not have); the corridor's warm-up (0 by default, since SUMO's
road starts empty too); no merge controller unless one is given. The presets ``paper-C1``
... ``paper-C5`` are the conditions C1-C5 written this way: their scenario configs equal the
conditions' except for name and description, so they run bit for bit the same.
"""

from __future__ import annotations

import os
from typing import Any

from hcomc.config import ConfigError, ScenarioConfig, load_config, merge_tables
from hcomc.corridor.demand import OriginDemand, VehicleClass
from hcomc.corridor.model import Corridor
from hcomc.corridor.road import OnRamp

__all__ = ["ramp_road", "scenario_config", "scenario_of", "scenario_only"]

_SUMO = "run it in SUMO: hcomc export sumo"


def _refuse(key: str, value: Any, allowed: str) -> ConfigError:
    return ConfigError(f"key '{key}' = {value!r}: hcomc's engine runs the paper's layout only; "
                       f"allowed: {allowed} ({_SUMO})")  # fmt: skip


def scenario_only(c: Corridor) -> tuple[str, Any] | None:
    """The first key of ``c`` that only hcomc's scenario engine runs, with its value: a
    warm-up, per-lane mainline flows, a single ramp release (the paper's conditions C1-C5,
    presets ``paper-C1`` ... ``paper-C5``); None if there is none."""
    if c.corridor.warmup > 0:
        return "corridor.warmup", c.corridor.warmup
    for origin, demand in c.demand.items():
        if demand.lane_flows is not None:
            return f"demand.{origin}.lane_flows", demand.lane_flows
        if demand.release is not None:
            return f"demand.{origin}.release", demand.release
    return None


def _headway(flow: float) -> float:
    """Mean headway [s] of a flow [veh/h], to the nanosecond: a flow written with 16 digits
    (3600 / 7 s = 514.2857142857143 veh/h) gives back the headway it came from."""
    return round(3600.0 / flow, 9)


def _lane_headways(main: OriginDemand) -> tuple[float, float]:
    """Mean headways of mainline lanes 1 and 2 [s]: the lane flows', or the one flow split
    equally."""
    if main.lane_flows is not None:
        first, second = main.lane_flows
        return _headway(first), _headway(second)
    flow = _constant("main", main)
    return _headway(flow / 2), _headway(flow / 2)


def _ramp_demand(key: str, demand: OriginDemand) -> dict[str, Any]:
    """The scenario's ramp keys: one release (``ramp = "single"``) or a continuous flow."""
    if demand.release is not None:
        _destinations(key, demand)
        return {"ramp": "single", "ramp_entry_time": demand.release}
    return {"ramp": "flow", "ramp_mean_headway": _headway(_constant(key, demand))}


def _destinations(key: str, demand: OriginDemand) -> None:
    if set(demand.destinations) != {"exit"}:
        raise _refuse(f"demand.{key}.destinations", demand.destinations, "{ exit = 1.0 }")


def _constant(key: str, demand: OriginDemand) -> float:
    flows = {f for _, f in demand.flow}
    if len(flows) != 1:
        raise _refuse(f"demand.{key}.flow", [list(p) for p in demand.flow], "a constant flow")
    flow = flows.pop()
    if flow <= 0:
        raise _refuse(f"demand.{key}.flow", flow, "a flow > 0 veh/h")
    _destinations(key, demand)
    return flow


def _one_class(c: Corridor) -> tuple[str, VehicleClass]:
    used = {name for d in c.demand.values() for name, share in d.classes.items() if share > 0}
    if len(used) != 1:
        raise _refuse("demand.*.classes", sorted(used), "one vehicle class for every origin")
    name = used.pop()
    return name, c.vehicles[name]


def _idm(vehicle: VehicleClass) -> dict[str, float]:
    keys = ("desired_speed", "time_headway", "min_gap", "max_accel", "comfort_decel", "exponent")
    return {k: getattr(vehicle, k) for k in keys}


def _layout(c: Corridor) -> None:
    road = c.road
    checks = [
        ("road.lanes", road.lanes, road.lanes == 2, "2"),
        ("road.on_ramps", len(road.on_ramps), len(road.on_ramps) == 1, "one on-ramp"),
        ("road.off_ramps", len(road.off_ramps), not road.off_ramps, "none"),
        ("road.lane_drops", len(road.lane_drops), not road.lane_drops, "none"),
        ("road.speed_limits", len(road.speed_limits), not road.speed_limits, "none"),
    ]
    for key, value, fits, allowed in checks:
        if not fits:
            raise _refuse(key, value, allowed)
    if road.on_ramps[0].lanes != 1:
        raise _refuse("road.on_ramps[0].lanes", road.on_ramps[0].lanes, "1")


def ramp_road(c: Corridor, ramp: OnRamp, vehicle: VehicleClass) -> dict[str, float]:
    """The scenario's ``[road]`` table for ``ramp`` of ``c``: the paper's road with the
    ramp's geometry in corridor coordinates (the ramp road enters at ``x - ramp_length``),
    bodies of ``vehicle``'s class."""
    return {
        "length": c.road.length, "lane_width": c.road.lane_width,
        "accel_lane_start": ramp.x, "accel_lane_end": ramp.x + ramp.accel_length,
        "ramp_start": ramp.x - ramp.ramp_length,
        "control_zone_length": ramp.control_zone_length,
        "vehicle_length": vehicle.length, "vehicle_width": vehicle.width,
    }  # fmt: skip


def scenario_of(c: Corridor, **overrides: Any) -> ScenarioConfig:
    """The scenario config of corridor ``c`` for hcomc's engine (module docstring), with
    ``overrides`` as :func:`hcomc.config.load_config` takes them; a :class:`ConfigError`
    naming the key when the corridor does not have the paper's layout."""
    _layout(c)
    ramp = c.road.on_ramps[0]
    if set(c.demand) != {"main", ramp.id}:
        raise _refuse("demand", sorted(c.demand), f"the origins main and {ramp.id}")
    lane_1, lane_2 = _lane_headways(c.demand["main"])
    _destinations("main", c.demand["main"])
    if c.demand["main"].cav_share != c.demand[ramp.id].cav_share:
        shares = [c.demand["main"].cav_share, c.demand[ramp.id].cav_share]
        raise _refuse(f"demand.{ramp.id}.cav_share", shares[1], f"{shares[0]}, main's share")
    _, vehicle = _one_class(c)
    cav = {**_idm(vehicle), **vehicle.cav.model_dump(exclude_none=True)}
    lane_change = {"lane_change_duration": c.corridor.lane_change_duration}
    settings: dict[str, Any] = {
        "name": c.name,
        "description": c.corridor.description or f"corridor {c.name}",
        "seed": c.corridor.seed,
        "dt": c.corridor.step_length,
        "duration": c.corridor.duration,
        "warmup": c.corridor.warmup,
        "road": ramp_road(c, ramp, vehicle),
        "demand": {
            "mean_headway_main_1": lane_1, "mean_headway_main_2": lane_2,
            "cav_penetration": c.demand["main"].cav_share,
            **_ramp_demand(ramp.id, c.demand[ramp.id]),
        },
        "hdv": {**_idm(vehicle), **lane_change},
        "cav": {**cav, **lane_change},
        **c.impairment_tables(),
    }  # fmt: skip
    return load_config("C1", **merge_tables(settings, overrides))


def scenario_config(source: str | os.PathLike[str], **overrides: Any) -> ScenarioConfig:
    """The scenario config of ``source``: a condition preset or scenario file as
    :func:`hcomc.config.load_config` reads it, or a corridor of the paper's layout (``paper``,
    ``paper-C1`` ...) as :func:`scenario_of` translates it; ``overrides`` are the scenario's
    keys either way. A :class:`ConfigError` names the key of a corridor that does not fit."""
    from hcomc.corridor.loading import is_corridor_source, load_corridor

    if is_corridor_source(source):
        return scenario_of(load_corridor(source, {}), **overrides)
    return load_config(source, **overrides)
