"""What the road lets and makes a vehicle do where it is, read from the lane table of the
compiled state (:mod:`hcomc.sim.lane_table`): which section it is in, whether a lane exists
there, where it must have left its lane, the speed limit, and the change its lane or its
route needs. Inlined into the step's kernels.

A compiled call with arrays as arguments inside a per-vehicle loop pays numba's reference
counting on every array, inlined or not (``NRT_incref``/``NRT_decref`` stay calls): about 5 ns
an array a vehicle, against the few nanoseconds of the lookup itself. The helpers called for
every vehicle (:func:`stop_point`, :func:`speed_limit`) therefore take numbers; those that
need the table (:func:`lane_end_at`, :func:`needed_change`, :func:`side_allowed`) are
called only for vehicles whose lane ends somewhere (the table's ``L_ENDS``) or that leave by
an off-ramp.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc.sim.lane_table import (
    KIND_MAIN,
    KIND_OFF,
    KIND_ON,
    L_BEGIN,
    L_END,
    L_KIND,
    L_LEFT,
    L_RIGHT,
)
from hcomc.sim.step.state import CoreArrays

__all__ = [
    "RoadArrays", "lane_end_at", "main_index", "needed_change", "road_of", "section_at",
    "side_allowed", "speed_limit", "stop_point",
]  # fmt: skip


class RoadArrays(NamedTuple):
    """The lane table of the compiled state (:func:`road_of`), as one argument of the
    helpers that read several of its arrays."""

    ints: np.ndarray  # (4, L) L_KIND, L_LEFT, L_RIGHT, L_ENDS
    floats: np.ndarray  # (8, L) L_CENTRE ... L_SPEED
    sec_x0: np.ndarray  # (S,) where each section begins [m]
    sec_speed: np.ndarray  # (S,) its speed limit [m/s]
    main_end: np.ndarray  # (M, S) where mainline lane k ends at or after section s [m]


@kernel(inline="always")
def road_of(c: CoreArrays) -> RoadArrays:
    """The road of the compiled state ``c``."""
    return RoadArrays(c.road_int, c.road_f, c.sec_x0, c.sec_speed, c.main_end)


@kernel(inline="always")
def section_at(sec_x0: np.ndarray, x: float) -> int:
    """Index of the section (starts ``sec_x0``, ascending) containing mainline position x
    [m] (clipped to the road)."""
    lo, hi = 0, sec_x0.size
    while lo < hi:  # the last section with x0 <= x
        mid = (lo + hi) // 2
        if sec_x0[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return max(lo - 1, 0)


@kernel(inline="always")
def main_index(road: RoadArrays, code: int) -> int:
    """k of mainline lane ``code`` (0 = rightmost; the mainline's codes are the last)."""
    return code - (road.ints.shape[1] - road.main_end.shape[0])


@kernel(inline="always")
def lane_end_at(road: RoadArrays, code: int, x: float) -> float:
    """Where lane ``code`` ends at or after x [m] (inf: never): a mainline lane where the
    sections drop it, an acceleration lane at its end; an off-ramp's lane leads off the
    road."""
    kind = road.ints[L_KIND, code]
    if kind == KIND_MAIN:
        return road.main_end[main_index(road, code), section_at(road.sec_x0, x)]
    if kind == KIND_ON:
        return road.floats[L_END, code]
    return math.inf


@kernel(inline="always")
def stop_point(lane_end: float, on_main: bool, exit_end: float, x: float) -> float:
    """Where a vehicle at x [m] must have left its lane [m] (inf: nowhere): its lane's end
    ``lane_end`` (:func:`lane_end_at`) and, bound for an off-ramp whose deceleration lane
    ends at ``exit_end`` (inf: none) and still on the mainline (``on_main``) before it, that
    end. Numbers, not arrays: it is called for every vehicle bound for an off-ramp at every
    step."""
    if on_main and x < exit_end:
        return min(lane_end, exit_end)
    return lane_end


@kernel(inline="always")
def speed_limit(
    kind: int, opens: float, end: float, ramp_speed: float, section_speed: float, x: float
) -> float:
    """The speed limit [m/s] at x in a lane of ``kind`` (``KIND_*``) whose rows ``L_OPENS``,
    ``L_END`` and ``L_SPEED`` are ``opens``, ``end`` and ``ramp_speed``, in a section whose
    limit is ``section_speed`` (inf: none): a ramp road's own before its acceleration lane or
    after its deceleration lane, elsewhere the section's. Numbers, not arrays: it is called
    for every vehicle at every step of a road with speed limits."""
    if (kind == KIND_ON and x < opens) or (kind == KIND_OFF and x >= end):
        return ramp_speed
    return section_speed


@kernel(inline="always")
def needed_change(
    road: RoadArrays, code: int, x: float, exit_code: int, lookahead: float
) -> tuple[int, float]:
    """The change a vehicle at x [m] in lane ``code``, bound for off-ramp lane ``exit_code``
    (-1: none), needs now and the distance left for it [m] (``(-1, inf)``: none), taken as
    soon as it is safe (``lookahead``: :attr:`~hcomc.config.LaneChangeParams.exit_lookahead`):

    * bound for an off-ramp, in the lane beside the ramp's deceleration lane: into it;
    * bound for an off-ramp k lanes further left: one lane right once the end of the
      ramp's deceleration lane is within ``(k + 1)`` times the look-ahead;
    * in a mainline lane that ends within the look-ahead: one lane right.

    The distance left is that to the lane's end, or the off-ramp's last point shared by the
    changes still needed.
    """
    if road.ints[L_KIND, code] != KIND_MAIN:
        return -1, math.inf
    right = road.ints[L_RIGHT, code]
    target, left = -1, math.inf
    end = lane_end_at(road, code, x)
    if right >= 0 and end - x < lookahead:
        target, left = right, end - x
    if exit_code >= 0:
        begin, last = road.floats[L_BEGIN, exit_code], road.floats[L_END, exit_code]
        k = main_index(road, code)
        if code == road.ints[L_LEFT, exit_code]:
            if begin <= x < last:
                target, left = exit_code, last - x
        elif right >= 0 and last - x < (k + 1) * lookahead:
            target, left = right, min(left, (last - x) / (k + 1))
    return target, left


@kernel(inline="always")
def side_allowed(
    road: RoadArrays, code: int, target: int, x: float, exit_code: int, lookahead: float
) -> bool:
    """Whether a vehicle at x [m] in mainline lane ``code``, bound for off-ramp lane
    ``exit_code`` (-1: none), may change of its own accord to ``target``, the mainline lane
    beside it: one that exists here and does not end within ``lookahead``; not to the left
    once its off-ramp is within reach of the changes it would then need. Always true for a
    lane that never ends (``L_ENDS`` 0) and a vehicle bound for no off-ramp, for which the
    step does not call it."""
    if lane_end_at(road, target, x) - x < lookahead:  # also where the lane does not exist
        return False
    reach = (main_index(road, code) + 2) * lookahead
    near = exit_code >= 0 and road.floats[L_END, exit_code] - x < reach
    return not (target == road.ints[L_LEFT, code] and near)
