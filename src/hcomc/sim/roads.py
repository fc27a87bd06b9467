"""The roads the engine drives, as lane tables (:mod:`hcomc.sim.lane_table`): the paper's
road of a scenario's ``[road]`` table (:func:`paper_lanes`), a corridor's road
(:func:`road_lanes`), and an on-ramp of either as its controller sees it (:func:`ramp_of`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from hcomc.interface.ramp import Ramp
from hcomc.sim.lane_table import (
    KIND_OFF,
    KIND_ON,
    L_END,
    L_KIND,
    L_LEFT,
    L_OPENS,
    L_WIDTH,
    L_ZONE,
    LaneTable,
    RampLanes,
    lane_table,
)

if TYPE_CHECKING:
    from hcomc.config import RoadParams
    from hcomc.corridor.road import Road

__all__ = ["paper_lanes", "ramp_of", "road_lanes"]


def paper_lanes(road: RoadParams) -> LaneTable:
    """The paper's road (Section II-A, a scenario's ``[road]`` table): two mainline lanes
    over ``length`` and one single-lane on-ramp whose road begins at ``ramp_start``, whose
    acceleration lane runs from ``accel_lane_start`` to ``accel_lane_end``, with its control
    zone from ``control_zone_start``; no speed limit."""
    ramp = RampLanes(KIND_ON, 1, road.ramp_start, road.accel_lane_start, road.accel_lane_end,
                     road.control_zone_start, math.inf, math.inf)  # fmt: skip
    return lane_table(road.lane_width, road.length, [(0.0, 2, math.inf)], [ramp])


def road_lanes(road: Road) -> LaneTable:
    """A corridor's road (:class:`hcomc.corridor.Road`): its sections and ramps. An on-ramp's
    road begins ``ramp_length`` before its acceleration lane, its control zone
    ``control_zone_length`` before it; an off-ramp's lanes begin with its deceleration lane
    and its vehicles leave the road ``ramp_length`` after it; a ramp's road has the speed
    limit where it joins the mainline."""
    from hcomc.corridor.road import OnRamp, sections

    ramps = []
    for ramp in road.ramps:
        speed = road.speed_at(ramp.x)
        if isinstance(ramp, OnRamp):
            zone = ramp.x - ramp.control_zone_length
            ramps.append(RampLanes(KIND_ON, ramp.lanes, ramp.x - ramp.ramp_length, ramp.x,
                                   ramp.end, zone, math.inf, speed))  # fmt: skip
        else:
            ramps.append(RampLanes(KIND_OFF, ramp.lanes, ramp.x, -math.inf, ramp.end, math.inf,
                                   ramp.end + ramp.ramp_length, speed))  # fmt: skip
    cuts = [(s.x0, s.lanes, s.speed_limit) for s in sections(road)]
    return lane_table(road.lane_width, road.length, cuts, ramps)


def ramps_of(lanes: LaneTable) -> tuple[Ramp, ...]:
    """Every on-ramp of the road, as a controller sees it (:func:`ramp_of`), in lane-code
    order."""
    return tuple(ramp_of(lanes, int(code)) for code in lanes.codes_of_kind(KIND_ON))


def ramp_of(lanes: LaneTable, code: int) -> Ramp:
    """The on-ramp of lane ``code`` (an on-ramp lane) as a controller sees it
    (:class:`hcomc.interface.Ramp`): its control zone and acceleration lane, the lane width,
    its lane, the lane left of it (lane 1 of Section II-A) and the one beyond (lane 2; -1:
    none). On the paper's road, :meth:`hcomc.interface.Ramp.of` of its ``[road]`` table."""
    if lanes.ints[L_KIND, code] != KIND_ON:
        raise ValueError(f"lane {code} is not an on-ramp lane")
    target = int(lanes.ints[L_LEFT, code])
    beyond = int(lanes.ints[L_LEFT, target]) if target >= 0 else -1
    f = lanes.floats
    return Ramp(
        control_zone_start=float(f[L_ZONE, code]), accel_lane_start=float(f[L_OPENS, code]),
        accel_lane_end=float(f[L_END, code]),
        lane_width=float(f[L_WIDTH, code]),
        lane=int(code), target=target, beyond=beyond,
    )  # fmt: skip
