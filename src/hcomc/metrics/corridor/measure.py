"""What a corridor run measured, read from its log: the induction loops, Edie's space-time
cells, the backlog at each origin, the collisions and the sampled trajectories.

The engine logs every vehicle at every step of a corridor run, so each measurement is a
function of the log (and of the demand, for the backlog) that any run of the engine can be
measured with:

* **loops**: SUMO's E1 quantities on every mainline lane at each detector position, per
  period (:func:`hcomc.metrics.detectors.detector_table`; lane 0 the rightmost);
* **Edie's cells**: per cell of ``cell_length`` metres along the mainline and period, the
  distance driven and the time spent by the vehicles on its mainline lanes (Edie 1963: the
  cell's flow is distance / (length x period), its density time / (length x period)); a
  step's move counts in the cell of its midpoint, in the period of its start;
* **backlog**: per origin and period, the most vehicles that had departed (their demand
  time passed) and were not yet on the road, at the start of any of the period's steps;
* **collisions**: one row per Eq. 7 contact as it begins (its two vehicles, ``vehicle`` the
  one released first, and ``x`` its front position);
* **trajectories**: every vehicle's state every ``interval`` seconds.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from hcomc.corridor import Corridor, detector_positions, sections
from hcomc.corridor.layout import lane_numbers, ramp_lane_count
from hcomc.metrics.cell_passes import edie_sums
from hcomc.metrics.detectors import VehicleRows, detector_table, holders
from hcomc.sim.log import EventKind, SimulationLog

__all__ = [
    "COLLISION_COLUMNS",
    "TRAJECTORY_COLUMNS",
    "backlog",
    "collision_table",
    "edie_cells",
    "loops",
    "trajectory_table",
]

COLLISION_COLUMNS = ("t", "vehicle", "other", "x")
"""Columns of :func:`collision_table`."""

TRAJECTORY_COLUMNS = {"t": np.float64, "id": np.int32, "x": np.float64, "lane": np.int8,
                      "code": np.int16, "v": np.float64, "a": np.float64}  # fmt: skip
"""Columns of :func:`trajectory_table` and their types: time [s], vehicle, front position
[m] along the mainline (continued along ramp roads), lane number (k >= 0 mainline lane k,
``-1 - j`` ramp lane j), the engine's lane code, speed [m/s] and acceleration [m/s^2]."""


def loops(c: Corridor, log: SimulationLog, rows: VehicleRows) -> pd.DataFrame:
    """The loops of corridor ``c`` on every mainline lane where they lie (module
    docstring)."""
    first = ramp_lane_count(c.road)
    cuts = sections(c.road)
    lanes = {}
    for x in detector_positions(c):
        section = next(s for s in reversed(cuts) if s.x0 <= x)
        lanes[float(x)] = range(first, first + section.lanes)
    table = detector_table(log, lanes, c.detectors.period, lanes, rows)
    table["lane"] -= first
    return table


def edie_cells(c: Corridor, rows: VehicleRows, duration: float) -> pd.DataFrame:
    """Distance [m] and time [s] in each space-time cell of the mainline (module
    docstring); columns ``x0, x1, t0, t1, distance, time``."""
    cell, period = c.detectors.cell_length, c.detectors.period
    n_cells = max(1, math.ceil(c.road.length / cell))
    n_periods = max(1, math.ceil(duration / period - 1e-9))
    main = lane_numbers(c.road) >= 0  # by lane code
    distance, spent = edie_sums(rows.vehicle, rows.row, rows.t, rows.x, rows.lane, main,
                                 cell, period, n_cells, n_periods)  # fmt: skip
    ix, it = np.meshgrid(np.arange(n_cells), np.arange(n_periods), indexing="ij")
    return pd.DataFrame({
        "x0": (ix * cell).ravel(), "x1": np.minimum((ix + 1) * cell, c.road.length).ravel(),
        "t0": (it * period).ravel(), "t1": ((it + 1) * period).ravel(),
        "distance": distance.ravel(), "time": spent.ravel(),
    })  # fmt: skip


def backlog(
    origins: tuple[str, ...], origin: np.ndarray, depart: np.ndarray, insert: np.ndarray,
    period: float, duration: float, dt: float,
) -> pd.DataFrame:  # fmt: skip
    """The most vehicles waiting at each origin per period (module docstring): one column
    per origin, a row per period with its ``begin`` [s]. ``origin`` indexes ``origins`` per
    vehicle, ``depart`` and ``insert`` are its demand and insertion times (NaN: never)."""
    n_periods = max(1, math.ceil(duration / period - 1e-9))
    steps = np.arange(round(duration / dt)) * dt
    cut = np.minimum((steps / period + 1e-9).astype(np.int64), n_periods - 1)
    starts = np.flatnonzero(np.diff(cut, prepend=-1))
    out = {}
    for o, name in enumerate(origins):
        mine = origin == o
        departed = np.searchsorted(np.sort(depart[mine]), steps + 1e-9, side="right")
        inserted = np.searchsorted(np.sort(insert[mine & ~np.isnan(insert)]), steps + 1e-9,
                                   side="right")  # fmt: skip
        waiting = np.maximum(departed - inserted, 0)
        most = np.maximum.reduceat(waiting, starts) if steps.size else np.zeros(0, np.int64)
        out[name] = np.zeros(n_periods, dtype=np.int64)
        out[name][cut[starts]] = most
    frame = pd.DataFrame(out)
    return frame.assign(begin=frame.index * period)


def collision_table(log: SimulationLog) -> pd.DataFrame:
    """One row per collision of the run (module docstring)."""
    found = log.events_of(EventKind.COLLISION)
    return pd.DataFrame({"t": found["t"], "vehicle": found["vehicle"], "other": found["other"],
                         "x": found["x"]}, columns=list(COLLISION_COLUMNS))  # fmt: skip


def trajectory_table(c: Corridor, log: SimulationLog, interval: float) -> pd.DataFrame:
    """Every vehicle on the road every ``interval`` seconds (a multiple of the logging
    interval), ordered by time, then vehicle; columns :data:`TRAJECTORY_COLUMNS`."""
    every = max(1, round(interval / log.dt))
    cells = log.cells
    picked = np.arange(0, int(log.n_recorded), every)
    row, column = np.nonzero(cells["active"][picked])
    row = picked[row]
    vehicle = column.astype(np.int64)
    if not log.one_column_per_vehicle:
        vehicle = holders(log, row, column)
    order = np.lexsort((vehicle, row))
    row, column, vehicle = row[order], column[order], vehicle[order]
    code = cells["lane"][row, column].astype(np.int64)
    columns = {
        "t": log.t[row], "id": vehicle, "x": cells["x"][row, column],
        "lane": lane_numbers(c.road)[code], "code": code, "v": cells["v"][row, column],
        "a": cells["a"][row, column],
    }  # fmt: skip
    return pd.DataFrame(
        {
            name: np.asarray(columns[name]).astype(dtype)
            for name, dtype in TRAJECTORY_COLUMNS.items()
        }
    )
