"""The road as the compiled step reads it: a table of lanes, one column per lane code.

The step knows no road of its own. Whatever it needs to know of a lane it reads from this
table, by the lane's *code* (the integer in the state's ``lane``, ``origin`` and ``target``
columns and in the log): what kind of lane it is, the lanes to its left and right, where its
centre line lies, from where its vehicles may leave it for the mainline, where it ends, and
where the cooperative control zone of a ramp lane begins.

Codes number the ramp lanes first, in the order of the ramps and, within a ramp, from the
mainline outwards, then the mainline lanes from the right. The paper's road (Section II-A,
Fig. 1: two mainline lanes and one single-lane on-ramp, :func:`paper_lanes`) therefore has
the codes of :class:`hcomc.road.Lane`: the ramp and its acceleration lane 0, lane 1 code 1,
lane 2 code 2; its lane centres lie at ``(code - 1) W``, lane 1's on y = 0.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from hcomc.config import RoadParams

__all__ = [
    "KIND_MAIN", "KIND_OFF", "KIND_ON", "L_CENTRE", "L_END", "L_KIND", "L_LEFT", "L_OPENS",
    "L_RIGHT", "L_ZONE", "LaneTable", "OnRampLanes", "lane_table", "paper_lanes",
]  # fmt: skip

KIND_MAIN, KIND_ON, KIND_OFF = 0, 1, 2
"""Kinds of lane: mainline, on-ramp (its road and acceleration lane), off-ramp."""

L_KIND, L_LEFT, L_RIGHT = range(3)
"""Rows of :attr:`LaneTable.ints`: the kind, the code of the lane to the left and to the
right (-1: none a vehicle may change to)."""
L_CENTRE, L_OPENS, L_END, L_ZONE = range(4)
"""Rows of :attr:`LaneTable.floats` [m]: the centre line's y; the x from which a vehicle may
leave the lane for the one to its left (an acceleration lane's start; -inf on the
mainline); the x where the lane ends (an acceleration lane's end; inf on the mainline);
the x where the cooperative control zone of a ramp lane begins (inf: none)."""


class LaneTable(NamedTuple):
    """A road's lanes by code (module docstring): ``ints`` (3, L) with rows ``L_KIND``,
    ``L_LEFT``, ``L_RIGHT``; ``floats`` (4, L) with rows ``L_CENTRE``, ``L_OPENS``, ``L_END``,
    ``L_ZONE``. Arrays only, so that the compiled state holds them as they are."""

    ints: np.ndarray
    floats: np.ndarray

    @property
    def n_lanes(self) -> int:
        """Number of lane codes."""
        return int(self.ints.shape[1])

    def codes_of_kind(self, kind: int) -> np.ndarray:
        """The codes of the lanes of ``kind`` (``KIND_*``), ascending."""
        return np.flatnonzero(self.ints[L_KIND] == kind)


@dataclass(frozen=True, slots=True)
class OnRampLanes:
    """An on-ramp as the lane table needs it [m]: its acceleration lane ``[start, end]``
    along the mainline, where its control zone begins, and its number of lanes."""

    start: float
    end: float
    zone: float
    lanes: int = 1


def lane_table(main_lanes: int, lane_width: float, on_ramps: Sequence[OnRampLanes]) -> LaneTable:
    """The table of a road with ``main_lanes`` mainline lanes of ``lane_width`` [m] and the
    given on-ramps (codes as in the module docstring). Mainline lane k is centred at
    ``k W``, lane j of a ramp at ``-(j + 1) W``; a ramp's lane j = 0 has mainline lane 0 to
    its left, lane j = 1 has lane j = 0."""
    if main_lanes < 1:
        raise ValueError(f"main_lanes = {main_lanes}: allowed: 1 or more")
    n_ramp = sum(r.lanes for r in on_ramps)
    n = n_ramp + main_lanes
    ints = np.full((3, n), -1, dtype=np.int64)
    floats = np.empty((4, n))
    first_main = n_ramp
    code = 0
    for ramp in on_ramps:
        for j in range(ramp.lanes):
            ints[L_KIND, code] = KIND_ON
            ints[L_LEFT, code] = first_main if j == 0 else code - 1
            ints[L_RIGHT, code] = code + 1 if j + 1 < ramp.lanes else -1
            floats[:, code] = -(j + 1) * lane_width, ramp.start, ramp.end, ramp.zone
            code += 1
    for k in range(main_lanes):
        code = first_main + k
        ints[L_KIND, code] = KIND_MAIN
        ints[L_LEFT, code] = code + 1 if k + 1 < main_lanes else -1
        ints[L_RIGHT, code] = code - 1 if k > 0 else -1
        floats[:, code] = k * lane_width, -math.inf, math.inf, math.inf
    return LaneTable(ints, floats)


def paper_lanes(road: RoadParams) -> LaneTable:
    """The paper's road (Section II-A, a scenario's ``[road]`` table): two mainline lanes
    and one single-lane on-ramp whose acceleration lane runs from ``accel_lane_start`` to
    ``accel_lane_end``, its control zone from ``control_zone_start``."""
    ramp = OnRampLanes(road.accel_lane_start, road.accel_lane_end, road.control_zone_start)
    return lane_table(2, road.lane_width, [ramp])
