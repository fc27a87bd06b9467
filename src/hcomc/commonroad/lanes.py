"""The road of a run as lane strips: the lanelets of a CommonRoad scenario, in plain numpy.

A :class:`Strip` is one lanelet: a straight (or, for a corridor's ramp road, slanted) stretch
of one lane with its left and right bounds in driving direction, its kind, the lanes it
continues from and into, and its neighbours. The road is cut wherever a lane begins or ends,
so that neighbouring strips share a bound over their whole length, as CommonRoad's adjacency
requires.

* **The paper's road** (:func:`paper_road_strips`, every run of hcomc's scenario engine,
  conditions and corridors of the paper's layout alike) is cut, as its SUMO network is
  (:mod:`hcomc.sumo.network`), at ``ramp_start``, ``accel_lane_start`` and
  ``accel_lane_end``. Lane centres lie at ``y = (lane - 1) W`` (:func:`hcomc.road.lane_centre`):
  the ramp runs parallel to lane 1 from ``ramp_start`` (a solid line: no change) and becomes
  the acceleration lane (a broad dashed line: merging allowed), which ends at
  ``accel_lane_end``.
* **A corridor** (:func:`corridor_strips`, a run of the corridor engine) is cut at its
  sections (:func:`hcomc.corridor.sections`), the description its SUMO export and the
  corridor engine read. The mainline's right border lies on ``y = 0``, so mainline lane k
  (0 = rightmost) is centred at ``(k + 1/2) W`` and ramp lane j at ``-(j + 1/2) W``, as in
  :mod:`hcomc.sumo.corridor_network`. An on-ramp road ends at ``x`` and an off-ramp road
  starts at the end of its deceleration lane; both run at the slope :data:`RAMP_SLOPE` away
  from the mainline (the SUMO export's), over their ``ramp_length`` along the centre line,
  so that ramps of neighbouring junctions never overlap.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from enum import Enum
from itertools import pairwise

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.corridor import Corridor, OffRamp, OnRamp, sections
from hcomc.road import Lane

__all__ = [
    "RAMP_SLOPE",
    "Marking",
    "Strip",
    "StripKind",
    "corridor_strips",
    "paper_road_strips",
    "ramp_road_pose",
]

RAMP_SLOPE = 0.1
"""Lateral offset per metre along the mainline of a corridor's ramp road [-] (as exported to
SUMO, :mod:`hcomc.sumo.corridor_network`)."""

_EPS = 1e-6  # [m] stretches shorter than this are left out


class StripKind(Enum):
    """What a strip is: mainline, ramp road, acceleration, deceleration or exit-ramp road."""

    MAIN = "main"
    RAMP = "ramp"
    ACCEL = "accel"
    DECEL = "decel"
    EXIT = "exit"


class Marking(Enum):
    """Line marking of a bound (CommonRoad's names)."""

    SOLID = "solid"
    DASHED = "dashed"
    BROAD_DASHED = "broad_dashed"


@dataclass(frozen=True, slots=True)
class Strip:
    """One lanelet: bounds (n, 2) [m] in driving direction, kind, hcomc lane and links.

    ``lane`` is the hcomc lane: a :class:`hcomc.road.Lane` on the paper's road; on a corridor
    the corridor engine's lane (k >= 0 mainline lane k from the right, ``-1 - j`` ramp lane
    j), with ``ramp`` the ramp's id. Links are strip ids; 0 means none."""

    id: int
    left: np.ndarray
    right: np.ndarray
    kind: StripKind
    lane: int
    ramp: str | None
    left_marking: Marking
    right_marking: Marking
    predecessors: tuple[int, ...] = ()
    successors: tuple[int, ...] = ()
    left_neighbour: int = 0
    right_neighbour: int = 0

    @property
    def centre(self) -> np.ndarray:
        """Centre line (n, 2) [m]."""
        return 0.5 * (self.left + self.right)

    @property
    def x0(self) -> float:
        """Upstream end along the mainline [m]."""
        return float(self.centre[0, 0])

    @property
    def x1(self) -> float:
        """Downstream end along the mainline [m]."""
        return float(self.centre[-1, 0])


@dataclass(frozen=True, slots=True)
class _Cut:
    """A lane over one stretch [x0, x1] before ids and links: its identity ``key`` (the same
    along the lane), lateral bounds and kind."""

    key: tuple[object, ...]
    x0: float
    x1: float
    y_right: float
    y_left: float
    kind: StripKind
    lane: int
    ramp: str | None = None
    drop: tuple[float, float] = (0.0, 0.0)  # lateral shift of the two ends [m] (a ramp road)


def paper_road_strips(config: ScenarioConfig) -> tuple[Strip, ...]:
    """The strips of the paper's road (module docstring), upstream first, right to left."""
    r = config.road
    half = 0.5 * r.lane_width
    cuts = [0.0, r.ramp_start, r.accel_lane_start, r.accel_lane_end, r.length]
    pieces = []
    for x0, x1 in pairwise(cuts):
        lanes = [Lane.MAIN_1, Lane.MAIN_2]
        if r.ramp_start <= x0 < r.accel_lane_end:
            lanes.insert(0, Lane.RAMP)
        for lane in lanes:
            y = (int(lane) - 1) * r.lane_width
            kind = StripKind.MAIN
            if lane == Lane.RAMP:
                kind = StripKind.ACCEL if x0 >= r.accel_lane_start else StripKind.RAMP
            pieces.append(_Cut((int(lane),), x0, x1, y - half, y + half, kind, int(lane)))
    return _linked([p for p in pieces if p.x1 - p.x0 > _EPS])


def corridor_strips(corridor: Corridor) -> tuple[Strip, ...]:
    """The strips of a corridor's road (module docstring), upstream first, right to left;
    ramp roads after the mainline."""
    road, width = corridor.road, corridor.road.lane_width
    pieces = []
    for s in sections(road):
        for k in range(s.lanes):
            pieces.append(_Cut(("main", k), s.x0, s.x1, k * width, (k + 1) * width,
                               StripKind.MAIN, k))  # fmt: skip
        kind = StripKind.ACCEL if s.kind == "accel" else StripKind.DECEL
        for j in range(s.ramp_lanes):
            pieces.append(_Cut(("ramp", s.ramp, j), s.x0, s.x1, -(j + 1) * width, -j * width,
                               kind, -1 - j, s.ramp))  # fmt: skip
    for ramp in road.ramps:
        road_kind = StripKind.RAMP if isinstance(ramp, OnRamp) else StripKind.EXIT
        x0, x1 = _ramp_road_span(ramp)
        for j in range(ramp.lanes):
            pieces.append(_Cut(("ramp", ramp.id, j), x0, x1, -(j + 1) * width, -j * width,
                               road_kind, -1 - j, ramp.id, _drop(ramp)))  # fmt: skip
    return _linked(pieces)


def ramp_road_pose(ramp: OnRamp | OffRamp, distance: np.ndarray) -> tuple[np.ndarray, ...]:
    """Where a point ``distance`` [m] along a corridor's ramp road, measured from its junction
    with the mainline (upstream for an on-ramp, downstream for an off-ramp), lies relative to
    the junction: ``(dx, dy, heading)`` [m, m, rad] of the ramp's slope (heading of a vehicle
    driving on it)."""
    angle = math.atan(RAMP_SLOPE)
    d = np.asarray(distance, dtype=np.float64)
    sign = -1.0 if isinstance(ramp, OnRamp) else 1.0
    heading = np.full(d.shape, angle if isinstance(ramp, OnRamp) else -angle)
    return sign * d * math.cos(angle), -d * math.sin(angle), heading


def _ramp_road_span(ramp: OnRamp | OffRamp) -> tuple[float, float]:
    """The ramp road's extent along x [m] (its slant shortens it by cos(atan(slope)))."""
    run = ramp.ramp_length * math.cos(math.atan(RAMP_SLOPE))
    if isinstance(ramp, OnRamp):
        return ramp.x - run, ramp.x
    return ramp.end, ramp.end + run


def _drop(ramp: OnRamp | OffRamp) -> tuple[float, float]:
    """Lateral shift [m] of a ramp road's upstream and downstream ends (the junction: 0)."""
    drop = -ramp.ramp_length * math.sin(math.atan(RAMP_SLOPE))
    return (drop, 0.0) if isinstance(ramp, OnRamp) else (0.0, drop)


def _linked(pieces: list[_Cut]) -> tuple[Strip, ...]:
    """Number the pieces and link them: a lane's pieces in a row are predecessor and successor
    (a ramp road joins its acceleration lane and leaves its deceleration lane), pieces side by
    side over the same stretch sharing a bound are neighbours."""
    ids = {id(p): k + 1 for k, p in enumerate(pieces)}
    by_key: dict[tuple[object, ...], list[_Cut]] = {}
    for p in sorted(pieces, key=lambda p: p.x0):
        by_key.setdefault(p.key, []).append(p)
    after: dict[int, int] = {}
    for row in by_key.values():
        for up, down in pairwise(row):
            if abs(up.x1 - down.x0) < _EPS:
                after[ids[id(up)]] = ids[id(down)]
    before = {down: up for up, down in after.items()}
    strips = []
    for p in pieces:
        sid = ids[id(p)]
        left, right = _side_by_side(p, pieces)
        shift = np.array(p.drop)
        xs = np.array([p.x0, p.x1])
        strips.append(Strip(
            id=sid, left=np.column_stack([xs, p.y_left + shift]),
            right=np.column_stack([xs, p.y_right + shift]), kind=p.kind, lane=p.lane,
            ramp=p.ramp, left_marking=_marking(p, left),
            right_marking=_marking(p, right),
            predecessors=_some(before.get(sid)), successors=_some(after.get(sid)),
            left_neighbour=ids[id(left)] if left else 0,
            right_neighbour=ids[id(right)] if right else 0,
        ))  # fmt: skip
    return tuple(strips)


def _side_by_side(p: _Cut, pieces: Iterable[_Cut]) -> tuple[_Cut | None, _Cut | None]:
    """The pieces to the left and right of ``p`` over the same stretch (sharing a bound)."""
    left = right = None
    for q in pieces:
        same = abs(q.x0 - p.x0) < _EPS and abs(q.x1 - p.x1) < _EPS and q.drop == p.drop
        if q is p or not same:
            continue
        if abs(q.y_right - p.y_left) < _EPS:
            left = q
        elif abs(q.y_left - p.y_right) < _EPS:
            right = q
    return left, right


def _marking(p: _Cut, beside: _Cut | None) -> Marking:
    """The line between ``p`` and ``beside``: solid at the road's edge and between the paper
    road's ramp and lane 1, broad dashed along an acceleration or deceleration lane, dashed
    between mainline lanes."""
    if beside is None:
        return Marking.SOLID
    kinds = {p.kind, beside.kind}
    if StripKind.RAMP in kinds:
        return Marking.SOLID
    if kinds & {StripKind.ACCEL, StripKind.DECEL}:
        return Marking.BROAD_DASHED
    return Marking.DASHED


def _some(value: int | None) -> tuple[int, ...]:
    return () if value is None else (value,)
