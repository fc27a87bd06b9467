"""Virtual induction loops: what a detector at position x would have counted, per lane and
interval, measured on a run's log with the quantities of SUMO's E1 detectors (SUMO
documentation, "Induction Loops Detectors (E1)": nVehContrib, flow, occupancy, speed,
harmonicMeanSpeed, length). One difference: SUMO counts a vehicle in the interval in which its
rear leaves the loop, this module in the interval in which its front reaches it; the two
differ only for a vehicle on the loop at an interval's boundary.

A vehicle is counted by a detector when its front crosses the detector's position x_d
moving downstream; the time and speed of the crossing are interpolated linearly between the
two logged rows around it, and the vehicle is counted in the lane it occupies in the first of
them (a vehicle in the middle of a lane change counts in the lane it is leaving, as its
logged lane says). Per detector, lane and interval [begin, end):

========================  ======================================================================
``count``                 vehicles whose front crossed x_d in the interval
``flow`` [veh/h]          3600 · count / (end − begin)
``speed`` [m/s]           arithmetic (time-) mean of their crossing speeds; NaN without vehicles
``harmonic_speed`` [m/s]  harmonic mean of the crossing speeds, the space-mean speed estimate
``occupancy`` [%]         share of the interval during which some vehicle's body covered x_d:
                          each vehicle from its front's to its rear's crossing, clipped to the
                          interval (overlapping vehicles in one lane do not occur)
``mean_length`` [m]       mean length of the counted vehicles
========================  ======================================================================

The rear crosses when the front reaches x_d + length; a vehicle whose rear has not crossed by
the end of the log covers the detector until then. Only rows in which the vehicle is active
count, so a vehicle that enters or leaves the road at x_d is not counted twice or half.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields
from itertools import pairwise

import numpy as np
import pandas as pd

from hcomc._typing import FloatArray
from hcomc.metrics.cell_passes import cells_by_column, pass_entries
from hcomc.sim.log import SimulationLog

__all__ = [
    "DETECTOR_COLUMNS", "Crossings", "VehicleRows", "all_crossings", "column_takers",
    "crossings", "detector_table", "holders", "vehicle_rows",
]  # fmt: skip

DETECTOR_COLUMNS = (
    "x", "lane", "begin", "end", "count", "flow", "speed", "harmonic_speed", "occupancy",
    "mean_length",
)  # fmt: skip
"""Columns of :func:`detector_table`, in order."""


@dataclass(frozen=True)
class Crossings:
    """Every downstream crossing of one position by a vehicle's front (one entry each)."""

    vehicle: np.ndarray  # (K,) int64
    lane: np.ndarray  # (K,) int64, the logged lane in the row before the crossing
    t_front: FloatArray  # (K,) [s]
    speed: FloatArray  # (K,) [m/s] at the crossing
    t_rear: FloatArray  # (K,) [s] when the rear crossed (the log's end if it had not)
    length: FloatArray  # (K,) [m]


@dataclass(frozen=True)
class VehicleRows:
    """A log's active cells grouped by vehicle, each vehicle's in time order (K,): its
    ``vehicle``, logged ``row`` and stored ``column``, ``t`` [s], ``x`` [m], ``v`` [m/s],
    ``lane`` and ``length`` [m]. The groups come in the order of the log's stored columns,
    so reading them needs no sort however long the run (:mod:`hcomc.sim.log.slots`)."""

    vehicle: np.ndarray
    row: np.ndarray
    column: np.ndarray
    t: FloatArray
    x: FloatArray
    v: FloatArray
    lane: np.ndarray
    length: FloatArray

    def next_is_same(self) -> np.ndarray:
        """(K - 1,) whether entry k + 1 is the same vehicle's next logged row."""
        return (self.vehicle[1:] == self.vehicle[:-1]) & (self.row[1:] == self.row[:-1] + 1)

    def last_of_vehicle(self, entries: np.ndarray) -> np.ndarray:
        """The last entry of the vehicle of each of ``entries``."""
        ends = np.append(
            np.flatnonzero(self.vehicle[1:] != self.vehicle[:-1]), self.vehicle.size - 1
        )
        return ends[np.searchsorted(ends, entries)]


def holders(log: SimulationLog, row: np.ndarray, column: np.ndarray) -> np.ndarray:
    """The vehicle holding stored column ``column[k]`` at row ``row[k]`` of a slot-column
    log (:mod:`hcomc.sim.log.slots`): the last vehicle to take that column at or before that
    row, found without the (T, S) grid of the log's owners."""
    held = np.flatnonzero(log.slot >= 0)
    keys = log.slot[held] * log.n_steps + log.span[held, 0]
    order = np.argsort(keys, kind="stable")
    at = np.searchsorted(keys[order], column * log.n_steps + row, side="right") - 1
    return held[order][at]


def column_takers(log: SimulationLog) -> tuple[np.ndarray, np.ndarray]:
    """Each vehicle's first logged row, and the vehicles that took a stored column, ordered
    by that row (stably): what the compiled passes walk to know a column's holder at a row
    (:mod:`hcomc.metrics.cell_passes`)."""
    first = np.asarray(log.span[:, 0], dtype=np.int64)
    takers = np.flatnonzero(log.slot >= 0)
    return first, takers[np.argsort(first[takers], kind="stable")]


def vehicle_rows(log: SimulationLog) -> VehicleRows:
    """The active cells of ``log`` by vehicle (:class:`VehicleRows`), gathered in two passes
    over its rows (:func:`hcomc.metrics.cell_passes.cells_by_column`)."""
    cells = log.cells
    first, takers = column_takers(log)
    vehicle, row, column, t, x, v, lane = cells_by_column(
        cells["active"], cells["x"], cells["v"], cells["lane"], log.t, log.slot, first, takers
    )
    length = np.asarray(log.length, dtype=np.float64)[vehicle]
    return VehicleRows(vehicle, row, column, t, x, v, lane, length)


def _passes(rows: VehicleRows, rear: bool, positions: FloatArray) -> tuple[np.ndarray, np.ndarray]:
    """Entries k and position indices j with p[k] < positions[j] <= p[k + 1] for entries k and
    k + 1 that are one vehicle's consecutive logged rows (:meth:`VehicleRows.next_is_same`),
    where p is the front position ``x``, or with ``rear`` the rear ``x - length`` (positions
    sorted): in the order of k, then j (:func:`hcomc.metrics.cell_passes.pass_entries`)."""
    return pass_entries(rows.x, rows.length, rows.vehicle, rows.row, rear, positions)


def _rear_times(
    rows: VehicleRows, k: np.ndarray, j: np.ndarray, t_front: FloatArray, rear_key: np.ndarray,
    rear_t: FloatArray, n_pos: int,
) -> FloatArray:  # fmt: skip
    """When the rear of the vehicle of each front crossing (entry ``k``, position ``j``)
    crossed the same position: its rear crossing (key vehicle * n_pos + position) at or
    after the front's, else the vehicle's last logged time."""
    last = rows.t[rows.last_of_vehicle(k)]
    if rear_key.size == 0:
        return last
    order = np.argsort(rear_key, kind="stable")
    key, when = rear_key[order], rear_t[order]
    front_key = rows.vehicle[k] * n_pos + j
    at = np.minimum(np.searchsorted(key, front_key), key.size - 1)
    matched = (key[at] == front_key) & (when[at] >= t_front)
    return np.where(matched, when[at], last)


def all_crossings(rows: VehicleRows, positions: Iterable[float]) -> dict[float, Crossings]:
    """The front crossings of each position [m] (module docstring), by position."""
    where = np.unique(np.asarray(list(positions), dtype=np.float64))
    k, j = _passes(rows, False, where)
    share = (where[j] - rows.x[k]) / (rows.x[k + 1] - rows.x[k])
    t_front = rows.t[k] + share * (rows.t[k + 1] - rows.t[k])
    rear_k, rear_j = _passes(rows, True, where)
    rear_share = (where[rear_j] - rows.x[rear_k] + rows.length[rear_k]) / (
        rows.x[rear_k + 1] - rows.x[rear_k]
    )
    rear_t = rows.t[rear_k] + rear_share * (rows.t[rear_k + 1] - rows.t[rear_k])
    t_rear = _rear_times(rows, k, j, t_front, rows.vehicle[rear_k] * where.size + rear_j, rear_t,
                         where.size)  # fmt: skip
    out = {}
    for index, x_d in enumerate(where.tolist()):
        mine = np.flatnonzero(j == index)
        mine = mine[np.lexsort((t_front[mine], rows.vehicle[k[mine]]))]
        e = k[mine]
        out[x_d] = Crossings(
            vehicle=rows.vehicle[e], lane=rows.lane[e], t_front=t_front[mine],
            speed=rows.v[e] + share[mine] * (rows.v[e + 1] - rows.v[e]), t_rear=t_rear[mine],
            length=rows.length[e],
        )  # fmt: skip
    return out


def crossings(log: SimulationLog, x_d: float) -> Crossings:
    """The front crossings of position ``x_d`` [m] in ``log`` (module docstring)."""
    return all_crossings(vehicle_rows(log), [x_d])[float(x_d)]


def _interval_row(c: Crossings, begin: float, end: float) -> dict[str, float]:
    counted = (c.t_front >= begin) & (c.t_front < end)
    speeds = c.speed[counted]
    covered = np.clip(np.minimum(c.t_rear, end) - np.maximum(c.t_front, begin), 0.0, None)
    n = int(counted.sum())
    return {
        "count": n,
        "flow": 3600.0 * n / (end - begin),
        "speed": float(speeds.mean()) if n else np.nan,
        "harmonic_speed": float(n / np.sum(1.0 / speeds)) if n and (speeds > 0).all() else np.nan,
        "occupancy": 100.0 * float(covered.sum()) / (end - begin),
        "mean_length": float(c.length[counted].mean()) if n else np.nan,
    }


def detector_table(
    log: SimulationLog,
    positions: Iterable[float],
    interval: float = 60.0,
    lanes: Iterable[int] | Mapping[float, Iterable[int]] | None = None,
    rows: VehicleRows | None = None,
) -> pd.DataFrame:
    """E1 measurements at every position [m] and lane, per interval [s] from the log's first
    time to one step past its last (a shorter last interval is dropped); ``lanes`` (the same
    for every position, or per position) defaults, per position, to every lane a vehicle was
    counted in there; ``rows``: the log's :func:`vehicle_rows` when already read. Columns
    :data:`DETECTOR_COLUMNS`."""
    if not interval > 0:
        raise ValueError(f"interval must be > 0 [s], got {interval}")
    times = log.t[np.isfinite(log.t)]
    t0, t1 = float(times[0]), float(times[-1]) + log.dt  # the last row stands for [t, t + dt)
    edges = t0 + interval * np.arange(int(np.floor((t1 - t0) / interval + 1e-9)) + 1)
    found = all_crossings(vehicle_rows(log) if rows is None else rows, positions)
    out = []
    for x_d, c in found.items():
        here_lanes = lanes.get(x_d, ()) if isinstance(lanes, Mapping) else lanes
        for lane in sorted(set(here_lanes) if here_lanes is not None else set(c.lane.tolist())):
            here = c.lane == lane
            mine = Crossings(*(getattr(c, f.name)[here] for f in fields(Crossings)))
            for begin, end in pairwise(edges.tolist()):
                row = {"x": x_d, "lane": lane, "begin": begin, "end": end}
                out.append(row | _interval_row(mine, begin, end))
    return pd.DataFrame(out, columns=list(DETECTOR_COLUMNS))
