"""What the road lets and makes a vehicle do where it is, read from the lane table of the
compiled state (:mod:`hcomc.sim.lane_table`): which section it is in, whether a lane exists
there, where it must have left its lane, the speed limit, and the change its lane or its
route needs. Inlined into the step's kernels, so that reading the table costs no call.
"""

from __future__ import annotations

import math

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
    L_OPENS,
    L_RIGHT,
    L_SPEED,
)
from hcomc.sim.step.state import LOOKAHEAD, CoreArrays

__all__ = [
    "discretionary_target", "lane_end_at", "main_index", "needed_change", "section_at",
    "speed_limit", "stop_point",
]  # fmt: skip


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
def main_index(c: CoreArrays, code: int) -> int:
    """k of mainline lane ``code`` (0 = rightmost; the mainline's codes are the last)."""
    return code - (c.road_int.shape[1] - c.main_end.shape[0])


@kernel(inline="always")
def lane_end_at(c: CoreArrays, code: int, x: float) -> float:
    """Where lane ``code`` ends at or after x [m] (inf: never): a mainline lane where the
    sections drop it, an acceleration lane at its end; an off-ramp's lane leads off the
    road."""
    kind = c.road_int[L_KIND, code]
    if kind == KIND_MAIN:
        return c.main_end[main_index(c, code), section_at(c.sec_x0, x)]
    if kind == KIND_ON:
        return c.road_f[L_END, code]
    return math.inf


@kernel(inline="always")
def stop_point(c: CoreArrays, i: int) -> float:
    """Where vehicle i must have left its lane [m] (inf: nowhere): its lane's end and, bound
    for an off-ramp and still on the mainline before it, the end of that ramp's
    deceleration lane."""
    code, x = c.lane[i], c.x[i]
    end = lane_end_at(c, code, x)
    exit_code = c.route[i]
    if exit_code >= 0 and c.road_int[L_KIND, code] == KIND_MAIN:
        last = c.road_f[L_END, exit_code]
        if x < last:
            end = min(end, last)
    return end


@kernel(inline="always")
def speed_limit(c: CoreArrays, code: int, x: float) -> float:
    """The speed limit [m/s] at x in lane ``code`` (inf: none): a ramp road's own before its
    acceleration lane or after its deceleration lane, elsewhere the section's."""
    kind = c.road_int[L_KIND, code]
    if (kind == KIND_ON and x < c.road_f[L_OPENS, code]) or (
        kind == KIND_OFF and x >= c.road_f[L_END, code]
    ):
        return c.road_f[L_SPEED, code]
    return c.sec_speed[section_at(c.sec_x0, x)]


@kernel(inline="always")
def needed_change(c: CoreArrays, i: int) -> tuple[int, float]:
    """The change vehicle i's mainline lane or route needs now and the distance left for it
    [m] (``(-1, inf)``: none), taken as soon as it is safe:

    * bound for an off-ramp, in the lane beside the ramp's deceleration lane: into it;
    * bound for an off-ramp k lanes further left: one lane right once the end of the
      ramp's deceleration lane is within ``(k + 1)`` times the look-ahead;
    * in a mainline lane that ends within the look-ahead: one lane right.

    The distance left is that to the lane's end, or the off-ramp's last point shared by the
    changes still needed.
    """
    code, x = c.lane[i], c.x[i]
    if c.road_int[L_KIND, code] != KIND_MAIN:
        return -1, math.inf
    lookahead, right = c.consts[LOOKAHEAD], c.road_int[L_RIGHT, code]
    target, left = -1, math.inf
    end = lane_end_at(c, code, x)
    if right >= 0 and end - x < lookahead:
        target, left = right, end - x
    exit_code = c.route[i]
    if exit_code >= 0:
        begin, last = c.road_f[L_BEGIN, exit_code], c.road_f[L_END, exit_code]
        k = main_index(c, code)
        if code == c.road_int[L_LEFT, exit_code]:
            if begin <= x < last:
                target, left = exit_code, last - x
        elif right >= 0 and last - x < (k + 1) * lookahead:
            target, left = right, min(left, (last - x) / (k + 1))
    return target, left


@kernel(inline="always")
def discretionary_target(c: CoreArrays, i: int, side: int) -> int:
    """The mainline lane to the left (``side`` = 1) or right (-1) that vehicle i may change
    to of its own accord (-1: none): one that exists here and does not end within the
    look-ahead; not away from its off-ramp once that is within reach of the changes it
    would then need."""
    code, x = c.lane[i], c.x[i]
    target = c.road_int[L_LEFT if side > 0 else L_RIGHT, code]
    if target < 0 or c.road_int[L_KIND, target] != KIND_MAIN:
        return -1
    lookahead = c.consts[LOOKAHEAD]
    if lane_end_at(c, target, x) - x < lookahead:  # also where the lane does not exist
        return -1
    exit_code = c.route[i]
    near = exit_code >= 0 and c.road_f[L_END, exit_code] - x < (main_index(c, code) + 2) * lookahead
    return -1 if side > 0 and near else target
