"""Actual leaders and followers in a lane, row by row: any vehicle on the road, key or not.

Definition: in a logged row, the vehicles of a lane are the active vehicles whose *logged*
lane it is, in the **lane order**: sorted by front-bumper position ``x``, ties in vehicle
order, NaN positions last (numpy's stable sort, as the lane profiles sort their knots). A
vehicle's **leader** is the next vehicle in that order, its **follower** the previous one.
The bumper gap to the leader is :math:`x_l - L_l - x_f` [m] (float64 of the logged float32
positions); two vehicles at the same ``x`` are leader and follower with a negative gap (an
overlap), not hidden from each other. A vehicle with a NaN position has no leader, and is
nobody's leader.

A vehicle between two key vehicles is the follower's leader: the gap measured is the one the
follower actually keeps. (TTC and DRAC also count a vehicle in a lane change in both lanes
while its body overlaps both: :mod:`hcomc.metrics.bodies`.)
"""

from __future__ import annotations

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.metrics.lane_order import lane_order
from hcomc.sim.log import SimulationLog
from hcomc.sim.log.slots import active_columns

__all__ = ["lane_follower", "lane_leaders"]


def lane_leaders(
    log: SimulationLog, rows: slice, vehicles: IntArray
) -> tuple[IntArray, FloatArray]:
    """Each of ``vehicles``' actual leader and bumper gap to it in the rows ``rows``.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    rows : slice
        Contiguous logged rows (step 1), e.g. from :func:`hcomc.metrics.window.rows_between`.
    vehicles : array of int
        Distinct vehicle indices (K,).

    Returns
    -------
    leader : numpy.ndarray
        (R, K) int64: the leader of ``vehicles[j]`` in row ``rows.start + r`` (module
        docstring), -1 where it has none (inactive, nobody ahead in its lane, or a NaN
        position).
    gap : numpy.ndarray
        (R, K) float64: ``x_l - L_l - x_f`` [m], NaN where there is no leader.
    """
    vehicles = np.asarray(vehicles, dtype=np.int64)
    r0, r1, _ = rows.indices(log.n_steps)
    r1 = max(r0, r1)
    leader = np.full((r1 - r0, vehicles.size), -1, dtype=np.int64)
    gap = np.full((r1 - r0, vehicles.size), np.nan)
    if r1 == r0 or vehicles.size == 0:
        return leader, gap
    cells = log.cells
    start, vehicle, column = active_columns(cells["active"], log.slot, log.span, r0, r1)
    row = np.repeat(np.arange(r0, r1), np.diff(start))  # each roster entry's row
    x = cells["x"][row, column].astype(np.float64)
    lane = cells["lane"][row, column].astype(np.int64)
    order = lane_order(start, lane, x, vehicle)  # by row, lane, x (NaN last), vehicle
    ahead = np.empty(order.size, dtype=np.int64)  # the roster entry of each entry's leader
    ahead[order[:-1]] = order[1:]
    if order.size:
        ahead[order[-1]] = -1
    asked = np.flatnonzero(np.isin(vehicle, vehicles))
    nxt = ahead[asked]
    lead = nxt >= 0
    lead[lead] &= (row[nxt[lead]] == row[asked[lead]]) & (lane[nxt[lead]] == lane[asked[lead]])
    asked, nxt = asked[lead], nxt[lead]
    d = x[nxt] - log.length[vehicle[nxt]].astype(np.float64) - x[asked]
    ok = np.isfinite(d)  # a NaN position on either side: no leader
    asked, nxt, d = asked[ok], nxt[ok], d[ok]
    sorter = np.argsort(vehicles, kind="stable")
    cols = sorter[np.searchsorted(vehicles, vehicle[asked], sorter=sorter)]
    leader[row[asked] - r0, cols] = vehicle[nxt]
    gap[row[asked] - r0, cols] = d
    return leader, gap


def lane_follower(log: SimulationLog, row: int, vehicle: int, lane: int) -> int:
    """The follower of ``vehicle`` in ``lane`` in logged row ``row`` (module docstring),
    counting ``vehicle`` in ``lane`` whatever its logged lane: the vehicle just behind it in
    the lane order; -1 if ``vehicle`` is inactive or has a NaN position, or nobody is behind
    it."""
    active = np.asarray(log.active[row], dtype=bool)
    x = np.asarray(log.x[row], dtype=np.float64)
    if not active[vehicle] or np.isnan(x[vehicle]):
        return -1
    on = active & (np.asarray(log.lane[row]) == lane)
    on[vehicle] = True
    ids = np.flatnonzero(on)
    ordered = ids[np.lexsort((ids, x[ids]))]
    k = int(np.flatnonzero(ordered == vehicle)[0])
    return int(ordered[k - 1]) if k > 0 else -1
