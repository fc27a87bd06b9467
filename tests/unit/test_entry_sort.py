"""The step's sort of lane entries (hcomc.sim.neighbours.sort_entries, the natural merge
sort hcomc.sim.arrays.sort_runs it uses lane by lane on the paper road, and the resort from
the previous step's order, hcomc.sim.arrays.resort_into, that the engine's steps use) against
numpy's stable argsort."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.sim.arrays import resort_into, sort_runs
from hcomc.sim.neighbours import (
    OFFSET,
    PreviousOrder,
    build_lane_index,
    neighbour,
    neighbours_into,
    sort_entries_into,
)


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


@settings(max_examples=300, deadline=None)
@given(
    keys=st.lists(st.integers(0, 8).map(float), max_size=60),
    kept=st.lists(st.booleans(), min_size=60, max_size=60),
    seed=st.integers(0, 2**16),
    swaps=st.integers(0, 6),
)
def test_resort_gives_the_stable_order_from_any_start(keys, kept, seed, swaps):
    """Kept indices in a nearly sorted order (a few swaps), the others added in any order:
    the result is numpy's stable order."""
    k = np.array(keys, dtype=np.float64)
    stable = np.argsort(k, kind="stable")
    keep = np.array(kept[: k.size], dtype=bool)
    start = stable[keep[stable]].copy()
    rng = np.random.default_rng(seed)
    for _ in range(swaps if start.size > 1 else 0):
        a, b = rng.integers(0, start.size, 2)
        start[[a, b]] = start[[b, a]]
    order = np.zeros(k.size, dtype=np.int64)
    order[: start.size] = start
    added = rng.permutation(np.flatnonzero(~keep)).astype(np.int64)
    work = np.concatenate([added, np.zeros(k.size - added.size, dtype=np.int64)])
    assert resort_into(k, order, start.size, work, added.size, 10**6)
    np.testing.assert_array_equal(order, stable)


def test_resort_gives_up_beyond_its_budget_or_on_nan():
    k = np.arange(50, dtype=np.float64)
    reverse = np.arange(50, dtype=np.int64)[::-1].copy()
    assert not resort_into(k, reverse.copy(), 50, np.zeros(0, dtype=np.int64), 0, 100)
    assert resort_into(k, reverse.copy(), 50, np.zeros(0, dtype=np.int64), 0, 50 * 49 // 2)
    k[3] = np.nan
    assert not resort_into(k, np.arange(50, dtype=np.int64), 50, np.zeros(0, np.int64), 0, 10**6)


def _step_entries(
    rng: np.random.Generator, x: np.ndarray, lane: np.ndarray, alive: np.ndarray, lanes: int
):
    """One step of a road of lanes ``0 .. lanes - 1``: vehicles move on at random speeds
    (overtaking each other), a few enter, leave, change lane (a changer has a second entry in
    its target lane, after all first entries)."""
    x += rng.uniform(0.0, 3.0, x.size)
    alive &= rng.random(x.size) > 0.02
    born = ~alive & (rng.random(x.size) < 0.05)
    alive |= born
    x[born] = rng.choice([0.0, 500.0, 1000.0], born.sum())  # ramps: ties with each other
    lane[born] = rng.integers(0, lanes, born.sum())
    moved = alive & (rng.random(x.size) < 0.03)
    lane[moved] = rng.integers(0, lanes, moved.sum())
    ids = np.flatnonzero(alive)
    changers = ids[rng.random(ids.size) < 0.1]
    vehicle = np.concatenate([ids, changers]).astype(np.int64)
    lane_of = np.concatenate([lane[ids], (lane[changers] + 1) % lanes]).astype(np.int64)
    return vehicle, lane_of, x[vehicle]


@pytest.mark.parametrize("lanes", [3, 8])
def test_entries_sorted_from_the_previous_steps_order_equal_a_fresh_sort(lanes):
    """The engine's path: each step sorts from the last step's sorted entries
    (:class:`PreviousOrder`) and must give numpy's stable order, as a fresh sort; on the
    paper road's three lane codes and on a road of eight."""
    rng = np.random.default_rng(11)
    n = 300
    x, lane = rng.uniform(0.0, 2000.0, n), rng.integers(0, lanes, n)
    alive = rng.random(n) < 0.7
    width = 2 * n + 1
    ints = np.zeros((7, width), dtype=np.int64)
    ints[3] = -1  # the sorted vehicles' row: nothing sorted yet
    floats = np.zeros((2, width))
    for _ in range(200):
        vehicle, lane_of, xs = _step_entries(rng, x, lane, alive, lanes)
        previous = PreviousOrder(True, ints[5], ints[6])
        got = sort_entries_into(vehicle, lane_of, xs, *ints[:5], *floats, previous)
        for g, want in zip(got, _stable(vehicle, lane_of, xs), strict=True):
            np.testing.assert_array_equal(g, want)
