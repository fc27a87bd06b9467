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

from collections.abc import Iterable
from dataclasses import dataclass, fields
from itertools import pairwise

import numpy as np
import pandas as pd

from hcomc._typing import FloatArray
from hcomc.sim.log import SimulationLog

__all__ = ["DETECTOR_COLUMNS", "Crossings", "crossings", "detector_table"]

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


def _vehicle_rows(log: SimulationLog) -> pd.DataFrame:
    """Active cells ordered by vehicle then time: vehicle, t, x, v, lane, length."""
    cells = log.long_columns()
    frame = pd.DataFrame({k: cells[k] for k in ("vehicle", "t", "x", "v", "lane", "length")})
    return frame.sort_values(["vehicle", "t"], kind="stable", ignore_index=True)


def _first_reach(
    vehicle: np.ndarray, t: FloatArray, x: FloatArray, target: FloatArray, start: np.ndarray
) -> FloatArray:
    """Per entry k, the interpolated time at which vehicle ``vehicle[start[k]]`` first has
    x ≥ ``target[k]`` at or after row ``start[k]`` (its last row's time if never)."""
    out = np.empty(start.size)
    for k, r in enumerate(start.tolist()):
        row = r
        while row + 1 < x.size and vehicle[row + 1] == vehicle[r] and x[row + 1] < target[k]:
            row += 1
        if row + 1 < x.size and vehicle[row + 1] == vehicle[r]:
            share = (target[k] - x[row]) / (x[row + 1] - x[row])
            out[k] = t[row] + share * (t[row + 1] - t[row])
        else:
            out[k] = t[row]
    return out


def crossings(log: SimulationLog, x_d: float) -> Crossings:
    """The front crossings of position ``x_d`` [m] in ``log`` (module docstring)."""
    rows = _vehicle_rows(log)
    vehicle = rows["vehicle"].to_numpy(np.int64)
    t = rows["t"].to_numpy(np.float64)
    x = rows["x"].to_numpy(np.float64)
    same = vehicle[1:] == vehicle[:-1]
    consecutive = same & np.isclose(t[1:] - t[:-1], log.dt, rtol=1e-6)
    hit = np.flatnonzero(consecutive & (x[:-1] < x_d) & (x[1:] >= x_d))
    share = (x_d - x[hit]) / (x[hit + 1] - x[hit])
    v = rows["v"].to_numpy(np.float64)
    length = rows["length"].to_numpy(np.float64)[hit]
    return Crossings(
        vehicle=vehicle[hit],
        lane=rows["lane"].to_numpy(np.int64)[hit],
        t_front=t[hit] + share * (t[hit + 1] - t[hit]),
        speed=v[hit] + share * (v[hit + 1] - v[hit]),
        t_rear=_first_reach(vehicle, t, x, x_d + length, hit),
        length=length,
    )


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
    lanes: Iterable[int] | None = None,
) -> pd.DataFrame:
    """E1 measurements at every position [m] and lane, per interval [s] from the log's first
    time to one step past its last (a shorter last interval is dropped); ``lanes`` defaults,
    per position, to every lane a vehicle was counted in there. Columns
    :data:`DETECTOR_COLUMNS`."""
    if not interval > 0:
        raise ValueError(f"interval must be > 0 [s], got {interval}")
    times = log.t[np.isfinite(log.t)]
    t0, t1 = float(times[0]), float(times[-1]) + log.dt  # the last row stands for [t, t + dt)
    edges = t0 + interval * np.arange(int(np.floor((t1 - t0) / interval + 1e-9)) + 1)
    found = {float(p): crossings(log, float(p)) for p in positions}
    out = []
    for x_d, c in found.items():
        for lane in sorted(set(lanes) if lanes is not None else set(c.lane.tolist())):
            here = c.lane == lane
            mine = Crossings(*(getattr(c, f.name)[here] for f in fields(Crossings)))
            for begin, end in pairwise(edges.tolist()):
                row = {"x": x_d, "lane": lane, "begin": begin, "end": end}
                out.append(row | _interval_row(mine, begin, end))
    return pd.DataFrame(out, columns=list(DETECTOR_COLUMNS))
