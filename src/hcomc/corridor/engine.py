"""The corridors hcomc's own engine runs: those with the paper's layout, as a scenario config.

hcomc's engine simulates the paper's road (Section II-A): two mainline lanes, one single-lane
on-ramp with its acceleration lane, no off-ramps, constant demand. A corridor of that layout
(the ``paper`` preset, or a file based on it) becomes a :class:`~hcomc.config.ScenarioConfig`
with :func:`scenario_of` — so the same description runs in our engine and, exported, in SUMO.
Any other corridor is refused with the key that does not fit; it runs in SUMO.

The translation: road geometry one to one (the ramp enters at ``x - ramp_length``); the
mainline flow split equally over the two lanes as mean headways (``2 · 3600 / flow`` s per
lane) and the ramp flow as a continuous ramp demand (``3600 / flow`` s); one CAV share; the
one vehicle class's length and IDM parameters for the HDVs, with its CAV values for the CAVs
(the engine's HDVs keep their reaction delays and estimation errors, paper Eq. 2, which
SUMO's IDM does not have); no warm-up, since SUMO's road starts empty too; no merge
controller unless one is given.
"""

from __future__ import annotations

from typing import Any

from hcomc.config import ConfigError, ScenarioConfig, load_config, merge_tables
from hcomc.corridor.demand import OriginDemand, VehicleClass
from hcomc.corridor.model import Corridor
from hcomc.corridor.road import OnRamp

__all__ = ["ramp_road", "scenario_of"]

_SUMO = "run it in SUMO: hcomc export sumo"


def _refuse(key: str, value: Any, allowed: str) -> ConfigError:
    return ConfigError(f"key '{key}' = {value!r}: hcomc's engine runs the paper's layout only; "
                       f"allowed: {allowed} ({_SUMO})")  # fmt: skip


def _constant(key: str, demand: OriginDemand) -> float:
    flows = {f for _, f in demand.flow}
    if len(flows) != 1:
        raise _refuse(f"demand.{key}.flow", [list(p) for p in demand.flow], "a constant flow")
    flow = flows.pop()
    if flow <= 0:
        raise _refuse(f"demand.{key}.flow", flow, "a flow > 0 veh/h")
    if set(demand.destinations) != {"exit"}:
        raise _refuse(f"demand.{key}.destinations", demand.destinations, "{ exit = 1.0 }")
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
    main, on_ramp = _constant("main", c.demand["main"]), _constant(ramp.id, c.demand[ramp.id])
    if c.demand["main"].cav_share != c.demand[ramp.id].cav_share:
        shares = [c.demand["main"].cav_share, c.demand[ramp.id].cav_share]
        raise _refuse(f"demand.{ramp.id}.cav_share", shares[1], f"{shares[0]}, main's share")
    _, vehicle = _one_class(c)
    cav = {**_idm(vehicle), **vehicle.cav.model_dump(exclude_none=True)}
    lane_change = {"lane_change_duration": c.corridor.lane_change_duration}
    settings: dict[str, Any] = {
        "name": c.name,
        "seed": c.corridor.seed,
        "dt": c.corridor.step_length,
        "duration": c.corridor.duration,
        "warmup": 0.0,
        "road": ramp_road(c, ramp, vehicle),
        "demand": {
            "mean_headway_main_1": 2 * 3600.0 / main, "mean_headway_main_2": 2 * 3600.0 / main,
            "cav_penetration": c.demand["main"].cav_share, "ramp": "flow",
            "ramp_mean_headway": 3600.0 / on_ramp,
        },
        "hdv": {**_idm(vehicle), **lane_change},
        "cav": {**cav, **lane_change},
    }  # fmt: skip
    return load_config("C1", **merge_tables(settings, overrides))
