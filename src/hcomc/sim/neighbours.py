"""Vectorised leader/follower search per lane (sort by position, no pairwise loops).

A snapshot's *entries* are (vehicle, lane) pairs: every active vehicle in the lane it is
driving in and, while it changes lane, also in its target lane (as in SUMO's sublane model),
so followers in both lanes see it during the manoeuvre. Entries are sorted by
``lane * OFFSET + x``; a vehicle's leader in a lane is the next entry of the same lane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._typing import FloatArray, IntArray

OFFSET = 1.0e7
"""Key offset between lanes [m]; larger than any road length."""


@dataclass(frozen=True, slots=True)
class LaneIndex:
    """Entries of one snapshot sorted by (lane, x).

    Attributes
    ----------
    vehicle : vehicle index of each sorted entry.
    lane : lane of each sorted entry.
    key : ``lane * OFFSET + x`` of each sorted entry (ascending).
    rank : position in the sorted order of each entry as given to :func:`build_lane_index`.
    """

    vehicle: IntArray
    lane: IntArray
    key: FloatArray
    rank: IntArray

    def leader_of(self, entries: IntArray) -> IntArray:
        """Vehicle ahead of each given (unsorted) entry in the same lane, -1 if none."""
        pos = self.rank[entries]
        return self._neighbour(pos + 1, self.lane[pos])

    def follower_of(self, entries: IntArray) -> IntArray:
        """Vehicle behind each given (unsorted) entry in the same lane, -1 if none."""
        pos = self.rank[entries]
        return self._neighbour(pos - 1, self.lane[pos])

    def _neighbour(self, pos: IntArray, lane: IntArray) -> IntArray:
        """Vehicle of sorted entry ``pos`` if it exists and lies in ``lane``, else -1."""
        if self.vehicle.size == 0:
            return np.full(np.shape(pos), -1, dtype=np.int64)
        safe = np.minimum(np.maximum(pos, 0), self.vehicle.size - 1)  # np.clip is slower
        same = (pos == safe) & (self.lane[safe] == lane)
        return np.where(same, self.vehicle[safe], -1)

    def lookup(self, lane: IntArray, x: FloatArray) -> tuple[IntArray, IntArray]:
        """Leader and follower a vehicle would have at position x in ``lane`` (-1 if none).

        An entry at exactly the same position counts as the follower.
        """
        pos = np.searchsorted(self.key, lane * OFFSET + x, side="right")
        leader = self._neighbour(pos, lane)
        follower = self._neighbour(pos - 1, lane)
        return leader, follower


def build_lane_index(vehicle: IntArray, lane: IntArray, x: FloatArray) -> LaneIndex:
    """Sort entries (vehicle, lane) at positions x into a :class:`LaneIndex`."""
    key = lane * OFFSET + x
    order = np.argsort(key, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return LaneIndex(vehicle=vehicle[order], lane=lane[order], key=key[order], rank=rank)
