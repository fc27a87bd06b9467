"""Which vehicles touch when: by CommonRoad's collision checker and by hcomc's Eq. 7 test.

A :class:`Contact` is a pair of vehicles (hcomc ids) whose bodies share a point at a time
step. :func:`commonroad_contacts` asks the CommonRoad drivability checker (``commonroad_dc``):
each dynamic obstacle becomes its time-variant collision object
(``create_collision_object``), and at every time step every pair of oriented boxes that may
reach each other is tested with the checker's ``collide``. :func:`log_contacts` applies hcomc's
own oriented-rectangle test (paper Eq. 7, :func:`hcomc.equations.collision.vehicles_collide`,
from the front bumper) to the rows of a log. :func:`onsets` keeps the contacts that begin at
their step, which is what hcomc counts as collisions (a COLLISION event when a pair's
contact begins).

Touching counts as a collision in Eq. 7; the two checkers may disagree on pairs within
rounding of touching (the file stores 6 decimals), which real runs do not come near.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from importlib import import_module
from typing import Any

import numpy as np
from commonroad.scenario.scenario import Scenario

from hcomc.commonroad.scenario import OBSTACLE_IDS
from hcomc.equations.collision import vehicles_collide
from hcomc.sim.log import SimulationLog

__all__ = ["Contact", "commonroad_contacts", "log_contacts", "onsets"]


@dataclass(frozen=True, order=True, slots=True)
class Contact:
    """Vehicles ``a < b`` (hcomc ids) touch at time step ``step``."""

    step: int
    a: int
    b: int


def commonroad_contacts(scenario: Scenario) -> tuple[Contact, ...]:
    """Every contact between the scenario's dynamic obstacles, by CommonRoad's checker."""
    create = _collision_objects()
    obstacles = {o.obstacle_id - OBSTACLE_IDS: o for o in scenario.dynamic_obstacles}
    objects = {vid: create(o) for vid, o in obstacles.items()}
    reach = {vid: _half_diagonal(o.obstacle_shape.length, o.obstacle_shape.width)
             for vid, o in obstacles.items()}  # fmt: skip
    if not objects:
        return ()
    first = min(o.time_start_idx() for o in objects.values())
    last = max(o.time_end_idx() for o in objects.values())
    found = []
    for step in range(first, last + 1):
        boxes = {vid: o.obstacle_at_time(step) for vid, o in objects.items()
                 if o.time_start_idx() <= step <= o.time_end_idx()}  # fmt: skip
        centre = {vid: float(obstacles[vid].state_at_time(step).position[0]) for vid in boxes}
        for a, b in _near_pairs(centre, reach):
            if boxes[a].collide(boxes[b]):
                found.append(Contact(step, min(a, b), max(a, b)))
    return tuple(sorted(found))


def log_contacts(log: SimulationLog) -> tuple[Contact, ...]:
    """Every contact between the vehicles of ``log`` by hcomc's Eq. 7 test (step = row)."""
    n = log.n_recorded
    active = np.asarray(log.active[:n])
    x, y, h = (np.asarray(getattr(log, name)[:n], dtype=np.float64)
               for name in ("x", "y", "heading"))  # fmt: skip
    length = np.asarray(log.length, dtype=np.float64)
    width = np.asarray(log.width, dtype=np.float64)
    reach = {i: _half_diagonal(length[i], width[i]) for i in range(log.n_vehicles)}
    found = []
    for row in range(n):
        ids = np.flatnonzero(active[row])
        # a rectangle's centre is half a length behind its front bumper
        centre = {int(i): float(x[row, i] - 0.5 * length[i] * math.cos(h[row, i])) for i in ids}
        pairs = np.array(list(_near_pairs(centre, reach)), dtype=np.int64).reshape(-1, 2)
        if pairs.size == 0:
            continue
        a, b = pairs[:, 0], pairs[:, 1]
        hit = vehicles_collide(x[row, a], y[row, a], h[row, a], length[a], width[a],
                               x[row, b], y[row, b], h[row, b], length[b], width[b])  # fmt: skip
        found += [Contact(row, int(min(i, j)), int(max(i, j)))
                  for i, j in pairs[np.asarray(hit, dtype=bool)]]  # fmt: skip
    return tuple(sorted(found))


def onsets(contacts: Iterable[Contact]) -> tuple[Contact, ...]:
    """The contacts whose pair was not in contact at the step before (collisions begun)."""
    touching = {(c.step, c.a, c.b) for c in contacts}
    return tuple(sorted(Contact(s, a, b) for s, a, b in touching if (s - 1, a, b) not in touching))


def _collision_objects() -> Any:
    """The drivability checker's ``create_collision_object``. Imported by name: the type
    stub commonroad_dc ships (``pycrcc.pyi``) does not parse, so mypy must not follow it."""
    module = "commonroad_dc.collision.collision_detection.pycrcc_collision_dispatch"
    return import_module(module).create_collision_object


def _half_diagonal(length: float, width: float) -> float:
    return 0.5 * math.hypot(length, width)


def _near_pairs(centre: dict[int, float], reach: dict[int, float]) -> Iterator[tuple[int, int]]:
    """Pairs of vehicles whose bounding circles overlap along x (a sweep over the centres'
    x, so that a long road costs pairs of neighbours only)."""
    order = sorted(centre, key=centre.__getitem__)
    widest = 2.0 * max((reach[v] for v in order), default=0.0)
    for k, a in enumerate(order):
        for b in order[k + 1 :]:
            if centre[b] - centre[a] > widest:
                break
            if centre[b] - centre[a] <= reach[a] + reach[b]:
                yield a, b
