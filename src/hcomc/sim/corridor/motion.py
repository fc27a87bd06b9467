"""The compiled corridor step's insertion, motion, measurement and bookkeeping, and the
loop over steps (:func:`advance`).

**Insertion** as SUMO's ``departLane="best"``, ``departSpeed="max"``: a due vehicle enters
with its front one length past its origin's start (SUMO's ``departPos="base"``), on the
lane of its origin with the most free road ahead (a vehicle bound for an off-ramp on the
rightmost mainline lane, the one that leads to it, if its exit lies within the distance in
which it would have to move there anyway, ``exit_lookahead`` per lane), at the highest
speed up to its desired speed and the speed limit that keeps the IDM's equilibrium gap
``s0 + v T`` to the vehicle ahead, and no faster than that vehicle if the IDM would then
brake harder than ``b``. With less than ``s0`` free it waits, and its origin's later
vehicles wait behind it: the backlog, recorded per origin and period, never dropped.

**Motion** is ballistic (a vehicle that would reverse stops at v = 0); a lane change lasts
``lane_change_duration`` (a merge plan may set its ramp vehicle's) and counts in its target
lane from its middle on. A vehicle arrives
when its front reaches the mainline's end or the end of its off-ramp's road; one bound for
an off-ramp that passes the end of the ramp's deceleration lane in the mainline has missed
its exit and drives on to the mainline's end (recorded).

**Measurement** on the fly: virtual induction loops across the mainline lanes (count,
crossing speeds, occupancy, lengths, as SUMO's E1 detectors; the front's crossing time and
speed interpolated within the step), Edie's distance and time sums over space-time cells of
the mainline (Edie 1963), collisions (a vehicle's body overlapping its leader's in a lane),
and, on request, trajectory samples.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import borrow_all, kernel
from hcomc.equations.car_following import follow_accel_given, free_term
from hcomc.equations.integrate import ballistic_step
from hcomc.sim.corridor.lanes import section_at, speed_limit
from hcomc.sim.corridor.layout import KIND_MAIN, KIND_OFF, KIND_ON, Layout
from hcomc.sim.corridor.plans import (
    due_replans,
    execute,
    finish_plans,
    identify,
    mark_commanded,
    track_events,
    virtual_leaders,
)  # fmt: skip
from hcomc.sim.corridor.state import (
    ARRIVED,
    C_COLLISIONS,
    C_CONTROLLED,
    C_ENTRIES,
    C_ON_ROAD,
    C_OPEN,
    C_PENDING,
    C_PLANS,
    C_ROWS,
    C_SAMPLE_EVERY,
    C_SORTED,
    C_STEP,
    C_VEHICLE_STEPS,
    D_COUNT,
    D_INVERSE_SPEED,
    D_LENGTH,
    D_OCCUPIED,
    D_SPEED,
    G_DISTANCE,
    G_TIME,
    OFFSET,
    ON_ROAD,
    P_CELL,
    P_DT,
    P_LOOKAHEAD,
    P_PERIOD,
    P_REPLAN,
    State,
    Vehicles,
)  # fmt: skip
from hcomc.sim.corridor.step import accelerations, decide, sort_entries

__all__ = ["advance"]


@kernel(inline="always")
def _free_ahead(veh: Vehicles, s: State, code: int, x: float) -> tuple[float, int]:
    """Bumper gap [m] from x to the most upstream vehicle of lane ``code``, and that vehicle
    (inf, -1 if the lane is empty)."""
    j = s.code_first[code]
    if j < 0:
        return math.inf, -1
    return s.x[j] - veh.length[j] - x, j


@kernel
def _insert(road: Layout, veh: Vehicles, s: State, i: int, t: float) -> bool:
    """Put vehicle i on the road if its origin has room (module docstring)."""
    road, veh, s = borrow_all(road), borrow_all(veh), borrow_all(s)
    start = veh.start_code[i]
    if start < 0:
        x, first = veh.length[i], 0
        last = road.sec_lanes[section_at(road.sec_x0, x)] - 1
        exit_code = s.exit_code[i]
        if exit_code >= 0 and road.code_x1[exit_code] - x < (last + 1) * s.params[P_LOOKAHEAD]:
            last = 0  # its exit is within reach of the changes it will need: the lane to it
    else:
        x, first = road.code_far[start] + veh.length[i], start
        last = start + 1 if road.code_right[start] == start + 1 else start
    code, gap, lead = -1, -math.inf, -1
    for c in range(first, last + 1):
        g, j = _free_ahead(veh, s, c, x)
        if g > gap:
            code, gap, lead = c, g, j
    if gap < veh.s0[i]:
        return False
    v0e = min(veh.v0[i], speed_limit(road, code, x))
    v = min(v0e, (gap - veh.s0[i]) / veh.T[i])
    if lead >= 0 and v > s.v[lead]:
        free = free_term(v, v0e, veh.a[i], veh.b[i], veh.delta[i], False)
        acc = follow_accel_given(gap, v, s.v[lead], 0.0, v0e, veh.T[i], veh.s0[i], veh.a[i],
                                 veh.b[i], 0.0, False, free)  # fmt: skip
        if acc < -veh.b[i]:
            v = s.v[lead]
    s.x[i], s.v[i], s.a[i] = x, v, 0.0
    s.code[i] = s.target[i] = code
    s.status[i], s.insert_t[i] = ON_ROAD, t
    p = s.counters[C_ENTRIES]
    s.e_veh[p], s.e_code[p], s.e_key[p] = i, code, code * OFFSET + x
    s.counters[C_ENTRIES] = p + 1
    s.code_first[code] = i
    return True


@kernel
def release(road: Layout, veh: Vehicles, s: State, t: float) -> None:
    """Insert the due vehicles of each origin in order; record each origin's backlog."""
    road, veh, s = borrow_all(road), borrow_all(veh), borrow_all(s)
    period = min(int(t / s.params[P_PERIOD]), s.backlog.shape[1] - 1)
    for o in range(veh.queue_start.size - 1):
        q0, q1 = veh.queue_start[o], veh.queue_start[o + 1]
        k = q0 + s.queue_pos[o]
        while k < q1 and veh.depart[veh.queue[k]] <= t + 1e-9:
            if not _insert(road, veh, s, veh.queue[k], t):
                break
            k += 1
        s.queue_pos[o] = k - q0
        waiting = 0
        while k + waiting < q1 and veh.depart[veh.queue[k + waiting]] <= t + 1e-9:
            waiting += 1
        s.backlog[o, period] = max(s.backlog[o, period], waiting)


@kernel(inline="always")
def _detect(s: State, lane: int, x0: float, x1: float, v0: float, v1: float, length: float,
            t: float, dt: float) -> None:  # fmt: skip
    """Add a vehicle's move from x0 to x1 in [t, t + dt] to the loops it touched."""
    det, xs = s.detectors, s.det_x
    periods, period = det.shape[2], s.params[P_PERIOD]
    lo, hi = 0, xs.size
    while lo < hi:  # first loop downstream of the rear
        mid = (lo + hi) // 2
        if xs[mid] <= x0 - length:
            lo = mid + 1
        else:
            hi = mid
    moved = x1 - x0
    for k in range(lo, xs.size):
        xd = xs[k]
        if xd > x1:
            break
        here = min(int(t / period), periods - 1)
        if moved <= 0.0:
            det[k, lane, here, D_OCCUPIED] += dt
            continue
        enter = t
        if x0 < xd:  # the front crosses in this step
            f = (xd - x0) / moved
            enter = t + dt * f
            speed = v0 + (v1 - v0) * f
            when = min(int(enter / period), periods - 1)
            det[k, lane, when, D_COUNT] += 1.0
            det[k, lane, when, D_SPEED] += speed
            det[k, lane, when, D_INVERSE_SPEED] += 1.0 / max(speed, 1e-3)
            det[k, lane, when, D_LENGTH] += length
        leave = t + dt if x1 - length < xd else t + dt * (xd + length - x0) / moved
        det[k, lane, here, D_OCCUPIED] += max(0.0, leave - enter)


@kernel
def move(road: Layout, veh: Vehicles, s: State, t: float) -> None:
    """Integrate every vehicle over the step and measure the moves (module docstring)."""
    road, veh, s = borrow_all(road), borrow_all(veh), borrow_all(s)
    dt, counters = s.params[P_DT], s.counters
    every = counters[C_SAMPLE_EVERY]
    sample = every > 0 and counters[C_STEP] % every == 0
    cells, cell, cell_t = s.grid.shape[0], s.params[P_CELL], s.params[P_PERIOD]
    t_cell = min(int(t / cell_t), s.grid.shape[1] - 1)
    n_main = road.lane_end.shape[0]
    for k in range(counters[C_ON_ROAD]):
        i = s.ids[k]
        x0, v0, acc = s.x[i], s.v[i], s.acc[i]
        dx, s.v[i], s.a[i] = ballistic_step(v0, acc, dt)
        s.x[i] = x0 + dx
        lane = s.code[i]
        if s.target[i] != lane and t - s.lc_start[i] >= 0.5 * s.lc_dur[i]:
            lane = s.target[i]
        if lane < n_main:
            _detect(s, lane, x0, s.x[i], v0, s.v[i], veh.length[i], t, dt)
            c = min(max(int(0.5 * (x0 + s.x[i]) / cell), 0), cells - 1)
            s.grid[c, t_cell, G_DISTANCE] += s.x[i] - x0
            s.grid[c, t_cell, G_TIME] += dt
        if sample:
            r = counters[C_ROWS]
            out = lane if lane < n_main else -1 - (lane - n_main) % 2  # ramp lane j: -1 - j
            s.traj_t[r], s.traj_id[r], s.traj_x[r], s.traj_lane[r] = t, i, x0, out
            s.traj_code[r], s.traj_v[r], s.traj_a[r] = lane, v0, acc
            counters[C_ROWS] = r + 1
    counters[C_VEHICLE_STEPS] += counters[C_ON_ROAD]


@kernel
def finish(road: Layout, veh: Vehicles, s: State, t_next: float) -> None:
    """End finished lane changes, let vehicles arrive, note missed exits and collisions."""
    road, veh, s = borrow_all(road), borrow_all(veh), borrow_all(s)
    end = road.sec_x1[-1]
    for k in range(s.counters[C_ON_ROAD]):
        i = s.ids[k]
        if s.target[i] != s.code[i] and t_next - s.lc_start[i] >= s.lc_dur[i] - 1e-9:
            if road.code_kind[s.code[i]] == KIND_ON and road.code_kind[s.target[i]] == KIND_MAIN:
                s.merge_t[i], s.merge_x[i] = t_next, s.x[i]
            s.code[i] = s.target[i]
        c, x = s.code[i], s.x[i]
        kind = road.code_kind[c]
        if (kind == KIND_MAIN and x >= end) or (kind == KIND_OFF and x >= road.code_far[c]):
            s.status[i], s.arrive_t[i] = ARRIVED, t_next
        elif kind == KIND_MAIN and 0 <= s.exit_code[i] != s.target[i] and _past_exit(road, s, i):
            s.missed[i], s.exit_code[i] = True, -1
    _collisions(s, veh.length, t_next)


@kernel(inline="always")
def _past_exit(road: Layout, s: State, i: int) -> bool:
    """Whether vehicle i is past the last point where it could enter its off-ramp."""
    return s.x[i] > road.code_x1[s.exit_code[i]]


@kernel(inline="always")
def _collisions(s: State, length: np.ndarray, t: float) -> None:
    """Record each new overlap of a vehicle's body with its leader's in a lane."""
    m = s.counters[C_SORTED]
    for p in range(m - 1):
        if s.e_code[p + 1] != s.e_code[p]:
            continue
        f, lead = s.e_veh[p], s.e_veh[p + 1]
        if s.status[f] != ON_ROAD or s.status[lead] != ON_ROAD:
            continue
        gap = s.x[lead] - length[lead] - s.x[f]
        if gap < 0.0 and s.colliding[f] != lead:
            s.colliding[f] = lead
            r = s.counters[C_COLLISIONS]
            if r < s.collisions.shape[0]:
                s.collisions[r, 0], s.collisions[r, 1], s.collisions[r, 2] = t, f, lead
                s.collisions[r, 3], s.collisions[r, 4] = s.x[f], s.e_code[p]
            s.counters[C_COLLISIONS] = r + 1
        elif gap >= 0.0 and s.colliding[f] == lead:
            s.colliding[f] = -1


@kernel
def advance(road: Layout, veh: Vehicles, s: State, n_steps: int) -> None:
    """Run up to ``n_steps`` steps from ``counters[C_STEP]`` (module docstrings of this
    module, :mod:`hcomc.sim.corridor.step` and :mod:`hcomc.sim.corridor.plans`); return
    early, between steps, when VRs await the controller (``counters[C_PENDING]``)."""
    road, veh, s = borrow_all(road), borrow_all(veh), borrow_all(s)
    dt, controlled = s.params[P_DT], s.counters[C_CONTROLLED] != 0
    for _ in range(n_steps):
        step = s.counters[C_STEP]
        t, t_next = step * dt, (step + 1) * dt
        release(road, veh, s, t)
        sort_entries(s)
        if s.counters[C_OPEN]:
            track_events(veh, s, t)
        if controlled:
            mark_commanded(veh, s)
        accelerations(road, veh, s)
        if s.counters[C_PLANS]:
            virtual_leaders(veh, s, t)
            execute(road, veh, s, t, step)
        decide(road, veh, s, t, step)
        move(road, veh, s, t)
        finish(road, veh, s, t_next)
        if s.counters[C_PLANS]:
            finish_plans(road, s)
        identify(s, t_next)
        if controlled and s.params[P_REPLAN] > 0.0:
            due_replans(s, t_next)
        s.counters[C_STEP] = step + 1
        if s.counters[C_PENDING]:
            return
