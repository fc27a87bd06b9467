"""Which lanes a vehicle's body occupies, and the follower-leader pairs that makes: any vehicle
on the road, a body over two lanes counting in both.

A vehicle is **in a lane change** in the logged rows with ``t_s <= t <= t_e`` between its
LANE_CHANGE_START event (time ``t_s``, ``value`` = target lane) and the next
LANE_CHANGE_END or LANE_CHANGE_ABORT event (time ``t_e``; none: to the end of the log). The
row logged at ``t_e`` is included because the engine logs a step's events at its start time
and its state at its end: that row still shows the body part-way. Its **body overlaps** lane
``L`` if ``abs(y - y_L) < (W + w) / 2``, with ``y`` its logged lateral position [m],
``y_L = (L - 1) W`` the lane's centre line, ``W`` the lane width (``road.lane_width``) and
``w`` its width [m]: the engine's own test of which lanes a changer occupies
(:mod:`hcomc.sim.step.motion`).

A vehicle occupies its logged lane and, while in a lane change, the lane next to it on the
side of its lateral offset from the logged lane's centre if its body overlaps that lane (the
origin lane once the logged lane has switched at the change's middle, the target lane
before). In each lane the occupants are in the **lane order** of
:mod:`hcomc.metrics.leaders` (by front bumper ``x``, ties in vehicle order, NaN last); each
occupant's **leader** is the next occupant, as the engine's followers see a changer from the
start of its change.
"""

from __future__ import annotations

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.metrics.lane_order import lane_order
from hcomc.metrics.window import EPS_T, road_of, times
from hcomc.road import N_LANES
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.log.slots import active_columns

__all__ = ["body_pairs", "change_targets", "overlaps"]


def change_targets(log: SimulationLog, vehicles: IntArray, t: FloatArray) -> IntArray:
    """(R, V) target lane of each of ``vehicles``' lane change in progress at the row times
    ``t`` (``t_s <= t <= t_e``, see the module docstring), -1 where it is not changing."""
    out = np.full((t.size, vehicles.size), -1, dtype=np.int64)
    starts = log.events_of(EventKind.LANE_CHANGE_START)
    starts = starts[np.isin(starts["vehicle"], vehicles)]
    if not starts.size:
        return out
    done = (log.events_of(EventKind.LANE_CHANGE_END), log.events_of(EventKind.LANE_CHANGE_ABORT))
    ends = np.sort(np.concatenate(done), order="t")
    for c, i in enumerate(vehicles.tolist()):
        s = starts[starts["vehicle"] == i]
        if not s.size:
            continue
        t_end = ends["t"][ends["vehicle"] == i]
        n_started = np.searchsorted(s["t"], t + EPS_T, side="right")
        n_ended = np.searchsorted(t_end, t - EPS_T, side="left")  # ended strictly before t
        on = n_started > n_ended
        out[on, c] = s["value"][n_started[on] - 1].astype(np.int64)
    return out


def overlaps(y: FloatArray, lane: IntArray, width: FloatArray, lane_width: float) -> np.ndarray:
    """Whether a body at lateral position ``y`` [m] of ``width`` [m] overlaps ``lane``
    (``abs(y - (lane - 1) W) < (W + w) / 2``); False where ``y`` is NaN."""
    with np.errstate(invalid="ignore"):
        return np.abs(y - (lane - 1.0) * lane_width) < 0.5 * (lane_width + width)


def _second_lanes(
    log: SimulationLog, row: IntArray, vehicle: IntArray, y: FloatArray, lane: IntArray
) -> IntArray:
    """Second lane of each roster entry (its row, vehicle, logged ``y`` and lane), -1 if
    none: for a vehicle in a lane change, the lane next to its logged lane on the side of its
    lateral offset, if its body overlaps it (0 <= lane < N_LANES)."""
    out = np.full(vehicle.size, -1, dtype=np.int64)
    changers = np.unique(log.events_of(EventKind.LANE_CHANGE_START)["vehicle"]).astype(np.int64)
    if not changers.size or not vehicle.size:
        return out
    r0 = int(row.min())
    t = times(log)[r0 : int(row.max()) + 1]
    targets = change_targets(log, changers, t)
    k = np.searchsorted(changers, vehicle).clip(max=changers.size - 1)
    changing = (changers[k] == vehicle) & (targets[row - r0, k] >= 0)
    lane_width = road_of(log).lane_width
    offset = y - (lane - 1.0) * lane_width
    side = np.where(np.isfinite(offset), np.sign(offset), 0.0).astype(np.int64)
    other = lane + side
    inside = (side != 0) & (other >= 0) & (other < N_LANES)
    width = log.width[vehicle].astype(np.float64)
    ok = changing & inside & overlaps(y, other, width, lane_width)
    out[ok] = other[ok]
    return out


def body_pairs(
    log: SimulationLog, rows: slice, vehicles: IntArray
) -> tuple[FloatArray, FloatArray]:
    """Bumper gaps and closing speeds of every follower-leader pair of a lane (module
    docstring) in the rows ``rows`` in which one of ``vehicles`` takes part, as follower or
    as leader.

    Returns ``(gap, closing)``, 1-D over the pairs: ``gap`` = x_l - L_l - x_f [m] (float64 of
    the logged positions), ``closing`` = v_f - v_l [m/s]. A pair with a NaN position is left
    out.
    """
    vehicles = np.asarray(vehicles, dtype=np.int64)
    r0, r1, _ = rows.indices(log.n_steps)
    r1 = max(r0, r1)
    if r1 == r0 or vehicles.size == 0:
        return np.empty(0), np.empty(0)
    cells = log.cells
    start, vehicle, column = active_columns(cells["active"], log.slot, log.span, r0, r1)
    row = np.repeat(np.arange(r0, r1), np.diff(start))  # each roster entry's row
    x = cells["x"][row, column].astype(np.float64)
    v = cells["v"][row, column].astype(np.float64)
    lane = cells["lane"][row, column].astype(np.int64)
    second = _second_lanes(log, row, vehicle, cells["y"][row, column].astype(np.float64), lane)
    twice = np.flatnonzero(second >= 0)
    extra = np.bincount(row[twice] - r0, minlength=r1 - r0)  # second entries per row
    start = start + np.concatenate(([0], np.cumsum(extra)))
    at = twice + 1  # a vehicle's second-lane entry right after its first: rows in vehicle order
    row, vehicle = np.insert(row, at, row[twice]), np.insert(vehicle, at, vehicle[twice])
    x, v = np.insert(x, at, x[twice]), np.insert(v, at, v[twice])
    lane = np.insert(lane, at, second[twice])
    order = lane_order(start, lane, x, vehicle)  # by row, lane, x (NaN last), vehicle
    f, ld = order[:-1], order[1:]  # each entry and the next one: follower, leader
    key = np.isin(vehicle, vehicles)
    pair = (row[f] == row[ld]) & (lane[f] == lane[ld]) & (key[f] | key[ld])
    f, ld = f[pair], ld[pair]
    gap = x[ld] - log.length[vehicle[ld]].astype(np.float64) - x[f]
    closing = v[f] - v[ld]
    ok = np.isfinite(gap)
    return gap[ok], closing[ok]
