"""The vehicles of a corridor run: who departs when and where, with which parameters.

Departure times, origins and destinations come from the corridor's departure schedule
(:func:`hcomc.corridor.schedule.departure_times`, the same vehicles SUMO gets); each
vehicle's class and automation are drawn from its origin's shares with the run's seed (as
SUMO draws a flow's vehicle type from its ``vTypeDistribution``: class share x CAV share or
1 - CAV share). A CAV drives the IDM with its class's CAV values.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hcomc.corridor import Corridor
from hcomc.corridor.schedule import departure_times
from hcomc.rng import make_rng
from hcomc.sim.corridor.layout import Layout

__all__ = ["IDM_COLUMNS", "CorridorFleet", "build_fleet"]

IDM_COLUMNS = ("desired_speed", "time_headway", "min_gap", "max_accel", "comfort_decel",
               "exponent")  # fmt: skip
"""Columns of :attr:`CorridorFleet.idm`, in order."""


class CorridorFleet(NamedTuple):
    """Per-vehicle arrays, vehicles in departure order (ids 0 … N-1)."""

    depart: np.ndarray  # wanted departure time [s]
    origin: np.ndarray  # index into ``origins``
    destination: np.ndarray  # index into ``destinations`` (0 = the mainline exit)
    vclass: np.ndarray  # index into ``classes``
    cav: np.ndarray  # bool
    idm: np.ndarray  # (N, 6): IDM_COLUMNS
    length: np.ndarray  # [m]
    max_speed: np.ndarray  # [m/s]
    start_code: np.ndarray  # ramp code j = 0 of an on-ramp origin, -1 for the mainline
    exit_code: np.ndarray  # code j = 0 of the destination off-ramp, -1 for the mainline exit
    queue_start: np.ndarray  # (n_origins + 1,): origin o's vehicles are queue[start[o]:start[o+1]]
    queue: np.ndarray  # vehicle ids grouped by origin, each group in departure order
    origins: tuple[str, ...]
    destinations: tuple[str, ...]
    classes: tuple[str, ...]


def build_fleet(c: Corridor, layout: Layout, seed: int, duration: float) -> CorridorFleet:
    """Every vehicle of corridor ``c``'s demand that departs before ``duration`` [s],
    classes drawn with ``seed``."""
    d = departure_times(c, duration)
    n = d.time.size
    classes = tuple(c.vehicles)
    rng = make_rng(seed)
    vclass = np.zeros(n, dtype=np.int64)
    cav = np.zeros(n, dtype=np.bool_)
    for o, origin in enumerate(d.origins):
        mine = np.flatnonzero(d.origin == o)
        demand = c.demand[origin]
        names = list(demand.classes)
        p = np.array([demand.classes[k] for k in names])
        vclass[mine] = [classes.index(names[k]) for k in rng.choice(len(names), mine.size, p=p)]
        cav[mine] = rng.random(mine.size) < demand.cav_share
    idm = np.zeros((n, len(IDM_COLUMNS)))
    for k, name in enumerate(classes):
        for flag in (False, True):
            rows = (vclass == k) & (cav == flag)
            params = c.vehicles[name].idm(flag)
            idm[rows] = [params[col] for col in IDM_COLUMNS]
    length = np.array([c.vehicles[name].length for name in classes])[vclass]
    max_speed = np.array([c.vehicles[name].max_speed for name in classes])[vclass]
    ramp_code = {r.id: layout.ramp_code(r.id, c) for r in c.road.ramps}
    start_code = np.array([ramp_code.get(o, -1) for o in d.origins], dtype=np.int64)[d.origin]
    exit_code = np.array([ramp_code.get(x, -1) for x in d.destinations], dtype=np.int64)
    order = np.argsort(d.origin, kind="stable")
    counts = np.bincount(d.origin, minlength=len(d.origins))
    return CorridorFleet(
        depart=d.time,
        origin=d.origin.astype(np.int64),
        destination=d.destination.astype(np.int64),
        vclass=vclass,
        cav=cav,
        idm=idm,
        length=length,
        max_speed=max_speed,
        start_code=start_code,
        exit_code=exit_code[d.destination],
        queue_start=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
        queue=order.astype(np.int64),
        origins=d.origins,
        destinations=d.destinations,
        classes=classes,
    )
