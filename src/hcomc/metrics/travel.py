"""Travel times and delays of the trips a run completed, per origin (mainline or ramp).

A *trip* is a vehicle inserted at its origin's upstream end (x = 0 on the mainline, the
ramp's start on the ramp: vehicles placed along the road at the start of the warm-up are
not trips) that left the road at its end (an EXIT event). Its travel time is the time
between the two events [s]; its delay is the travel time minus the free-flow time, the
distance driven at the desired speed of its kind (``hdv.desired_speed``, ``cav.desired_speed``
of the run's config) — the time a vehicle alone on the road would need, so delay ≥ 0 up to
the acceleration from the insertion speed. Only trips that ended in the measured time
(t ≥ 0, after the warm-up) count, as a traffic engineer counts the trips of a period.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from hcomc.road import Kind
from hcomc.sim.log import EventKind, SimulationLog

__all__ = ["TRAVEL_COLUMNS", "travel_summary", "trips"]

TRAVEL_COLUMNS = ("vehicle", "origin", "kind", "t_in", "t_out", "travel_time", "delay")
"""Columns of :func:`trips`."""

_AT_START = 1e-6  # [m] tolerance of "inserted at the origin's upstream end"


def trips(log: SimulationLog) -> pd.DataFrame:
    """One row per completed trip of ``log`` (module docstring), in the order the vehicles
    entered; columns :data:`TRAVEL_COLUMNS`, ``origin`` "main" or "ramp", ``kind`` "HDV" or
    "CAV"."""
    config = log.meta["config"]
    road = config["road"]
    starts = {"main": 0.0, "ramp": float(road["ramp_start"])}
    desired = {Kind.HDV: config["hdv"]["desired_speed"], Kind.CAV: config["cav"]["desired_speed"]}
    ins = log.events_of(EventKind.INSERTION)
    out = log.events_of(EventKind.EXIT)
    ended = dict(zip(out["vehicle"].tolist(), out["t"].tolist(), strict=True))
    rows = []
    for t_in, vehicle, x_in in zip(ins["t"], ins["vehicle"], ins["x"], strict=True):
        origin = next((o for o, x in starts.items() if abs(x_in - x) <= _AT_START), None)
        t_out = ended.get(int(vehicle))
        if origin is None or t_out is None or t_out < 0:
            continue
        kind = Kind(int(log.kind[vehicle]))
        free = (float(road["length"]) - float(x_in)) / float(desired[kind])
        travel = float(t_out - t_in)
        rows.append((int(vehicle), origin, kind.name, float(t_in), float(t_out), travel,
                     travel - free))  # fmt: skip
    return pd.DataFrame(rows, columns=list(TRAVEL_COLUMNS))


def travel_summary(log: SimulationLog) -> dict[str, dict[str, float | int | None]]:
    """Per origin: ``trips``, mean, median and 95th percentile of the travel time [s] and the
    mean delay [s] (None without trips)."""
    table = trips(log)
    summary: dict[str, dict[str, float | int | None]] = {}
    for origin in ("main", "ramp"):
        mine = table[table["origin"] == origin]
        times = mine["travel_time"].to_numpy()
        summary[origin] = {
            "trips": int(times.size),
            "mean_s": float(times.mean()) if times.size else None,
            "median_s": float(np.median(times)) if times.size else None,
            "p95_s": float(np.percentile(times, 95)) if times.size else None,
            "mean_delay_s": float(mine["delay"].mean()) if times.size else None,
        }
    return summary
