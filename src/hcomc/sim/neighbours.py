"""Leader/follower search per lane (sort by position, no pairwise loops).

A snapshot's *entries* are (vehicle, lane) pairs: every active vehicle in the lane it is
driving in and, while it changes lane, also in its target lane (as in SUMO's sublane model),
so followers in both lanes see it during the manoeuvre. Entries are sorted by
``lane * OFFSET + x``; a vehicle's leader in a lane is the next entry of the same lane.

The compiled kernels below (:func:`sort_entries`, :func:`neighbour`, :func:`lookup_one`) are
the one implementation; the simulation step calls them directly and :class:`LaneIndex` wraps
them for array callers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray, IntArray
from hcomc.sim.small import search_right, stable_argsort

OFFSET = 1.0e7
"""Key offset between lanes [m]; larger than any road length."""


@kernel
def sort_entries(
    vehicle: np.ndarray, lane: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Entries (vehicle, lane) at positions x sorted by ``lane * OFFSET + x`` (stable):
    ``(vehicle, lane, key, rank)`` with ``rank`` the sorted position of each given entry."""
    key = lane * OFFSET + x
    order = stable_argsort(key)
    rank = np.empty(order.size, dtype=np.int64)
    for p in range(order.size):
        rank[order[p]] = p
    return vehicle[order], lane[order], key[order], rank


@kernel(inline="always")
def neighbour(vehicle: np.ndarray, lane_of: np.ndarray, pos: int, lane: int) -> int:
    """Vehicle of sorted entry ``pos`` if it exists and lies in ``lane``, else -1."""
    if 0 <= pos < vehicle.size and lane_of[pos] == lane:
        return int(vehicle[pos])
    return -1


@kernel(inline="always")
def lookup_one(
    key: np.ndarray, lane_of: np.ndarray, vehicle: np.ndarray, lane: int, x: float
) -> tuple[int, int]:
    """Leader and follower a vehicle would have at position x in ``lane`` (-1 if none).

    An entry at exactly the same position counts as the follower.
    """
    pos = search_right(key, lane * OFFSET + x)
    return neighbour(vehicle, lane_of, pos, lane), neighbour(vehicle, lane_of, pos - 1, lane)


@kernel
def _neighbours_of(vehicle, lane_of, rank, entries, step):
    out = np.empty(entries.size, dtype=np.int64)
    for k in range(entries.size):
        pos = rank[entries[k]]
        out[k] = neighbour(vehicle, lane_of, pos + step, lane_of[pos])
    return out


@kernel
def _lookup_many(key, lane_of, vehicle, lane, x):
    leader = np.empty(x.size, dtype=np.int64)
    follower = np.empty(x.size, dtype=np.int64)
    for k in range(x.size):
        leader[k], follower[k] = lookup_one(key, lane_of, vehicle, lane[k], x[k])
    return leader, follower


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
        return _neighbours_of(self.vehicle, self.lane, self.rank, _ints(entries), 1)

    def follower_of(self, entries: IntArray) -> IntArray:
        """Vehicle behind each given (unsorted) entry in the same lane, -1 if none."""
        return _neighbours_of(self.vehicle, self.lane, self.rank, _ints(entries), -1)

    def lookup(self, lane: IntArray, x: FloatArray) -> tuple[IntArray, IntArray]:
        """Leader and follower a vehicle would have at position x in ``lane`` (-1 if none).

        An entry at exactly the same position counts as the follower.
        """
        x = np.asarray(x, dtype=np.float64).reshape(-1)
        lane = np.broadcast_to(np.asarray(lane, dtype=np.int64), x.shape).copy()
        return _lookup_many(self.key, self.lane, self.vehicle, lane, x)


def _ints(a: IntArray) -> IntArray:
    return np.ascontiguousarray(a, dtype=np.int64).reshape(-1)


def build_lane_index(vehicle: IntArray, lane: IntArray, x: FloatArray) -> LaneIndex:
    """Sort entries (vehicle, lane) at positions x into a :class:`LaneIndex`."""
    v, ln, key, rank = sort_entries(
        _ints(vehicle), _ints(lane), np.ascontiguousarray(x, dtype=np.float64).reshape(-1)
    )
    return LaneIndex(vehicle=v, lane=ln, key=key, rank=rank)
