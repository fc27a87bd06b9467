"""When each vehicle of a corridor's demand wants to enter: the departure schedule.

Both simulators read it, so they get the same vehicles at the same times: SUMO as one
``<flow>`` per :class:`Flow` (:mod:`hcomc.sumo.corridor`), hcomc as the
departure times of :func:`departure_times`.

Each origin's profile is cut into the piecewise-constant intervals of
:meth:`~hcomc.corridor.demand.OriginDemand.intervals` (a linear profile in steps of
:data:`PROFILE_STEP`). Per destination of share s, a vehicle departs whenever the cumulative
demand s * Q(t) passes k + phi, with phi = (j + 1/2) / n for the j-th of the origin's n
destinations, so that destinations take turns rather than arrive together; within an interval
of flow q the departures are evenly spaced, 3600 / (s q) seconds apart. The vehicles up to any
interval's end are the profile's integral rounded to a whole vehicle per destination, with no
bias from short intervals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hcomc.corridor.model import Corridor

__all__ = ["PROFILE_STEP", "Flow", "departure_times", "draw_classes", "flows"]

PROFILE_STEP = 60.0
"""Longest interval [s] a linear demand profile is cut into."""


@dataclass(frozen=True, slots=True)
class Flow:
    """``count`` vehicles from ``origin`` to ``destination``, the first at ``begin`` [s],
    then every ``period`` [s] (``rate`` = 3600 / period veh/h); ``interval`` numbers the
    profile interval it belongs to."""

    origin: str
    destination: str
    interval: int
    begin: float
    count: int
    rate: float

    @property
    def period(self) -> float:
        """Time between two departures [s]."""
        return 3600.0 / self.rate

    @property
    def end(self) -> float:
        """A time after the last departure and before the next one would be [s]."""
        return self.begin + (self.count - 0.5) * self.period

    def times(self) -> np.ndarray:
        """The departure times [s]."""
        return self.begin + self.period * np.arange(self.count)


def flows(c: Corridor, duration: float | None = None) -> list[Flow]:
    """Every flow of the corridor's demand over ``duration`` [s] (default: the corridor's),
    sorted by ``begin``."""
    out = []
    for origin, demand in c.demand.items():
        intervals = demand.intervals(c.corridor.duration if duration is None else duration,
                                     PROFILE_STEP)  # fmt: skip
        for j, (dest, share) in enumerate(demand.destinations.items()):
            phase = (j + 0.5) / len(demand.destinations)
            cumulative = 0.0  # expected vehicles to this destination so far
            for k, (a, b, q) in enumerate(intervals):
                rate = share * q  # [veh/h]
                before, cumulative = cumulative, cumulative + rate * (b - a) / 3600.0
                first = math.ceil(before - phase - 1e-9)  # next k with k + phase >= before
                count = math.floor(cumulative - phase - 1e-9) - first + 1
                if rate <= 0 or count <= 0:
                    continue
                begin = a + (first + phase - before) * 3600.0 / rate
                out.append(Flow(origin, dest, k, begin, count, rate))
    return sorted(out, key=lambda f: f.begin)


@dataclass(frozen=True, slots=True)
class Departures:
    """Every vehicle of the demand, sorted by departure time (ties by origin, destination)."""

    time: np.ndarray  # [s]
    origin: np.ndarray  # index into ``origins``
    destination: np.ndarray  # index into ``destinations``
    origins: tuple[str, ...]
    destinations: tuple[str, ...]


def departure_times(c: Corridor, duration: float | None = None) -> Departures:
    """The departures of all :func:`flows` over ``duration`` [s] (default: the corridor's):
    origins in the order of ``c.demand``, destinations ``exit`` first, then the off-ramps
    upstream first."""
    origins = tuple(c.demand)
    destinations = ("exit", *(r.id for r in c.road.off_ramps))
    times, origin, dest = [], [], []
    for f in flows(c, duration):
        t = f.times()
        times.append(t)
        origin.append(np.full(t.size, origins.index(f.origin)))
        dest.append(np.full(t.size, destinations.index(f.destination)))
    if not times:
        empty = np.zeros(0)
        return Departures(empty, empty.astype(int), empty.astype(int), origins, destinations)
    t_all, o_all, d_all = np.concatenate(times), np.concatenate(origin), np.concatenate(dest)
    order = np.lexsort((d_all, o_all, t_all))
    return Departures(t_all[order], o_all[order], d_all[order], origins, destinations)


def draw_classes(
    c: Corridor, d: Departures, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Each departure's vehicle class (an index into ``tuple(c.vehicles)``) and whether it
    is a CAV, drawn origin by origin from the origin's class and CAV shares with ``rng`` (as
    SUMO draws a flow's vehicle type from its ``vTypeDistribution``)."""
    classes = tuple(c.vehicles)
    vclass = np.zeros(d.time.size, dtype=np.int64)
    cav = np.zeros(d.time.size, dtype=np.bool_)
    for o, name in enumerate(d.origins):
        mine = np.flatnonzero(d.origin == o)
        demand = c.demand[name]
        names = list(demand.classes)
        p = np.array([demand.classes[k] for k in names])
        vclass[mine] = [classes.index(names[k]) for k in rng.choice(len(names), mine.size, p=p)]
        cav[mine] = rng.random(mine.size) < demand.cav_share
    return vclass, cav
