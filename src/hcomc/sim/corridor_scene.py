"""A corridor on the engine: its road as a lane table, its departure schedule as the demand,
its vehicle classes as the fleet, and the model parameters of the run.

:func:`corridor_scene` makes the :class:`~hcomc.sim.scene.Scene` of a corridor
(:class:`hcomc.corridor.Corridor`) for :class:`hcomc.sim.engine.Simulation`, and
:func:`corridor_config` the scenario that carries the run's model parameters (step, duration,
warm-up, seed, its lane-change, route and control tables; the human drivers' perception,
Eq. 2, and the CAVs' heuristic, Eq. 3, as the paper's conditions have them). The engine
reads the road from the scene only.

The demand is the corridor's (:func:`hcomc.corridor.schedule.departure_times`: the vehicles
SUMO gets); each vehicle's class and automation are drawn from its origin's shares with the
run's generator. A mainline vehicle waits at the road's start, its front one length in
(SUMO's ``departPos="base"``), and enters by the mainline lane with the most free road ahead
(``departLane="best"``); a ramp vehicle likewise at its ramp road's start. It enters at its
desired speed within the speed limit there, slower when the gap ahead asks for it
(:func:`hcomc.sim.step.release.release`). A vehicle of class ``c`` drives the IDM of the
class (its CAV values for a CAV), its desired speed within the class's top speed.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hcomc.config import ScenarioConfig, load_config
from hcomc.corridor import Corridor
from hcomc.corridor.layout import ramp_codes
from hcomc.corridor.schedule import departure_times, draw_classes
from hcomc.interface import Fleet
from hcomc.road import Kind
from hcomc.sim.demand import Demand
from hcomc.sim.lane_table import KIND_MAIN, L_BEGIN, L_KIND, L_SPEED, LaneTable
from hcomc.sim.roads import road_lanes
from hcomc.sim.scene import Scene, SceneMaker

__all__ = ["corridor_config", "corridor_scene"]

_IDM = ("desired_speed", "time_headway", "min_gap", "max_accel", "comfort_decel", "exponent")


def corridor_config(c: Corridor, **overrides: Any) -> ScenarioConfig:
    """The model parameters of a run of corridor ``c`` (module docstring), with
    ``overrides`` as :func:`hcomc.config.load_config` takes them."""
    from hcomc.config import merge_tables

    duration = {"lane_change_duration": c.corridor.lane_change_duration}
    settings = {
        "name": c.name, "description": c.corridor.description or f"corridor {c.name}",
        "seed": c.corridor.seed, "dt": c.corridor.step_length,
        "duration": c.corridor.duration, "warmup": c.corridor.warmup,
        "hdv": duration, "cav": duration,
        "lane_change": {**c.lane_change.model_dump(), **c.routes.model_dump()},
        "control": c.control.model_dump(),
        **c.impairment_tables(),
    }  # fmt: skip
    return load_config("C1", **merge_tables(settings, overrides))


def corridor_scene(c: Corridor) -> SceneMaker:
    """The scene maker of corridor ``c`` (module docstring)."""
    lanes = road_lanes(c.road)
    first = _first_codes(c, lanes)

    def make(config: ScenarioConfig, rng: np.random.Generator) -> Scene:
        d = departure_times(c, config.warmup + config.duration)
        n = d.time.size
        classes = tuple(c.vehicles)
        vclass, cav = draw_classes(c, d, rng)
        bodies = np.array([[c.vehicles[k].length, c.vehicles[k].width] for k in classes])
        length, width = bodies[vclass, 0].reshape(n), bodies[vclass, 1].reshape(n)
        queue = np.array([first[o] for o in d.origins], dtype=np.int64)[d.origin]
        exits = np.array([first.get(x, -1) for x in d.destinations], dtype=np.int64)
        main = lanes.ints[L_KIND, queue] == KIND_MAIN
        x = np.where(main, 0.0, lanes.floats[L_BEGIN, queue]) + length
        fleet = _fleet(c, config, vclass, cav, length, width)
        limit = np.where(main, lanes.sec_speed[0], lanes.floats[L_SPEED, queue])
        demand = Demand(
            t=d.time - config.warmup, x=x, v=np.minimum(fleet.matrix[0], limit),
            lane=queue, kind=fleet.kind, scripted=fleet.scripted, route=exits[d.destination],
        )  # fmt: skip
        return Scene(lanes, demand, fleet, _release_last(c, lanes, first), classes, vclass)

    return make


def _first_codes(c: Corridor, lanes: LaneTable) -> dict[str, int]:
    """The lane code each origin releases into first, and each off-ramp's first lane, by
    name (``main``: the rightmost mainline lane)."""
    return {**ramp_codes(c.road), "main": lanes.n_lanes - lanes.n_main}


def _release_last(c: Corridor, lanes: LaneTable, first: dict[str, int]) -> np.ndarray:
    """The last lane each lane's queue may release into: a ramp's lanes, the mainline's
    lanes at its start."""
    out = np.arange(lanes.n_lanes, dtype=np.int64)
    for ramp in c.road.on_ramps:
        out[first[ramp.id]] = first[ramp.id] + ramp.lanes - 1
    out[first["main"]] = first["main"] + c.road.lanes - 1
    return out


def _fleet(
    c: Corridor, config: ScenarioConfig, vclass: np.ndarray, cav: np.ndarray,
    length: np.ndarray, width: np.ndarray,
) -> Fleet:  # fmt: skip
    """The vehicles' parameters: their class's IDM (its CAV values for a CAV), the desired
    speed within the class's top speed; a CAV's coolness and each kind's model variant as
    the scenario's (Eq. 3)."""
    n = vclass.size
    matrix = np.zeros((7, n))
    for k, name in enumerate(c.vehicles):
        vehicle = c.vehicles[name]
        for flag in (False, True):
            rows = (vclass == k) & (cav == flag)
            params = vehicle.idm(flag)
            matrix[:6, rows] = np.array([params[p] for p in _IDM])[:, None]
            matrix[0, rows] = min(params["desired_speed"], vehicle.max_speed)
    matrix[6] = np.where(cav, config.cav.coolness, 0.0)
    return Fleet(
        kind=np.where(cav, int(Kind.CAV), int(Kind.HDV)).astype(np.int64), matrix=matrix,
        iidm=np.where(cav, config.cav.variant == "iidm", config.hdv.variant == "iidm"),
        lc_duration=np.full(n, c.corridor.lane_change_duration), length=length, width=width,
        scripted=np.zeros(n, dtype=bool),
    )  # fmt: skip
