"""The road of a run as the replay page draws it: areas, lane markings and labels in world
coordinates [m].

The page knows no road layout of its own: it draws the shapes listed here (to scale, with
pan and zoom), so another road layout only needs another list. :func:`road_shapes` lists the
layout of paper Section II-A as :class:`hcomc.config.RoadParams` describes it (read from the
run by :func:`hcomc.metrics.road_of`): lane 2 at y = +W, lane 1 at y = 0, the ramp and
acceleration lane at y = -W, the cooperative control zone upstream of the acceleration lane.
A corridor's road is listed by :mod:`hcomc.viz.replay.corridor_road`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Literal

from hcomc.config import RoadParams
from hcomc.road import Lane, lane_centre

__all__ = ["Area", "Label", "Marking", "RoadShapes", "road_shapes"]

Surface = Literal["asphalt", "ramp", "zone"]
Stroke = Literal["solid", "dashed", "barrier"]

FOCUS_MARGIN = 100.0
"""Road shown up- and downstream of the control zone and acceleration lane at first [m]."""


@dataclass(frozen=True, slots=True)
class Area:
    """A rectangle of road surface (or the control zone's overlay) [m] from ``x0`` to ``x1``
    and ``y0`` to ``y1``; its upstream end shifted laterally by ``dy0`` and its downstream
    end by ``dy1`` [m] (a parallelogram: a ramp road sloping away from the mainline)."""

    surface: Surface
    x0: float
    x1: float
    y0: float
    y1: float
    dy0: float = 0.0
    dy1: float = 0.0


@dataclass(frozen=True, slots=True)
class Marking:
    """A lane marking from (x0, y0) to (x1, y1) [m]: ``solid`` edge or line, ``dashed`` lane
    divider that may be crossed, ``barrier`` a line that may not be crossed."""

    stroke: Stroke
    x0: float
    y0: float
    x1: float
    y1: float


@dataclass(frozen=True, slots=True)
class Label:
    """A text label at (x, y) [m], centred."""

    text: str
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class RoadShapes:
    """Everything the page draws of the road, and where to look first.

    ``bounds`` (x0, x1, y0, y1) encloses the road [m]; ``focus`` (x0, x1) is the stretch the
    view shows when nothing is selected (the merge area) [m]; ``lanes`` maps each lane index
    to its centre line y [m] (the page's lane readout and the virtual vehicles' lanes).
    """

    areas: tuple[Area, ...]
    markings: tuple[Marking, ...]
    labels: tuple[Label, ...]
    bounds: tuple[float, float, float, float]
    focus: tuple[float, float]
    lanes: dict[int, float]

    def to_json(self) -> dict[str, Any]:
        """The JSON-ready form the page reads."""
        return {
            "areas": [asdict(a) for a in self.areas],
            "markings": [asdict(m) for m in self.markings],
            "labels": [asdict(lb) for lb in self.labels],
            "bounds": list(self.bounds),
            "focus": list(self.focus),
            "lanes": {str(k): v for k, v in self.lanes.items()},
        }


def road_shapes(road: RoadParams) -> RoadShapes:
    """The shapes of the on-ramp road ``road`` (paper Section II-A, Fig. 1)."""
    w = road.lane_width
    centres = {int(lane): float(lane_centre(int(lane), w)) for lane in Lane}
    top, mid, low, bottom = 1.5 * w, 0.5 * w, -0.5 * w, -1.5 * w  # lane edges
    ramp0, acc0, acc1 = road.ramp_start, road.accel_lane_start, road.accel_lane_end
    end, zone0 = road.length, road.control_zone_start
    areas = (
        Area("asphalt", 0.0, end, low, top),
        Area("ramp", ramp0, acc1, bottom, low),
        Area("zone", zone0, acc0, bottom, top),
    )
    markings = (
        Marking("solid", 0.0, top, end, top),  # outer edge of lane 2
        Marking("dashed", 0.0, mid, end, mid),  # lane 2 | lane 1
        Marking("solid", 0.0, low, ramp0, low),  # lane 1's edge upstream of the ramp
        Marking("barrier", ramp0, low, acc0, low),  # ramp | lane 1: no crossing
        Marking("dashed", acc0, low, acc1, low),  # acceleration lane | lane 1
        Marking("solid", acc1, low, end, low),  # lane 1's edge downstream
        Marking("solid", ramp0, bottom, acc1, bottom),  # outer edge of the ramp
        Marking("solid", acc1, bottom, acc1, low),  # end of the acceleration lane
    )
    label_y = bottom - 0.9 * w
    labels = (
        Label("control zone", 0.5 * (zone0 + acc0), top + 0.9 * w),
        Label("ramp", 0.5 * (ramp0 + acc0), label_y),
        Label("acceleration lane", 0.5 * (acc0 + acc1), label_y),
        Label("lane 2", 0.5 * zone0, centres[Lane.MAIN_2]),
        Label("lane 1", 0.5 * zone0, centres[Lane.MAIN_1]),
    )
    return RoadShapes(
        areas=areas,
        markings=markings,
        labels=labels,
        bounds=(0.0, end, bottom - 1.5 * w, top + 1.5 * w),
        focus=(max(0.0, zone0 - FOCUS_MARGIN), min(end, acc1 + FOCUS_MARGIN)),
        lanes=centres,
    )
