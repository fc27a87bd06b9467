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
* **A corridor** (:func:`corridor_strips`, a corridor run) is cut into the
  lane stretches of :func:`hcomc.corridor.layout.lane_stretches` (its sections, the
  description its SUMO export and the engine read, and its ramp roads sloping away
  from the mainline), the layout the browser replay draws too.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from itertools import pairwise

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.corridor import Corridor
from hcomc.corridor.layout import LaneStretch, StretchKind, lane_stretches, side_by_side
from hcomc.road import Lane

__all__ = ["Marking", "Strip", "StripKind", "corridor_strips", "paper_road_strips"]

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
    the lane number of a corridor run (k >= 0 mainline lane k from the right, ``-1 - j`` ramp lane
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
            kind: StretchKind = "main"
            if lane == Lane.RAMP:
                kind = "accel" if x0 >= r.accel_lane_start else "ramp"
            pieces.append(LaneStretch((int(lane),), x0, x1, y - half, y + half, kind, int(lane)))
    return _linked([p for p in pieces if p.x1 - p.x0 > _EPS])


def corridor_strips(corridor: Corridor) -> tuple[Strip, ...]:
    """The strips of a corridor's road (module docstring), upstream first, right to left;
    ramp roads after the mainline."""
    return _linked(list(lane_stretches(corridor.road)))


def _linked(pieces: list[LaneStretch]) -> tuple[Strip, ...]:
    """Number the pieces and link them: a lane's pieces in a row are predecessor and successor
    (a ramp road joins its acceleration lane and leaves its deceleration lane), pieces side by
    side over the same stretch sharing a bound are neighbours."""
    ids = {id(p): k + 1 for k, p in enumerate(pieces)}
    by_key: dict[tuple[object, ...], list[LaneStretch]] = {}
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
        left, right = side_by_side(p, pieces)
        shift = np.array(p.drop)
        xs = np.array([p.x0, p.x1])
        strips.append(Strip(
            id=sid, left=np.column_stack([xs, p.y_left + shift]),
            right=np.column_stack([xs, p.y_right + shift]), kind=StripKind(p.kind), lane=p.lane,
            ramp=p.ramp, left_marking=_marking(p, left),
            right_marking=_marking(p, right),
            predecessors=_some(before.get(sid)), successors=_some(after.get(sid)),
            left_neighbour=ids[id(left)] if left else 0,
            right_neighbour=ids[id(right)] if right else 0,
        ))  # fmt: skip
    return tuple(strips)


def _marking(p: LaneStretch, beside: LaneStretch | None) -> Marking:
    """The line between ``p`` and ``beside``: solid at the road's edge and between the paper
    road's ramp and lane 1, broad dashed along an acceleration or deceleration lane, dashed
    between mainline lanes."""
    if beside is None:
        return Marking.SOLID
    kinds = {p.kind, beside.kind}
    if "ramp" in kinds:
        return Marking.SOLID
    if kinds & {"accel", "decel"}:
        return Marking.BROAD_DASHED
    return Marking.DASHED


def _some(value: int | None) -> tuple[int, ...]:
    return () if value is None else (value,)
