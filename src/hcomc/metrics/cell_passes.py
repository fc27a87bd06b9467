"""Compiled passes over a run log's stored cells, for the measures read from the log.

A corridor hour logs some ten million (row, vehicle) cells. Numpy's vectorised forms of these
measures build an array the size of the log for each of their intermediate results (masks,
gathers, differences), and in a fresh process each such array costs its memory's first touch;
here each measure is one or two compiled passes in the order the cells are stored, writing only
what it returns. The
results are those of the numpy forms, in the same order of summation (the tests hold them to
it): :func:`cells_by_column` (the cells by vehicle,
:func:`hcomc.metrics.detectors.vehicle_rows`), :func:`pass_entries` (detector crossings),
:func:`closing_cells` (time to collision and DRAC of every cell) and :func:`edie_sums`
(Edie's space-time cells).
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray

LANE_APART = 1e7
"""Lanes apart in :func:`closing_cells`'s sort key (lane x LANE_APART + position) [m]: more
than any road is long."""

_BLOCK = 16
"""Columns :func:`cells_by_column` gathers side by side: one cache line of a row of ``active``
or ``x`` at a time, and few enough streams of output for the cache."""


@kernel
def cells_by_column(
    active: np.ndarray, x: np.ndarray, v: np.ndarray, lane: np.ndarray, t: np.ndarray,
    slot: np.ndarray, first: np.ndarray, takers: np.ndarray,
) -> tuple[np.ndarray, ...]:  # fmt: skip
    """The active cells of stored columns (T, S) ordered by column, then row, with the vehicle
    holding the column at the row (the last of ``takers``, sorted by ``first`` row, to take it at
    or before that row; see :func:`hcomc.metrics.detectors.holders`), as ``(vehicle, row, column,
    t, x, v, lane)``. The first pass counts each column's cells; the second reads the rows of
    :data:`_BLOCK` columns at a time in storage order and appends each cell to its column's block
    of the output."""
    n_rows, n_cols = active.shape
    at = np.zeros(n_cols + 1, dtype=np.int64)
    for k in range(n_rows):
        for s in range(n_cols):
            if active[k, s]:
                at[s + 1] += 1
    for s in range(n_cols):
        at[s + 1] += at[s]
    n = at[n_cols]
    vehicle, row, column = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    tt, xx, vv, ll = np.empty(n), np.empty(n), np.empty(n), np.empty(n, np.int64)
    holder = np.empty(n_cols, dtype=np.int64)
    for s0 in range(0, n_cols, _BLOCK):
        s1 = min(s0 + _BLOCK, n_cols)
        holder[s0:s1] = -1
        q = 0
        for k in range(n_rows):
            while q < takers.size and first[takers[q]] <= k:
                if s0 <= slot[takers[q]] < s1:
                    holder[slot[takers[q]]] = takers[q]
                q += 1
            for s in range(s0, s1):
                if active[k, s]:
                    e = at[s]
                    at[s] = e + 1
                    vehicle[e], row[e], column[e], tt[e] = holder[s], k, s, t[k]
                    xx[e], vv[e], ll[e] = x[k, s], v[k, s], lane[k, s]
    return vehicle, row, column, tt, xx, vv, ll


@kernel
def pass_entries(
    x: FloatArray, length: FloatArray, vehicle: np.ndarray, row: np.ndarray, rear: bool,
    positions: FloatArray,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`hcomc.metrics.detectors.all_crossings` in two passes over the entries, the first
    counting. The positions at or behind each entry are counted by a cursor carried from entry to
    entry (a vehicle's next row is a step further on), which gives what a binary search would."""
    n = 0
    if x.size == 0:
        return np.empty(0, np.int64), np.empty(0, np.int64)
    for phase in range(2):
        entry, index = np.empty(n, np.int64), np.empty(n, np.int64)
        e, behind = 0, _at_or_behind(positions, _position(x, length, rear, 0), 0)
        for k in range(x.size - 1):
            lo = behind
            behind = _at_or_behind(positions, _position(x, length, rear, k + 1), behind)
            if vehicle[k + 1] != vehicle[k] or row[k + 1] != row[k] + 1:
                continue
            for j in range(lo, behind):
                if phase == 1:
                    entry[e], index[e] = k, j
                e += 1
        n = e
    return entry, index


@kernel(inline="always")
def _position(x: FloatArray, length: FloatArray, rear: bool, k: int) -> float:
    """Entry k's front position, or its rear's."""
    return x[k] - length[k] if rear else x[k]


@kernel(inline="always")
def _at_or_behind(positions: FloatArray, p: float, cursor: int) -> int:
    """How many of the sorted ``positions`` are at or behind ``p`` (numpy's
    ``searchsorted(positions, p, side="right")``), moving from ``cursor``."""
    while cursor < positions.size and positions[cursor] <= p:
        cursor += 1
    while cursor > 0 and positions[cursor - 1] > p:
        cursor -= 1
    return cursor


@kernel
def closing_cells(
    active: np.ndarray, x: np.ndarray, v: np.ndarray, lane: np.ndarray, length: np.ndarray,
    slot: np.ndarray, first: np.ndarray, takers: np.ndarray, closing_speed: float,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The cells of :func:`hcomc.metrics.corridor.events.closing_in` (T, S), float32. Each row's
    active cells are ordered by lane, then position, by an insertion sort from the order of the
    row before (vehicles rarely overtake: a few moves a row; ties keep that order), and each cell
    is measured against the next in its lane: gap ``max(x_l - L_l - x, 1e-3)``, closing speed ``v
    - v_l`` (float32, as logged). A cell's length is that of the vehicle holding its column (the
    last of ``takers``, sorted by ``first`` row, to take it by that row)."""
    n_rows, n_cols = active.shape
    ttc = np.full((n_rows, n_cols), np.inf, dtype=np.float32)
    drac = np.zeros((n_rows, n_cols), dtype=np.float32)
    holder = np.full(n_cols, -1, dtype=np.int64)
    order, kept = np.empty(n_cols, dtype=np.int64), np.empty(n_cols, dtype=np.bool_)
    key = np.empty(n_cols)
    m, q = 0, 0
    for k in range(n_rows):
        while q < takers.size and first[takers[q]] <= k:
            holder[slot[takers[q]]] = takers[q]
            q += 1
        # the last row's order, its columns still active, then the columns that became so
        kept[:] = False
        n = 0
        for i in range(m):
            s = order[i]
            if active[k, s]:
                order[n], kept[s] = s, True
                n += 1
        for s in range(n_cols):
            if active[k, s] and not kept[s]:
                order[n] = s
                n += 1
        m = n
        for i in range(m):
            s = order[i]
            key[s] = lane[k, s] * LANE_APART + np.float64(x[k, s])
        for i in range(1, m):  # insertion sort, stable
            s = order[i]
            j = i
            while j > 0 and key[order[j - 1]] > key[s]:
                order[j] = order[j - 1]
                j -= 1
            order[j] = s
        for i in range(m - 1):
            f, ahead = order[i], order[i + 1]
            if lane[k, f] != lane[k, ahead]:
                continue
            closing = v[k, f] - v[k, ahead]
            if closing >= closing_speed:
                rear = np.float64(x[k, ahead]) - np.float64(length[holder[ahead]])
                gap = max(rear - np.float64(x[k, f]), 1e-3)
                ttc[k, f] = gap / closing
                drac[k, f] = closing * closing / (2.0 * gap)
    return ttc, drac


@kernel
def edie_sums(
    vehicle: np.ndarray, row: np.ndarray, t: np.ndarray, x: np.ndarray, lane: np.ndarray,
    main: np.ndarray, cell: float, period: float, n_cells: int, n_periods: int,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(n_cells, n_periods) distance [m] and time [s] of
    :func:`hcomc.metrics.corridor.measure.edie_cells`: each move from one logged row of a vehicle
    to its next, on a mainline lane (by the lane code of its start), summed into the cell of its
    midpoint and the period of its start, in the order of the entries."""
    distance = np.zeros((n_cells, n_periods))
    spent = np.zeros((n_cells, n_periods))
    for k in range(vehicle.size - 1):
        if vehicle[k + 1] != vehicle[k] or row[k + 1] != row[k] + 1 or not main[lane[k]]:
            continue
        where = min(max(int(0.5 * (x[k] + x[k + 1]) / cell), 0), n_cells - 1)
        when = min(max(int(t[k] / period), 0), n_periods - 1)
        distance[where, when] += x[k + 1] - x[k]
        spent[where, when] += t[k + 1] - t[k]
    return distance, spent
