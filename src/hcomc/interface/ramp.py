"""The on-ramp a merge decision is for, as the controller sees it.

A controller plans for one ramp vehicle at one on-ramp; what it needs of the road is that
ramp's local geometry and the lanes beside it, not a whole scenario. :class:`Ramp` carries
them in the coordinates of the view it comes with (``TrafficView.ramp``): along the view's
x axis [m] the start of the cooperative control zone and the acceleration lane's start and
end, the lane width [m], and the codes, in ``TrafficView.lane``, of the ramp's own lane, the
mainline lane its vehicles merge into (lane 1 of Section II-A) and the lane beyond that
(lane 2). The paper's road is one such ramp (:meth:`Ramp.of`); a corridor hands each ramp's
controller its own. Every built-in controller reads the road from here only, so it runs
unchanged at one ramp or at every ramp of a corridor.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from hcomc.road import Lane

if TYPE_CHECKING:
    from hcomc.config import RoadParams

__all__ = ["Ramp", "ramp_in"]


@dataclass(frozen=True, slots=True)
class Ramp:
    """One on-ramp in a view's coordinates (module docstring).

    Attributes
    ----------
    control_zone_start : where the cooperative control zone begins [m] (a ramp vehicle is
        decided for from there on).
    accel_lane_start, accel_lane_end : the acceleration lane, along the mainline [m].
    lane_width : [m].
    lane, target, beyond : lane codes of the ramp's lane, the mainline lane it merges into
        and the lane beyond that (-1: none).
    """

    control_zone_start: float
    accel_lane_start: float
    accel_lane_end: float
    lane_width: float
    lane: int = int(Lane.RAMP)
    target: int = int(Lane.MAIN_1)
    beyond: int = int(Lane.MAIN_2)

    @classmethod
    def of(cls, road: RoadParams) -> Ramp:
        """The paper's road (Section II-A, a scenario's ``[road]`` table) as a ramp."""
        return cls(
            control_zone_start=float(road.control_zone_start),
            accel_lane_start=float(road.accel_lane_start),
            accel_lane_end=float(road.accel_lane_end),
            lane_width=float(road.lane_width),
        )


def ramp_in(ramps: Sequence[Ramp], lane: int) -> Ramp:
    """The ramp of ``ramps`` whose own lane is ``lane``; the first when none is (a vehicle
    that has left its ramp lane, or none given). A ValueError on a road without on-ramps."""
    if not ramps:
        raise ValueError("the road has no on-ramp: a merge decision is made at one")
    return next((r for r in ramps if r.lane == lane), ramps[0])
