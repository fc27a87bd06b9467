"""One row per vehicle of a corridor run: where it came from and went, when it departed,
entered, merged and arrived, how it ended, its travel time and delay.

A vehicle's route runs from its insertion (front one length past its origin's start) to its
arrival, when its rear passes the end of the road it leaves by (the mainline's, or its
off-ramp road's; the mainline's for one that missed its exit), where the engine removes it:
its front drives as far as from the origin's start to that end. Its free-flow time is the
time to drive that at min(desired speed, speed limit) everywhere (the limit of where its
front is, the last one beyond the end): the travel time it would have alone on the road,
apart from accelerating (a vehicle enters at its desired speed on a free road). Its delay is
its travel time minus that.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from hcomc.corridor import Corridor, OffRamp, OnRamp, sections
from hcomc.sim.log import EventKind, SimulationLog

__all__ = ["OUTCOMES", "Released", "first_event", "free_flow_times", "trip_table"]

OUTCOMES = ("arrived", "missed_exit", "on_road", "not_inserted")
"""A vehicle's outcome: arrived at its destination; arrived at the mainline's end after
missing its off-ramp; still on the road at the end; never inserted (backlog)."""


@dataclass(frozen=True, slots=True)
class Released:
    """Who a corridor run released, by vehicle index (N,): ``origin`` and ``destination``
    (indices into ``origins`` and ``destinations``), ``vclass`` (into ``classes``), ``cav``,
    ``depart`` [s], ``desired`` speed [m/s] and ``length`` [m]."""

    origins: tuple[str, ...]
    destinations: tuple[str, ...]
    classes: tuple[str, ...]
    origin: np.ndarray
    destination: np.ndarray
    vclass: np.ndarray
    cav: np.ndarray
    depart: np.ndarray
    desired: np.ndarray
    length: np.ndarray


def _pieces(c: Corridor, start: str, end: str) -> list[tuple[float, float, float]]:
    """(x0, x1, speed limit) pieces of the route from origin ``start`` to ``end``."""
    road = c.road
    pieces: list[tuple[float, float, float]] = []
    x_from, x_to, tail = 0.0, road.length, None
    for ramp in road.ramps:
        if isinstance(ramp, OnRamp) and ramp.id == start:
            pieces.append((ramp.x - ramp.ramp_length, ramp.x, road.speed_at(ramp.x)))
            x_from = ramp.x
        if isinstance(ramp, OffRamp) and ramp.id == end:
            x_to, tail = ramp.end, (ramp.end, ramp.end + ramp.ramp_length, road.speed_at(ramp.x))
    for s in sections(road):
        x0, x1 = max(s.x0, x_from), min(s.x1, x_to)
        if x1 > x0:
            pieces.append((x0, x1, s.speed_limit))
    if tail is not None:
        pieces.append(tail)
    return pieces


def free_flow_times(
    c: Corridor, who: Released, missed: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Free-flow time [s] and route length [m] of every vehicle (module docstring)."""
    n = who.depart.size
    free, length = np.zeros(n), np.zeros(n)
    for o, origin in enumerate(who.origins):
        for d, dest in enumerate(who.destinations):
            for was_missed in (False, True):
                rows = (who.origin == o) & (who.destination == d) & (missed == was_missed)
                if not rows.any():
                    continue
                pieces = _pieces(c, origin, "exit" if was_missed else dest)
                body = who.length[rows]
                start = pieces[0][0] + body  # the front enters one length in ...
                for k, (x0, x1, limit) in enumerate(pieces):
                    end = x1 + body if k == len(pieces) - 1 else x1  # ... and leaves one past
                    covered = np.maximum(end - np.maximum(x0, start), 0.0)
                    free[rows] += covered / np.minimum(who.desired[rows], limit)
                    length[rows] += covered
    return free, length


def first_event(log: SimulationLog, kind: EventKind, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Per vehicle, the time and position of its first event of ``kind`` (NaN: none)."""
    found = log.events_of(kind)[::-1]  # the first event of a vehicle written last
    t, x = np.full(n, np.nan), np.full(n, np.nan)
    t[found["vehicle"]], x[found["vehicle"]] = found["t"], found["x"]
    return t, x


def trip_table(c: Corridor, who: Released, log: SimulationLog) -> pd.DataFrame:
    """The trips of a finished run (module docstring), a row per vehicle in release order."""
    n = who.depart.size
    insert, _ = first_event(log, EventKind.INSERTION, n)
    arrive, _ = first_event(log, EventKind.EXIT, n)
    merge_t, merge_x = first_event(log, EventKind.MERGE, n)
    missed = ~np.isnan(first_event(log, EventKind.MISSED_EXIT, n)[0])
    outcome = np.where(
        ~np.isnan(arrive),
        np.where(missed, "missed_exit", "arrived"),
        np.where(~np.isnan(insert), "on_road", "not_inserted"),
    )
    travel = arrive - insert
    free, route = free_flow_times(c, who, missed)
    return pd.DataFrame(
        {
            "id": np.arange(n),
            "origin": np.array(who.origins, dtype=object)[who.origin],
            "destination": np.array(who.destinations, dtype=object)[who.destination],
            "vclass": np.array(who.classes, dtype=object)[who.vclass],
            "cav": who.cav,
            "depart": who.depart,
            "insert": insert,
            "arrive": arrive,
            "outcome": outcome,
            "merge_time": merge_t,
            "merge_x": merge_x,
            "travel_time": travel,
            "delay": travel - free,
            "route_length": route,
        }
    )
