"""Route lengths and free-flow travel times of a corridor's vehicles, for their delay.

A vehicle's route runs from its insertion point (front one length past its origin's start)
to where it arrives (the mainline's end, or the end of its off-ramp's road; the mainline's
end for one that missed its exit). Its free-flow time is the time to drive that route at
min(desired speed, speed limit) everywhere: the travel time it would have alone on the road,
apart from accelerating (a vehicle enters at its desired speed on a free road).
"""

from __future__ import annotations

import numpy as np

from hcomc.corridor import Corridor
from hcomc.sim.corridor.fleet import CorridorFleet
from hcomc.sim.corridor.layout import Layout

__all__ = ["free_flow_times"]


def _limits_along(
    c: Corridor, layout: Layout, start: str, end: str
) -> list[tuple[float, float, float]]:
    """(x0, x1, speed limit) pieces of the route from origin ``start`` to ``end``."""
    road = c.road
    pieces: list[tuple[float, float, float]] = []
    x_from = 0.0
    for ramp in road.on_ramps:
        if ramp.id == start:
            pieces.append((ramp.x - ramp.ramp_length, ramp.x, road.speed_at(ramp.x)))
            x_from = ramp.x
    x_to, tail = road.length, None
    for off in road.off_ramps:
        if off.id == end:
            x_to, tail = off.end, (off.end, off.end + off.ramp_length, road.speed_at(off.x))
    for k in range(layout.sec_x0.size):
        x0, x1 = max(layout.sec_x0[k], x_from), min(layout.sec_x1[k], x_to)
        if x1 > x0:
            pieces.append((float(x0), float(x1), float(layout.sec_speed[k])))
    if tail is not None:
        pieces.append(tail)
    return pieces


def free_flow_times(
    c: Corridor, layout: Layout, fleet: CorridorFleet, missed: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Free-flow time [s] and route length [m] of every vehicle (module docstring)."""
    n = fleet.depart.size
    free, length = np.zeros(n), np.zeros(n)
    v0 = np.minimum(fleet.idm[:, 0], fleet.max_speed)
    for o, origin in enumerate(fleet.origins):
        for d, dest in enumerate(fleet.destinations):
            for was_missed in (False, True):
                rows = (fleet.origin == o) & (fleet.destination == d) & (missed == was_missed)
                if not rows.any():
                    continue
                pieces = _limits_along(c, layout, origin, "exit" if was_missed else dest)
                start = pieces[0][0] + fleet.length[rows]  # the front enters one length in
                for x0, x1, limit in pieces:
                    lo = np.maximum(x0, start)
                    covered = np.maximum(x1 - lo, 0.0)
                    free[rows] += covered / np.minimum(v0[rows], limit)
                    length[rows] += covered
    return free, length
