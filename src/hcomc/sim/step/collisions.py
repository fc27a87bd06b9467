"""The collision check of the compiled step (Eq. 7): which pairs of vehicles touch, and which
contacts begin (logged as collision events)."""

from __future__ import annotations

import math

from hcomc._jit import kernel
from hcomc.equations._collision_kernels import vehicle_pair_collides
from hcomc.sim.arrays import search_left, unique
from hcomc.sim.neighbours import LaneIndex
from hcomc.sim.step.state import (
    COLLISIONS,
    EV_COLLISION,
    N_COLLIDING,
    S_CODES,
    CoreArrays,
    add_event,
)

__all__ = ["check_collisions"]


@kernel
def check_collisions(c: CoreArrays, t: float, index: LaneIndex) -> None:
    """Oriented-rectangle test (Eq. 7) of each entry against its next two leaders per lane;
    a pair is logged when its contact begins.

    A 1-D prefilter skips pairs whose x-extents cannot overlap: a rectangle whose front
    bumper centre is at x lies within ``[x - L - W/2, x + W/2]`` for any heading.
    """
    vs, ls = index.vehicle, index.lane
    n = c.x.size
    codes = c.scratch_int[S_CODES]  # at most 2 pairs per entry
    m = 0
    for gap in (1, 2):
        for p in range(vs.size - gap):
            i, j = vs[p], vs[p + gap]
            if ls[p] != ls[p + gap] or i == j:
                continue
            if c.x[i] + 0.5 * c.width[i] < c.x[j] - c.length[j] - 0.5 * c.width[j]:
                continue
            if vehicle_pair_collides(
                c.x[i],
                c.y[i],
                c.heading[i],
                c.length[i],
                c.width[i],
                c.x[j],
                c.y[j],
                c.heading[j],
                c.length[j],
                c.width[j],
            ):
                codes[m] = min(i, j) * n + max(i, j)
                m += 1
    if m == 0:  # the usual step: nothing in contact, nothing begins
        c.counters[N_COLLIDING] = 0
        return
    now = unique(codes[:m])
    before = c.colliding[: c.counters[N_COLLIDING]]
    for code in now:
        k = search_left(before, code)
        if k < before.size and before[k] == code:
            continue
        i, j = code // n, code % n
        add_event(c, t, EV_COLLISION, i, j, c.x[i], math.nan)
        c.counters[COLLISIONS] += 1
    c.colliding[: now.size] = now
    c.counters[N_COLLIDING] = now.size
