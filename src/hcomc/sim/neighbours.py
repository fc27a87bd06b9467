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

import math
from typing import NamedTuple

import numpy as np

from hcomc._jit import borrow, kernel
from hcomc._typing import FloatArray, IntArray
from hcomc.road import Lane
from hcomc.sim.arrays import resort_into, search_right, sort_runs, stable_argsort_into

OFFSET = 1.0e7
"""Key offset between lanes [m]; larger than any road length."""
_RAMP, _MAIN_1, _MAIN_2 = int(Lane.RAMP), int(Lane.MAIN_1), int(Lane.MAIN_2)


class PreviousOrder(NamedTuple):
    """The entries the step sorted last, from which :func:`sort_entries_into` starts: their
    vehicles and lanes, which its ``vehicle_out`` and ``lane_out`` hold from the last sort
    until a vehicle -1 (the engine's work rows start with -1: nothing sorted yet)."""

    kept: bool  # whether they do (False: the arrays hold nothing of a last sort)
    first_of: np.ndarray  # (N,) work: the given position of each vehicle's first entry
    second_of: np.ndarray  # (N,) work: the given position of its second entry, -1 if none


@kernel
def sort_entries(
    vehicle: np.ndarray, lane: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Entries (vehicle, lane) at positions x sorted by ``lane * OFFSET + x`` (stable):
    ``(vehicle, lane, key, rank)`` with ``rank`` the sorted position of each given entry."""
    n = vehicle.size
    ints = np.empty((5, n), dtype=np.int64)
    floats = np.empty((2, n))
    no_previous = PreviousOrder(False, ints[0, :0], ints[0, :0])
    return sort_entries_into(
        vehicle, lane, x, ints[0], ints[1], ints[2], ints[3], ints[4], floats[0], floats[1],
        no_previous,
    )  # fmt: skip


@kernel(inline="always")  # its four views returned from a call would be reference-counted
def sort_entries_into(
    vehicle: np.ndarray, lane: np.ndarray, x: np.ndarray, order: np.ndarray,
    buffer: np.ndarray, rank: np.ndarray, vehicle_out: np.ndarray, lane_out: np.ndarray,
    key: np.ndarray, key_out: np.ndarray, previous: PreviousOrder,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`sort_entries` in the caller's work arrays (each at least as long as
    ``vehicle``); returns views of them.

    The entries are ordered from the order of the previous step's (``previous``, whose
    vehicles and lanes ``vehicle_out`` and ``lane_out`` still hold), which vehicles rarely
    change (:func:`_order_from_previous`); the first step's on the paper road lane by lane
    (:func:`_order_by_lane`), and by the general sort when neither applies. All three give
    the one stable order."""
    n = vehicle.size
    key = key[:n]
    for p in range(n):
        key[p] = lane[p] * OFFSET + x[p]
    ordered = previous.kept and _order_from_previous(
        vehicle, lane, key, vehicle_out, lane_out, previous, order, buffer, rank
    )
    if not ordered:
        ordered = _order_by_lane(lane, key, order, buffer)
    if not ordered:
        order = stable_argsort_into(key, order, buffer)
    if previous.kept and n < vehicle_out.size:
        vehicle_out[n] = -1  # where the next sort's start ends
    rank, vehicle_out, lane_out, key_out = rank[:n], vehicle_out[:n], lane_out[:n], key_out[:n]
    for p in range(n):
        q = order[p]
        rank[q] = p
        vehicle_out[p], lane_out[p], key_out[p] = vehicle[q], lane[q], key[q]
    return vehicle_out, lane_out, key_out, rank


@kernel
def _order_by_lane(
    lane: np.ndarray, key: np.ndarray, order: np.ndarray, buffer: np.ndarray
) -> bool:
    """The stable order of ``key`` in ``order[:n]``, found lane by lane: the entries are
    partitioned by lane (ramp, lane 1, lane 2) in their given order and each lane is sorted
    by :func:`~hcomc.sim.arrays.sort_runs`, linear for the entries of a lane (nearly in
    reverse order of position). That is the stable order of all keys when every key of a
    lane lies below every key of the next; False (``order`` then undefined) when a lane is
    not 0-2 or the lanes' keys overlap, for the general sort."""
    n = key.size
    n_ramp = n_main = 0
    for p in range(n):
        if lane[p] == _RAMP:
            n_ramp += 1
        elif lane[p] == _MAIN_1:
            n_main += 1
        elif lane[p] != _MAIN_2:
            return False
    bounds = (0, n_ramp, n_ramp + n_main, n)
    f_ramp, f_main, f_outer = bounds[0], bounds[1], bounds[2]
    for p in range(n):
        if lane[p] == _RAMP:
            order[f_ramp] = p
            f_ramp += 1
        elif lane[p] == _MAIN_1:
            order[f_main] = p
            f_main += 1
        else:
            order[f_outer] = p
            f_outer += 1
    last = -math.inf
    for q in range(3):
        lo, hi = bounds[q], bounds[q + 1]
        if lo == hi:
            continue
        sort_runs(key, order, buffer, lo, hi)
        if not last < key[order[lo]]:
            return False
        last = key[order[hi - 1]]
    return True


@kernel
def _order_from_previous(
    vehicle: np.ndarray, lane: np.ndarray, key: np.ndarray, previous_vehicle: np.ndarray,
    previous_lane: np.ndarray, previous: PreviousOrder, order: np.ndarray, buffer: np.ndarray,
    placed: np.ndarray,
) -> bool:  # fmt: skip
    """The stable order of ``key`` in ``order[:n]``, from the previous step's sorted entries
    ((vehicle, lane) in ``previous_vehicle``, ``previous_lane``, until a vehicle -1):
    each entry that was there starts at its place then, each new one (a vehicle entered, a
    change begun) among the others; :func:`~hcomc.sim.arrays.resort_into` orders them, in
    one pass when nobody overtook. A vehicle's entries are found by ``previous``'s work
    arrays; ``placed`` (n,) is work space. False (``order`` then undefined) when the order
    changed too much or nothing was sorted before, for the other sorts."""
    n = vehicle.size
    first_of, second_of = previous.first_of, previous.second_of
    for p in range(n):  # a vehicle's entries in the order given: the first, then its other
        i = vehicle[p]
        f = first_of[i]
        if 0 <= f < p and vehicle[f] == i:
            second_of[i] = p
        else:
            first_of[i], second_of[i] = p, -1
        placed[p] = 0
    n_kept = 0
    for e in range(previous_vehicle.size):
        i, lane_then = previous_vehicle[e], previous_lane[e]
        if i < 0:
            break
        p = first_of[i]
        if not (0 <= p < n and vehicle[p] == i):
            continue  # the vehicle has left the road
        if lane[p] != lane_then:
            p = second_of[i]
            if p < 0 or lane[p] != lane_then:
                continue  # it has left that lane
        if not placed[p]:
            placed[p] = 1
            order[n_kept] = p
            n_kept += 1
    if n_kept == 0:
        return False
    n_added = 0
    for p in range(n):
        if not placed[p]:
            buffer[n_added] = p
            n_added += 1
    return resort_into(key, order, n_kept, buffer, n_added, 4 * n + 64)


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
def neighbours_into(
    vehicle: np.ndarray, lane_of: np.ndarray, rank: np.ndarray, step: int, out: np.ndarray
) -> None:
    """The vehicle ``step`` sorted entries away in the same lane (1: the leader, -1: the
    follower; -1 if none) of the entries at sorted positions ``rank[:out.size]``, written
    into ``out`` (:func:`neighbour` of each, on borrowed views: see
    :func:`hcomc._jit.borrow`)."""
    vehicle, lane_of = borrow(vehicle), borrow(lane_of)
    for k in range(out.size):
        p = rank[k]
        out[k] = neighbour(vehicle, lane_of, p + step, lane_of[p])


@kernel
def _neighbours_of(
    vehicle: np.ndarray, lane_of: np.ndarray, rank: np.ndarray, entries: np.ndarray, step: int
) -> np.ndarray:
    out = np.empty(entries.size, dtype=np.int64)
    neighbours_into(vehicle, lane_of, rank[entries], step, out)
    return out


@kernel
def lookup_into(
    key: np.ndarray, lane_of: np.ndarray, vehicle: np.ndarray, lane: np.ndarray,
    x: np.ndarray, leader: np.ndarray, follower: np.ndarray,
) -> None:  # fmt: skip
    """:func:`lookup_one` of every position ``x`` in its ``lane``, written into ``leader``
    and ``follower`` (on borrowed views: see :func:`hcomc._jit.borrow`)."""
    key, lane_of, vehicle = borrow(key), borrow(lane_of), borrow(vehicle)
    for k in range(x.size):
        leader[k], follower[k] = lookup_one(key, lane_of, vehicle, lane[k], x[k])


@kernel
def _lookup_many(
    key: np.ndarray, lane_of: np.ndarray, vehicle: np.ndarray, lane: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    leader = np.empty(x.size, dtype=np.int64)
    follower = np.empty(x.size, dtype=np.int64)
    lookup_into(key, lane_of, vehicle, lane, x, leader, follower)
    return leader, follower


class LaneIndex(NamedTuple):
    """Entries of one snapshot sorted by (lane, x); a record the compiled step also passes
    between its kernels (its methods are for Python callers).

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
