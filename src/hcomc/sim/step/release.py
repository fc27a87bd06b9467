"""Release: the compiled step's insertion of the vehicles due, queue by queue, into the lane
that has room (:func:`release`). Each lane has a release queue (the demand's vehicles of
that lane, by release time); a queue may release into the lanes up to ``queue_last`` (a
corridor's mainline: SUMO's ``departLane="best"``)."""

from __future__ import annotations

import math

from hcomc._jit import kernel
from hcomc.sim.lane_table import L_CENTRE, L_END
from hcomc.sim.step.motion import follow_exact
from hcomc.sim.step.road import lane_end_at, road_of
from hcomc.sim.step.state import EV_INSERTION, LOOKAHEAD, WARMUP, CoreArrays, add_event

__all__ = ["release"]


@kernel
def _insert(c: CoreArrays, i: int, queue: int, t: float) -> bool:
    """Place vehicle i of the release queue of lane ``queue`` at its release point if the
    lane has room for it.

    The lane is the queue's own or, for a queue that may release into the lanes up to
    ``queue_last`` (a corridor's mainline, SUMO's ``departLane="best"``), the one of them
    with the most free road ahead (the rightmost for a vehicle whose off-ramp is within
    the look-ahead per lane). A lane has no room while a vehicle's front lies within the
    new vehicle's body or its jam distance ``s0`` behind it (vehicles of other lengths
    released at the same point). The release speed is kept if the gap ahead exceeds
    ``s0 + v T`` and Eq. 1 behind the vehicle ahead brakes no harder than the comfortable
    deceleration ``b``; otherwise the vehicle is released at the speed of the vehicle ahead
    if that gap suffices, else it waits. The initial fill (released at ``-warmup``) does not
    check gaps.
    """
    x, v = c.d_x[i], c.d_v[i]
    fill = c.d_t[i] <= -c.consts[WARMUP] + 1e-9
    if fill and c.queue_last[queue] == queue:
        lane, j = queue, -1  # its queue's own lane, the only one (no scan of the road)
    else:
        lane, j = _best_lane(c, i, queue, x)
    if not fill:
        if lane < 0:
            return False
        if j >= 0:
            gap = c.x[j] - c.length[j] - x
            s0, T, b = c.matrix[2, i], c.matrix[1, i], c.matrix[4, i]
            if v > c.v[j] and follow_exact(c.matrix, c.iidm, i, gap, v, c.v[j], c.a[j]) < -b:
                v = c.v[j]  # it would close in faster than it can comfortably brake for
            if gap < s0 + v * T:
                v = min(v, c.v[j])
                if gap < s0 + v * T:
                    return False
    lane = queue if lane < 0 else lane
    if lane != c.lane[i]:
        c.lane[i] = c.origin[i] = c.target[i] = lane
        c.y[i] = c.road_f[L_CENTRE, lane]
    c.x[i], c.v[i], c.active[i] = x, v, True
    c.x_hist[:, i] = x
    c.v_hist[:, i] = v
    add_event(c, t, EV_INSERTION, i, -1, x, t - c.d_t[i])
    return True


@kernel(inline="always")
def _ahead(c: CoreArrays, lane: int, x: float, clear: float) -> int:
    """The nearest vehicle at or ahead of x with its body in ``lane`` (in it, or changing
    from or to it) (-1: none; -2: the lane is taken, a vehicle's front lying in
    ``[x - clear, x)``)."""
    j, best = -1, math.inf
    active, lanes, targets, origins = c.active, c.lane, c.target, c.origin
    for k in range(active.size):  # most of a long run's vehicles are not (or no longer) on it
        if not active[k]:
            continue
        if not (lanes[k] == lane or targets[k] == lane or origins[k] == lane):
            continue
        if x <= c.x[k] < best:
            j, best = k, c.x[k]
        elif x - clear <= c.x[k] < x:
            return -2
    return j


@kernel(inline="always")
def _best_lane(c: CoreArrays, i: int, queue: int, x: float) -> tuple[int, int]:
    """The lane vehicle i enters by from ``queue`` at x and the vehicle ahead of it there
    (-1: none), or ``(-1, -1)`` when no lane has room (:func:`_insert`)."""
    last, exit_code = c.queue_last[queue], c.route[i]
    reach = (last - queue + 1) * c.consts[LOOKAHEAD]
    if exit_code >= 0 and c.road_f[L_END, exit_code] - x < reach:
        last = queue  # its off-ramp is near: the rightmost lane, which leads to it
    clear = c.length[i] + c.matrix[2, i]
    lane, lead, room = -1, -1, -math.inf
    road = road_of(c)
    for code in range(queue, last + 1):
        if lane_end_at(road, code, x) <= x:
            continue  # no such lane here
        j = _ahead(c, code, x, clear)
        if j == -2:
            continue
        free = math.inf if j < 0 else c.x[j] - c.length[j] - x
        if free > room:
            lane, lead, room = code, j, free
    return lane, lead


@kernel
def release(c: CoreArrays, t: float) -> None:
    """Insert due vehicles queue by queue (a queue per lane, the lane they enter by); a
    blocked entry waits (and blocks its queue). Releasing twice at the same t is a no-op."""
    for lane in range(c.queue_pos.size):
        start, end = c.queue_start[lane], c.queue_start[lane + 1]
        pos = c.queue_pos[lane]
        while start + pos < end and c.d_t[c.queues[start + pos]] <= t + 1e-9:
            if not _insert(c, c.queues[start + pos], lane, t):
                break
            pos += 1
        c.queue_pos[lane] = pos
