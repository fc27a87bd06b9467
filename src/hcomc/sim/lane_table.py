"""The road as the compiled step reads it: a table of lanes, one column per lane code, and
the road's sections.

The step knows no road of its own. Whatever it needs to know of a lane it reads from this
table, by the lane's *code* (the integer in the state's ``lane``, ``origin`` and ``target``
columns and in the log): what kind of lane it is, the lanes to its left and right, where its
centre line lies, where it begins, from where its vehicles may leave it for the mainline,
where it ends, where the cooperative control zone of a ramp lane begins, where its vehicles
leave the road, and the speed limit of a ramp's own road. Along the mainline the road is cut
into *sections* of constant layout (:func:`hcomc.corridor.sections`): each has a number of
mainline lanes and a speed limit.

Codes number the ramp lanes first (the on-ramps, then the off-ramps, each by position and,
within a ramp, from the mainline outwards), then the mainline lanes from the right. Mainline
lane k is centred at ``y = k W`` and lane j of a ramp at ``-(j + 1) W``. The paper's road
(Section II-A, Fig. 1: two mainline lanes and one single-lane on-ramp) therefore has the
codes of :class:`hcomc.road.Lane`: the ramp and its acceleration lane 0, lane 1 code 1, lane
2 code 2, centred at ``(code - 1) W``. :mod:`hcomc.sim.roads` makes the table of the paper's
road and of a corridor's (:class:`hcomc.corridor.Road`: any number of mainline lanes, on-
and off-ramps, lane drops, speed zones). The module needs numpy only, so that the compiled
step may import it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

__all__ = [
    "ENDS_BLOCKED", "KIND_MAIN", "KIND_OFF", "KIND_ON", "L_BEGIN", "L_CENTRE", "L_END",
    "L_ENDS", "L_EXIT", "L_KIND", "L_LEFT", "L_OPENS", "L_RIGHT", "L_SPEED", "L_WIDTH", "L_ZONE",
    "MIN_CHANGE_LENGTHS", "LaneTable", "RampLanes", "lane_table",
]  # fmt: skip

KIND_MAIN, KIND_ON, KIND_OFF = 0, 1, 2
"""Kinds of lane: mainline, on-ramp (its road and acceleration lane), off-ramp (its
deceleration lane and road)."""

L_KIND, L_LEFT, L_RIGHT, L_ENDS = range(4)
"""Rows of :attr:`LaneTable.ints`: the kind, the code of the lane to the left and to the
right (-1: none), and whether the lane ends somewhere along the road (1: an acceleration
lane, a mainline lane that a section drops; :data:`ENDS_BLOCKED`: an acceleration lane that
a stalled vehicle ends; 0: its vehicles never have to leave it, so the step need not look
for its end). Mainline lane 0 has no lane to its right: a ramp's lanes join it over a
stretch only, and nobody changes into them of their own accord."""

MIN_CHANGE_LENGTHS = 3.0
"""A lane change takes at least this many of the vehicle's lengths of road: the engine
starts one as ``x_f = x_0 + max(v T_lc, 3 L)`` (Eq. 4-6 need room along x to move sideways,
even from a standstill)."""

ENDS_BLOCKED = 2
"""``L_ENDS`` of an acceleration lane that ends before a stalled vehicle
(:mod:`hcomc.sim.stalled`): every vehicle whose centre is in it stops at its end, a merge
plan under way or not, and so does a changer whose change would not be over
``MIN_CHANGE_LENGTHS`` of its lengths past it, since beyond it stands a vehicle."""
L_CENTRE, L_WIDTH, L_BEGIN, L_OPENS, L_END, L_ZONE, L_EXIT, L_SPEED = range(8)
"""Rows of :attr:`LaneTable.floats`, in this order:

- the centre line's y [m];
- the lane's width [m];
- where the lane begins [m]: a ramp road's start, a deceleration lane's; -inf on the
  mainline, whose lanes the sections give;
- from where a vehicle may leave the lane for the one to its left [m]: an acceleration
  lane's start; -inf elsewhere;
- where a vehicle must have left it [m]: an acceleration lane's end; where an off-ramp's
  deceleration lane ends, for the vehicles that want to take it; inf on the mainline, whose
  lane ends the sections give;
- where a ramp lane's cooperative control zone begins [m] (inf: none);
- where a vehicle in the lane leaves the road, its rear past it [m]: the mainline's end, an
  off-ramp road's end; inf on an on-ramp;
- the speed limit of a ramp's road, before an acceleration lane and after a deceleration
  lane [m/s] (inf: none)."""


class LaneTable(NamedTuple):
    """A road's lanes by code and its sections (module docstring). Arrays only, so that the
    compiled state holds them as they are.

    Attributes
    ----------
    ints : (4, L) rows ``L_KIND``, ``L_LEFT``, ``L_RIGHT``, ``L_ENDS``.
    floats : (8, L) rows ``L_CENTRE`` ... ``L_SPEED``.
    sec_x0 : (S,) where each section begins [m] (the first at 0).
    sec_speed : (S,) its speed limit [m/s] (inf: none).
    main_end : (M, S) where mainline lane k ends at or after section s [m] (inf: never);
        lane k exists in section s when ``main_end[k, s] > sec_x0[s]``.
    """

    ints: np.ndarray
    floats: np.ndarray
    sec_x0: np.ndarray
    sec_speed: np.ndarray
    main_end: np.ndarray

    @property
    def n_lanes(self) -> int:
        """Number of lane codes."""
        return int(self.ints.shape[1])

    @property
    def n_main(self) -> int:
        """M, the largest number of mainline lanes; their codes are the last M."""
        return int(self.main_end.shape[0])

    def codes_of_kind(self, kind: int) -> np.ndarray:
        """The codes of the lanes of ``kind`` (``KIND_*``), ascending."""
        return np.flatnonzero(self.ints[L_KIND] == kind)


@dataclass(frozen=True, slots=True)
class RampLanes:
    """A ramp as the lane table needs it: ``kind`` (``KIND_ON``, ``KIND_OFF``), its lanes
    and the rows ``L_BEGIN`` ... ``L_SPEED`` they share [m, m/s] (see the module
    docstring)."""

    kind: int
    lanes: int
    begin: float
    opens: float
    end: float
    zone: float
    exit: float
    speed: float


def lane_table(
    width: float, length: float, sections: Sequence[tuple[float, int, float]],
    ramps: Sequence[RampLanes],
) -> LaneTable:  # fmt: skip
    """The table of a road with lanes ``width`` [m] wide (module docstring): mainline
    ``sections`` ``(start [m], lanes, speed limit [m/s])`` in order from x = 0 to ``length``
    [m], where the mainline's vehicles leave the road, and ``ramps`` in code order."""
    sec_x0 = np.array([x0 for x0, _, _ in sections], dtype=np.float64)
    sec_lanes = np.array([lanes for _, lanes, _ in sections], dtype=np.int64)
    n_main = int(sec_lanes.max())
    n_ramp = sum(r.lanes for r in ramps)
    n = n_ramp + n_main
    ints = np.full((4, n), -1, dtype=np.int64)
    floats = np.empty((8, n))
    code = 0
    for ramp in ramps:
        for j in range(ramp.lanes):
            ints[:, code] = ramp.kind, n_ramp if j == 0 else code - 1, -1, ramp.kind == KIND_ON
            if j + 1 < ramp.lanes:
                ints[L_RIGHT, code] = code + 1
            floats[:, code] = (-(j + 1) * width, width, ramp.begin, ramp.opens, ramp.end,
                               ramp.zone, ramp.exit, ramp.speed)  # fmt: skip
            code += 1
    for k in range(n_main):
        code = n_ramp + k
        ints[:3, code] = KIND_MAIN, code + 1 if k + 1 < n_main else -1, code - 1 if k else -1
        floats[:, code] = (k * width, width, -math.inf, -math.inf, math.inf, math.inf, length,
                           math.inf)  # fmt: skip
    main_end = np.full((n_main, sec_x0.size), math.inf)
    for k in range(n_main):
        end = math.inf
        for s in range(sec_x0.size - 1, -1, -1):  # from downstream: the next section without k
            if sec_lanes[s] <= k:
                end = float(sec_x0[s])
            main_end[k, s] = end
        ints[L_ENDS, n_ramp + k] = bool(np.isfinite(main_end[k]).any())
    speed = np.array([limit for _, _, limit in sections], dtype=np.float64)
    return LaneTable(ints, floats, sec_x0, speed, main_end)
