"""A corridor's road in the plane: where each lane lies, and where a vehicle on it is drawn.

A corridor (:mod:`hcomc.corridor.road`) and its engine know positions along the mainline
(``x``) and lanes, not a plane. The views of a run that need one (the CommonRoad export,
:mod:`hcomc.commonroad`, and the browser replay, :mod:`hcomc.viz.replay`) take it from this
module, so that they draw the same road and put a vehicle at the same place:

* The mainline runs along +x with its right border on ``y = 0``, so mainline lane k (0 =
  rightmost) is centred at ``(k + 1/2) W`` and ramp lane j (0 next to the mainline) at
  ``-(j + 1/2) W``, as in the SUMO export (:mod:`hcomc.sumo.corridor_network`).
* :func:`lane_stretches` cuts the road into lane stretches (:class:`LaneStretch`): one lane
  over one section of :func:`hcomc.corridor.sections` (mainline, acceleration and
  deceleration lanes), and each lane of each ramp road. An on-ramp road ends at the ramp's
  ``x`` and an off-ramp road starts at the end of its deceleration lane; both run at the
  slope :data:`RAMP_SLOPE` away from the mainline over their ``ramp_length`` along the
  centre line (the SUMO export has the same slope, but starts its ramp edges at ``x -
  ramp_length`` with a short straight at the junction, so its ramp nodes lie a few metres
  from these ends), so that the ramps of neighbouring junctions lie
  apart (an off-ramp road that reaches past the start of the next on-ramp's road crosses
  it, as a flyover would).
* Lane codes are the engine's numbering of the lanes (its lane table,
  :func:`hcomc.sim.roads.road_lanes`): the ramps' lanes first, in the order of
  :attr:`hcomc.corridor.Road.ramps` (lane j of a ramp is its first code plus j,
  :func:`ramp_codes`), then mainline lane k as code ``R + k``, with R the number of ramp
  lanes (:func:`ramp_lane_count`); :func:`lane_numbers` turns codes into the lane numbers
  of the trajectories (k >= 0 mainline lane k, ``-1 - j`` ramp lane j).
  :func:`code_poses` places a sample ``(x, code)`` on its lane's centre line; the engine
  continues ``x`` along ramp roads, so a sample ``d`` metres upstream of an on-ramp's
  junction lies ``d`` metres along the slanted road (downstream for an off-ramp).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from hcomc.corridor.road import OffRamp, OnRamp, Road, sections

__all__ = [
    "RAMP_SLOPE",
    "LaneStretch",
    "StretchKind",
    "code_poses",
    "lane_numbers",
    "lane_stretches",
    "main_lane_count",
    "ramp_codes",
    "ramp_lane_count",
    "ramp_road_pose",
    "ramp_road_span",
    "side_by_side",
]

RAMP_SLOPE = 0.1
"""Lateral offset per metre along the mainline of a corridor's ramp road [-] (as exported to
SUMO, :mod:`hcomc.sumo.corridor_network`)."""

StretchKind = Literal["main", "ramp", "accel", "decel", "exit"]
"""What a stretch is: mainline, on-ramp road, acceleration lane, deceleration lane or
off-ramp road."""

_EPS = 1e-6  # [m] positions closer than this are the same point


@dataclass(frozen=True, slots=True)
class LaneStretch:
    """One lane over one stretch ``[x0, x1]`` along the mainline [m].

    ``key`` names the lane (the same on every stretch of it: ``("main", k)`` or ``("ramp",
    id, j)``); ``y_right`` and ``y_left`` are its bounds [m] where the stretch meets the
    mainline, and ``drop`` the lateral shift of its upstream and downstream ends [m]
    (non-zero on a sloping ramp road only). ``lane`` is the lane's number: on a corridor a
    corridor run's (k >= 0 mainline lane k, ``-1 - j`` lane j of ramp ``ramp``), on the
    paper's road (:mod:`hcomc.commonroad.lanes`) a :class:`hcomc.road.Lane`."""

    key: tuple[object, ...]
    x0: float
    x1: float
    y_right: float
    y_left: float
    kind: StretchKind
    lane: int
    ramp: str | None = None
    drop: tuple[float, float] = (0.0, 0.0)

    @property
    def centre(self) -> float:
        """Centre line y where the stretch meets the mainline (before ``drop``) [m]."""
        return 0.5 * (self.y_right + self.y_left)


def lane_stretches(road: Road) -> tuple[LaneStretch, ...]:
    """The stretches of ``road`` (module docstring): per section upstream first, its
    mainline lanes right to left, then its ramp lanes; the ramp roads last."""
    width = road.lane_width
    out = []
    for s in sections(road):
        for k in range(s.lanes):
            out.append(LaneStretch(("main", k), s.x0, s.x1, k * width, (k + 1) * width,
                                   "main", k))  # fmt: skip
        kind: StretchKind = "accel" if s.kind == "accel" else "decel"
        for j in range(s.ramp_lanes):
            out.append(LaneStretch(("ramp", s.ramp, j), s.x0, s.x1, -(j + 1) * width,
                                   -j * width, kind, -1 - j, s.ramp))  # fmt: skip
    for ramp in road.ramps:
        road_kind: StretchKind = "ramp" if isinstance(ramp, OnRamp) else "exit"
        x0, x1 = ramp_road_span(ramp)
        drop = -ramp.ramp_length * math.sin(math.atan(RAMP_SLOPE))
        ends = (drop, 0.0) if isinstance(ramp, OnRamp) else (0.0, drop)
        for j in range(ramp.lanes):
            out.append(LaneStretch(("ramp", ramp.id, j), x0, x1, -(j + 1) * width, -j * width,
                                   road_kind, -1 - j, ramp.id, ends))  # fmt: skip
    return tuple(out)


def side_by_side(
    p: LaneStretch, stretches: Iterable[LaneStretch]
) -> tuple[LaneStretch | None, LaneStretch | None]:
    """The stretches to the left and right of ``p`` over the same stretch of road (sharing a
    bound with it), None where there is none."""
    left = right = None
    for q in stretches:
        same = abs(q.x0 - p.x0) < _EPS and abs(q.x1 - p.x1) < _EPS and q.drop == p.drop
        if q is p or not same:
            continue
        if abs(q.y_right - p.y_left) < _EPS:
            left = q
        elif abs(q.y_left - p.y_right) < _EPS:
            right = q
    return left, right


def ramp_road_span(ramp: OnRamp | OffRamp) -> tuple[float, float]:
    """The ramp road's extent along x [m] (its slant shortens it by cos(atan(slope)))."""
    run = ramp.ramp_length * math.cos(math.atan(RAMP_SLOPE))
    if isinstance(ramp, OnRamp):
        return ramp.x - run, ramp.x
    return ramp.end, ramp.end + run


def ramp_road_pose(ramp: OnRamp | OffRamp, distance: np.ndarray) -> tuple[np.ndarray, ...]:
    """Where a point ``distance`` [m] along a ramp road, measured from its junction with the
    mainline (upstream for an on-ramp, downstream for an off-ramp), lies relative to the
    junction: ``(dx, dy, heading)`` [m, m, rad], the heading of a vehicle driving on it."""
    angle = math.atan(RAMP_SLOPE)
    d = np.asarray(distance, dtype=np.float64)
    sign = -1.0 if isinstance(ramp, OnRamp) else 1.0
    heading = np.full(d.shape, angle if isinstance(ramp, OnRamp) else -angle)
    return sign * d * math.cos(angle), -d * math.sin(angle), heading


def main_lane_count(road: Road) -> int:
    """M, the largest mainline lane count."""
    return max(s.lanes for s in sections(road))


def ramp_lane_count(road: Road) -> int:
    """R, the number of ramp lanes: the code of mainline lane 0."""
    return sum(ramp.lanes for ramp in road.ramps)


def ramp_codes(road: Road) -> dict[str, int]:
    """The code of lane j = 0 of each ramp (lane j is that plus j), by ramp id."""
    out, code = {}, 0
    for ramp in road.ramps:
        out[ramp.id] = code
        code += ramp.lanes
    return out


def lane_numbers(road: Road) -> np.ndarray:
    """Per lane code, the lane's number: k for mainline lane k, ``-1 - j`` for lane j of a
    ramp (module docstring)."""
    first = ramp_lane_count(road)
    out = np.arange(first + main_lane_count(road), dtype=np.int64) - first
    starts = ramp_codes(road)
    for ramp in road.ramps:
        out[starts[ramp.id] : starts[ramp.id] + ramp.lanes] = -1 - np.arange(ramp.lanes)
    return out


def code_poses(road: Road, x: np.ndarray, code: np.ndarray) -> tuple[np.ndarray, ...]:
    """Front bumper centre ``(px, py)`` [m] and heading [rad] of samples at mainline position
    ``x`` [m] in lane ``code``: the lane's centre line, on a ramp road ``|x - junction|``
    along it (module docstring)."""
    x = np.asarray(x, dtype=np.float64)
    code = np.asarray(code, dtype=np.int64)
    width, first = road.lane_width, ramp_lane_count(road)
    starts = ramp_codes(road)
    owner = {starts[r.id] + j: (r, j) for r in road.ramps for j in range(r.lanes)}
    px, py, heading = x.copy(), np.zeros(x.size), np.zeros(x.size)
    main = code >= first
    py[main] = (code[main] - first + 0.5) * width
    for index in np.unique(code[~main]).tolist():
        ramp, j = owner[index]
        on = code == index
        py[on] = -(j + 0.5) * width
        junction = ramp.x if isinstance(ramp, OnRamp) else ramp.end
        away = x[on] < junction if isinstance(ramp, OnRamp) else x[on] > junction
        if not away.any():
            continue
        where = np.flatnonzero(on)[away]
        dx, dy, h = ramp_road_pose(ramp, np.abs(x[where] - junction))
        px[where], py[where], heading[where] = junction + dx, py[where] + dy, h
    return px, py, heading
