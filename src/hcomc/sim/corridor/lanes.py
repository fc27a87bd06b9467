"""Where a vehicle may and must drive on a corridor: speed limits, lane ends, route needs.

Kernels over the :class:`~hcomc.sim.corridor.layout.Layout` arrays that the step calls per
vehicle; inlined, so that handing them the layout costs nothing.
"""

from __future__ import annotations

import math

from hcomc._jit import kernel
from hcomc.sim.corridor.layout import KIND_MAIN, KIND_OFF, KIND_ON, Layout
from hcomc.sim.step.road import section_at

__all__ = ["mandatory_target", "section_at", "speed_limit", "stop_point"]


@kernel(inline="always")
def speed_limit(road: Layout, code: int, x: float) -> float:
    """Speed limit [m/s] at x on lane ``code``: the section's on the mainline and on the
    acceleration/deceleration lanes, the ramp road's before (on) or after (off) them."""
    kind = road.code_kind[code]
    if (kind == KIND_ON and x < road.code_x0[code]) or (
        kind == KIND_OFF and x >= road.code_x1[code]
    ):
        return road.code_speed[code]
    return road.sec_speed[section_at(road.sec_x0, x)]


@kernel(inline="always")
def stop_point(road: Layout, code: int, x: float, exit_code: int) -> float:
    """Where a vehicle in lane ``code`` at x must have left it [m] (inf if nowhere): the end
    of an acceleration lane, of a mainline lane that drops, and, for a vehicle bound for an
    off-ramp, the end of that ramp's deceleration lane."""
    kind = road.code_kind[code]
    if kind == KIND_ON:
        return road.code_x1[code]
    if kind == KIND_OFF:
        return math.inf
    end = road.lane_end[code, section_at(road.sec_x0, x)]
    if exit_code >= 0 and x < road.code_x1[exit_code]:
        end = min(end, road.code_x1[exit_code])
    return end


@kernel(inline="always")
def mandatory_target(
    road: Layout, code: int, x: float, exit_code: int, lookahead: float
) -> tuple[int, float]:
    """The change a vehicle's route needs now: (target code, distance left for it [m]), or
    (-1, inf).

    * on an acceleration lane: to the left, until its end;
    * bound for an off-ramp, in mainline lane 0 beside the ramp's deceleration lane: into it;
    * bound for an off-ramp k lanes to the left of lane 0: one lane right once the ramp's
      end is within ``(k + 1) * lookahead`` (the distance left shared by the k + 1 changes);
    * in a mainline lane that ends within ``lookahead``: one lane right.
    """
    kind = road.code_kind[code]
    target, left = -1, math.inf
    if kind == KIND_ON and x >= road.code_x0[code]:
        target, left = road.code_left[code], road.code_x1[code] - x
    elif kind == KIND_MAIN:
        end = road.lane_end[code, section_at(road.sec_x0, x)]
        if code > 0 and end - x < lookahead:
            target, left = code - 1, end - x
        if exit_code >= 0:
            x0, x1 = road.code_x0[exit_code], road.code_x1[exit_code]
            if code == 0 and x0 <= x < x1:
                target, left = exit_code, x1 - x
            elif code > 0 and x1 - x < (code + 1) * lookahead:
                target, left = code - 1, min(left, (x1 - x) / (code + 1))
    return target, left
