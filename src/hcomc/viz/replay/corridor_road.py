"""A corridor's road as the replay page draws it: every lane stretch, each on-ramp with its
control zone and acceleration lane, the off-ramps and lane drops, in world coordinates [m].

The layout is :mod:`hcomc.corridor.layout`'s, the one the CommonRoad export writes: one
area per lane stretch (:func:`hcomc.corridor.layout.lane_stretches`: each lane of each
section of the mainline, acceleration and deceleration lanes included, and each lane of each
ramp road, sloping away from the mainline), so that a vehicle placed by
:func:`hcomc.corridor.layout.code_poses` drives on its lane. Lines between lanes side by
side are dashed (they may be crossed); the road's edges are solid, and so is the end of a
lane that ends (an acceleration lane, a lane dropped). An on-ramp's cooperative control zone
is shaded over the last ``control_zone_length`` metres of its ramp road.
"""

from __future__ import annotations

import math

from hcomc.corridor import Corridor, OnRamp
from hcomc.corridor.layout import (
    RAMP_SLOPE,
    LaneStretch,
    lane_stretches,
    main_lane_count,
    ramp_road_span,
    side_by_side,
)
from hcomc.viz.replay.geometry import (
    FOCUS_MARGIN,
    Area,
    Label,
    Marking,
    RoadShapes,
    Stroke,
    Surface,
)

__all__ = ["corridor_road_shapes"]

_EPS = 1e-6  # [m]


def _area(p: LaneStretch) -> Area:
    """The surface of one lane stretch: asphalt on the mainline, the ramp's colour on ramp
    roads and acceleration and deceleration lanes."""
    surface: Surface = "asphalt" if p.kind == "main" else "ramp"
    return Area(surface, p.x0, p.x1, p.y_right, p.y_left, p.drop[0], p.drop[1])


def _line(stroke: Stroke, p: LaneStretch, y: float) -> Marking:
    """A line along stretch ``p`` at ``y`` where it meets the mainline (shifted with it)."""
    return Marking(stroke, p.x0, y + p.drop[0], p.x1, y + p.drop[1])


def _markings(stretches: tuple[LaneStretch, ...], length: float) -> list[Marking]:
    """Dashed lines between stretches side by side (drawn once, from the right one), solid
    edges where a stretch has no neighbour, and a solid line across the end of a mainline,
    acceleration or deceleration lane that does not continue before the road's end."""
    out = []
    starts = {(p.key, round(p.x0, 6)) for p in stretches}
    for p in stretches:
        left, right = side_by_side(p, stretches)
        out.append(_line("dashed" if left is not None else "solid", p, p.y_left))
        if right is None:
            out.append(_line("solid", p, p.y_right))
        continues = (p.key, round(p.x1, 6)) in starts
        if p.kind in ("main", "accel", "decel") and not continues and p.x1 < length - _EPS:
            out.append(Marking("solid", p.x1, p.y_right + p.drop[1], p.x1, p.y_left + p.drop[1]))
    return out


def _zone(ramp: OnRamp, width: float) -> Area | None:
    """The control zone of ``ramp``: the last ``control_zone_length`` of its ramp road."""
    if ramp.control_zone_length <= 0:
        return None
    length, angle = ramp.control_zone_length, math.atan(RAMP_SLOPE)
    run, drop = length * math.cos(angle), length * math.sin(angle)
    return Area("zone", ramp.x - run, ramp.x, -ramp.lanes * width, 0.0, -drop, 0.0)


def _labels(corridor: Corridor, top: float) -> list[Label]:
    """Each ramp's id on its road with its control zone and acceleration or deceleration
    lane, each lane drop and speed-limit zone above the mainline."""
    road, width = corridor.road, corridor.road.lane_width
    angle = math.atan(RAMP_SLOPE)
    out = []
    for ramp in road.ramps:
        x0, x1 = ramp_road_span(ramp)
        middle = 0.5 * ramp.ramp_length * math.sin(angle)
        below = -(ramp.lanes + 0.9) * width
        out.append(Label(ramp.id, 0.5 * (x0 + x1), below - middle))
        lane = "acceleration lane" if isinstance(ramp, OnRamp) else "deceleration lane"
        out.append(Label(lane, 0.5 * (ramp.x + ramp.end), below))
    for ramp in road.on_ramps:
        zone = ramp.control_zone_length
        if zone > 0:
            x = ramp.x - 0.5 * zone * math.cos(angle)
            out.append(Label(f"{ramp.id} control zone", x, top + 0.9 * width))
    count = road.lanes
    for drop in road.lane_drops:
        out.append(Label(f"{count} → {drop.lanes} lanes", drop.x, top + 0.9 * width))
        count = drop.lanes
    for zone_limit in road.speed_limits:
        text = f"limit {zone_limit.speed * 3.6:.0f} km/h"
        out.append(Label(text, 0.5 * (zone_limit.x0 + zone_limit.x1), top + 0.9 * width))
    return out


def corridor_road_shapes(corridor: Corridor) -> RoadShapes:
    """The shapes of ``corridor``'s road (module docstring); the view first shows its first
    on-ramp's control zone and acceleration lane (the whole road without an on-ramp)."""
    road, width = corridor.road, corridor.road.lane_width
    stretches = lane_stretches(road)
    zones = [z for z in (_zone(r, width) for r in road.on_ramps) if z is not None]
    areas = (*(_area(p) for p in stretches), *zones)
    ys = [y + d for p in stretches for y in (p.y_right, p.y_left) for d in p.drop]
    top, bottom = max(ys), min(ys)
    x_min = min(0.0, *(p.x0 for p in stretches))
    x_max = max(road.length, *(p.x1 for p in stretches))
    if road.on_ramps:
        first = road.on_ramps[0]
        start = first.x - first.control_zone_length * math.cos(math.atan(RAMP_SLOPE))
        focus = (start - FOCUS_MARGIN, first.end + FOCUS_MARGIN)
    else:
        focus = (x_min, x_max)
    n_main = main_lane_count(road)
    lanes = {k: (k + 0.5) * width for k in range(n_main)}
    lanes.update({-1 - j: -(j + 0.5) * width for r in road.ramps for j in range(r.lanes)})
    return RoadShapes(
        areas=areas,
        markings=tuple(_markings(stretches, road.length)),
        labels=tuple(_labels(corridor, top)),
        bounds=(x_min, x_max, bottom - 1.5 * width, top + 1.5 * width),
        focus=focus,
        lanes=lanes,
    )
