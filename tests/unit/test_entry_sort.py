"""The step's sort of lane entries (hcomc.sim.neighbours.sort_entries and the natural merge
sort hcomc.sim.arrays.sort_runs it uses lane by lane) against numpy's stable argsort."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.sim.arrays import sort_runs
from hcomc.sim.neighbours import OFFSET, build_lane_index, neighbour, neighbours_into


def _stable(vehicle: np.ndarray, lane: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, ...]:
    """What the index must hold: entries in numpy's stable order of ``lane * OFFSET + x``."""
    key = lane * OFFSET + x
    order = np.argsort(key, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return vehicle[order], lane[order], key[order], rank


def _assert_stable_order(vehicle: np.ndarray, lane: np.ndarray, x: np.ndarray) -> None:
    index = build_lane_index(vehicle, lane, x)
    want = _stable(vehicle, lane, x)
    for got, expected in zip((index.vehicle, index.lane, index.key, index.rank), want, strict=True):
        np.testing.assert_array_equal(got, expected)


# positions as the engine meets them: per lane mostly in reverse order of entry (vehicles
# enter upstream), a few out of place (lane changes), some ties and near ties
_x = st.one_of(
    st.floats(-50.0, 1600.0, allow_nan=False),
    st.sampled_from([0.0, 1e-10, 2e-9, 5.0, 700.0]),  # ties, and distinct x whose keys tie
)


@settings(max_examples=200, deadline=None)
@given(
    xs=st.lists(_x, max_size=120),
    lanes=st.lists(st.integers(0, 2), min_size=120, max_size=120),
    descending=st.booleans(),
    swaps=st.lists(st.tuples(st.integers(0, 119), st.integers(0, 119)), max_size=4),
)
def test_entries_sort_in_numpys_stable_order(xs, lanes, descending, swaps):
    x = np.array(xs, dtype=np.float64)
    if descending:
        x = np.sort(x)[::-1].copy()
    for a, b in swaps:
        if a < x.size and b < x.size:
            x[[a, b]] = x[[b, a]]
    lane = np.array(lanes[: x.size], dtype=np.int64)
    vehicle = np.arange(x.size, dtype=np.int64)[::-1].copy()
    _assert_stable_order(vehicle, lane, x)


@pytest.mark.parametrize("n", [0, 1, 24, 25, 200, 2000])
def test_a_lane_in_reverse_order_of_position_sorts_exactly(n):
    """The engine's common case (one lane, downstream vehicles first), on both sides of the
    size where the sort switches from one insertion sort to the lane-by-lane merge sort."""
    x = np.linspace(10_000.0, 0.0, n)
    _assert_stable_order(np.arange(n, dtype=np.int64), np.ones(n, dtype=np.int64), x)


def test_lanes_outside_the_road_or_overlapping_keys_fall_back_to_the_general_sort():
    rng = np.random.default_rng(3)
    x = rng.uniform(0.0, 1500.0, 60)
    lane = rng.integers(0, 3, 60)
    lane[7] = 5  # not a lane of the road
    _assert_stable_order(np.arange(60, dtype=np.int64), lane, x)
    x[11], lane[7] = 2.5 * OFFSET, 1  # lane 1 reaches into lane 2's keys
    _assert_stable_order(np.arange(60, dtype=np.int64), lane, x)


@settings(max_examples=200, deadline=None)
@given(
    keys=st.lists(st.integers(0, 6).map(float), max_size=80),
    bounds=st.tuples(st.integers(0, 80), st.integers(0, 80)),
)
def test_sort_runs_sorts_a_segment_stably_and_leaves_the_rest(keys, bounds):
    k = np.array(keys, dtype=np.float64)
    lo, hi = sorted(min(b, k.size) for b in bounds)
    order = np.arange(k.size, dtype=np.int64)[::-1].copy()
    want = order.copy()
    want[lo:hi] = order[lo:hi][np.argsort(k[order[lo:hi]], kind="stable")]
    sort_runs(k, order, np.empty(k.size, dtype=np.int64), lo, hi)
    np.testing.assert_array_equal(order, want)


@settings(max_examples=100, deadline=None)
@given(
    xs=st.lists(st.integers(0, 40).map(float), max_size=50),
    lanes=st.lists(st.integers(0, 2), min_size=50, max_size=50),
    step=st.sampled_from([1, -1]),
)
def test_neighbours_into_is_neighbour_of_each_entry(xs, lanes, step):
    x = np.array(xs, dtype=np.float64)
    lane = np.array(lanes[: x.size], dtype=np.int64)
    index = build_lane_index(np.arange(x.size, dtype=np.int64), lane, x)
    out = np.empty(x.size, dtype=np.int64)
    neighbours_into(index.vehicle, index.lane, index.rank, step, out)
    want = [
        neighbour(index.vehicle, index.lane, index.rank[k] + step, index.lane[index.rank[k]])
        for k in range(x.size)
    ]
    np.testing.assert_array_equal(out, want)
