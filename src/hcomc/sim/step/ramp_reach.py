"""Where a run's ramp vehicles stand against the mainline, read from its compiled state:
whether every one released so far is still on the ramp before the acceleration lane
(:func:`ramp_untouched`), and whether one might reach the acceleration lane within a stretch
of time (:func:`ramp_may_reach`).

Until a ramp vehicle reaches the acceleration lane, the run's mainline is its undisturbed
run's (:mod:`hcomc.sim.twin`); learning environments call these for every episode at every
step, so they are compiled.
"""

from __future__ import annotations

from hcomc._jit import kernel
from hcomc.sim.lane_table import KIND_ON, L_KIND, L_OPENS
from hcomc.sim.step import state as layout

__all__ = ["ramp_may_reach", "ramp_untouched"]


@kernel
def ramp_untouched(c: layout.CoreArrays) -> bool:
    """Whether every ramp vehicle released so far in run ``c`` is still in its ramp lane
    before the acceleration lane and keeping its lane: the state part of
    :func:`hcomc.sim.twin.can_twin`."""
    for lane in range(c.queue_pos.size):
        if c.road_int[L_KIND, lane] != KIND_ON:
            continue
        start, first = c.road_f[L_OPENS, lane], c.queue_start[lane]
        for q in range(first, first + c.queue_pos[lane]):
            i = c.queues[q]
            on_ramp = c.active[i] and c.lane[i] == lane and c.origin[i] == c.target[i]
            if not (on_ramp and c.x[i] < start):
                return False
    return True


@kernel
def ramp_may_reach(c: layout.CoreArrays, horizon: float) -> bool:
    """Whether a ramp vehicle of run ``c`` might reach the acceleration lane within
    ``horizon`` [s]: a released one from its position and speed, one due for release by then
    from its release point and speed, each at its maximum acceleration all the way.

    Car following never exceeds that acceleration, an environment's actions are capped at it
    and no vehicle reverses, so False means none will unless driven harder from outside; a
    caller that relies on it checks afterwards with :func:`ramp_untouched`.
    """
    t = -c.consts[layout.WARMUP] + c.counters[layout.STEP] * c.consts[layout.DT]
    for lane in range(c.queue_pos.size):
        if c.road_int[L_KIND, lane] != KIND_ON:
            continue
        start = c.road_f[L_OPENS, lane]
        first, end = c.queue_start[lane], c.queue_start[lane + 1]
        released = first + c.queue_pos[lane]
        for q in range(first, end):
            i = c.queues[q]
            if q < released:
                if not c.active[i]:
                    continue
                x, v = c.x[i], c.v[i]
            elif c.d_t[i] <= t + horizon + 1e-9:
                x, v = c.d_x[i], c.d_v[i]
            else:
                continue
            if x + v * horizon + 0.5 * c.matrix[3, i] * horizon * horizon >= start:
                return True
    return False
