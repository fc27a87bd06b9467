"""Per-lane leader/follower search (hcomc.sim.neighbours) against a brute-force oracle."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.sim.neighbours import LaneIndex, build_lane_index


def _build(entries: list[tuple[int, int, float]]) -> LaneIndex:
    vehicle = np.array([e[0] for e in entries], dtype=np.int64)
    lane = np.array([e[1] for e in entries], dtype=np.int64)
    x = np.array([e[2] for e in entries], dtype=np.float64)
    return build_lane_index(vehicle, lane, x)


def _oracle_neighbours(entries: list[tuple[int, int, float]]) -> tuple[list[int], list[int]]:
    """O(N^2) leader/follower of each entry: nearest entry of the same lane ahead/behind.

    Entries at the same position are ordered by their input order (the stable sort of the
    index), so of two tied entries the later one is the leader of the earlier one.
    """
    leaders, followers = [], []
    for k, (_, lane, x) in enumerate(entries):
        ahead = [
            (xo, ko, vo)
            for ko, (vo, lo, xo) in enumerate(entries)
            if ko != k and lo == lane and (xo > x or (xo == x and ko > k))
        ]
        behind = [
            (xo, ko, vo)
            for ko, (vo, lo, xo) in enumerate(entries)
            if ko != k and lo == lane and (xo < x or (xo == x and ko < k))
        ]
        leaders.append(min(ahead)[2] if ahead else -1)
        followers.append(max(behind)[2] if behind else -1)
    return leaders, followers


def _oracle_lookup(entries: list[tuple[int, int, float]], lane: int, x: float) -> tuple[int, int]:
    """Leader (nearest entry strictly ahead) and follower (nearest at or behind x)."""
    ahead = [(xo, k, v) for k, (v, lo, xo) in enumerate(entries) if lo == lane and xo > x]
    behind = [(xo, k, v) for k, (v, lo, xo) in enumerate(entries) if lo == lane and xo <= x]
    return (min(ahead)[2] if ahead else -1), (max(behind)[2] if behind else -1)


# positions on a quarter-metre grid: exact in binary, so lane * OFFSET + x is exact and ties
# (same x in one lane) really occur
_position = st.integers(min_value=0, max_value=8000).map(lambda q: q / 4.0)


@st.composite
def _snapshots(draw: st.DrawFn) -> list[tuple[int, int, float]]:
    """Entries as the engine builds them: every vehicle once, lane changers twice."""
    n = draw(st.integers(min_value=0, max_value=25))
    lanes = draw(st.lists(st.integers(0, 2), min_size=n, max_size=n))
    xs = draw(st.lists(_position, min_size=n, max_size=n))
    entries = [(i, lanes[i], xs[i]) for i in range(n)]
    changers = draw(st.lists(st.integers(0, max(n - 1, 0)), max_size=n, unique=True)) if n else []
    for i in changers:
        other = 1 if lanes[i] != 1 else draw(st.sampled_from([0, 2]))
        entries.append((i, other, xs[i]))  # second entry at the same x, adjacent lane
    return entries


@settings(max_examples=100, deadline=None)
@given(entries=_snapshots())
def test_leader_and_follower_match_brute_force(entries):
    index = _build(entries)
    want_lead, want_fol = _oracle_neighbours(entries)
    all_entries = np.arange(len(entries), dtype=np.int64)
    np.testing.assert_array_equal(index.leader_of(all_entries), want_lead)
    np.testing.assert_array_equal(index.follower_of(all_entries), want_fol)
    # any subset, in any order
    sub = all_entries[::-2]
    np.testing.assert_array_equal(index.leader_of(sub), np.asarray(want_lead, dtype=int)[sub])
    np.testing.assert_array_equal(index.follower_of(sub), np.asarray(want_fol, dtype=int)[sub])


@settings(max_examples=100, deadline=None)
@given(
    entries=_snapshots(),
    queries=st.lists(st.tuples(st.integers(0, 2), _position), min_size=1, max_size=10),
    at_entries=st.booleans(),
)
def test_lookup_matches_brute_force(entries, queries, at_entries):
    if at_entries and entries:  # query exactly at existing positions: exercises the tie rule
        queries = [(lane, entries[k % len(entries)][2]) for k, (lane, _) in enumerate(queries)]
    index = _build(entries)
    lane = np.array([q[0] for q in queries], dtype=np.int64)
    x = np.array([q[1] for q in queries], dtype=np.float64)
    leader, follower = index.lookup(lane, x)
    want = [_oracle_lookup(entries, int(q[0]), float(q[1])) for q in queries]
    np.testing.assert_array_equal(leader, [w[0] for w in want])
    np.testing.assert_array_equal(follower, [w[1] for w in want])


@settings(max_examples=50, deadline=None)
@given(entries=_snapshots())
def test_sorted_keys_and_rank_are_consistent(entries):
    index = _build(entries)
    assert (np.diff(index.key) >= 0).all()
    np.testing.assert_array_equal(np.sort(index.rank), np.arange(len(entries)))
    for k, (v, lane, x) in enumerate(entries):
        pos = index.rank[k]
        assert index.vehicle[pos] == v
        assert index.lane[pos] == lane
        assert index.key[pos] == pytest.approx(lane * 1.0e7 + x, abs=1e-6)


def test_lane_changer_is_seen_by_followers_in_both_lanes():
    # vehicle 1 changes from lane 1 to lane 2 at x = 100: it has an entry in each lane
    entries = [(0, 1, 50.0), (1, 1, 100.0), (2, 2, 60.0), (3, 2, 150.0), (1, 2, 100.0)]
    index = _build(entries)
    np.testing.assert_array_equal(index.leader_of(np.arange(5)), [1, -1, 1, -1, 3])
    np.testing.assert_array_equal(index.follower_of(np.arange(5)), [-1, 0, -1, 1, 2])


def test_empty_index():
    empty_i = np.empty(0, dtype=np.int64)
    index = build_lane_index(empty_i, empty_i, np.empty(0))
    assert index.leader_of(empty_i).shape == (0,)
    assert index.follower_of(empty_i).shape == (0,)
    leader, follower = index.lookup(np.array([0, 1, 2]), np.array([0.0, 10.0, 1e6]))
    np.testing.assert_array_equal(leader, [-1, -1, -1])
    np.testing.assert_array_equal(follower, [-1, -1, -1])


def test_single_entry():
    index = _build([(7, 1, 100.0)])
    np.testing.assert_array_equal(index.leader_of(np.array([0])), [-1])
    np.testing.assert_array_equal(index.follower_of(np.array([0])), [-1])
    lanes = np.array([1, 1, 1, 0, 2])
    xs = np.array([99.9, 100.0, 100.1, 100.0, 100.0])
    leader, follower = index.lookup(lanes, xs)
    np.testing.assert_array_equal(leader, [7, -1, -1, -1, -1])
    np.testing.assert_array_equal(follower, [-1, 7, 7, -1, -1])


def test_lookup_entry_at_exactly_the_query_position_is_the_follower():
    index = _build([(0, 1, 10.0), (1, 1, 20.0), (2, 1, 30.0), (3, 2, 20.0)])
    leader, follower = index.lookup(np.array([1, 2]), np.array([20.0, 20.0]))
    np.testing.assert_array_equal(leader, [2, -1])
    np.testing.assert_array_equal(follower, [1, 3])


def test_lanes_do_not_leak_at_the_lane_boundary():
    # the last entry of lane 0 and the first of lane 1 are adjacent in the sorted order
    index = _build([(0, 0, 900.0), (1, 1, 0.0), (2, 2, 0.0)])
    np.testing.assert_array_equal(index.leader_of(np.arange(3)), [-1, -1, -1])
    np.testing.assert_array_equal(index.follower_of(np.arange(3)), [-1, -1, -1])
    leader, follower = index.lookup(np.array([0, 1]), np.array([950.0, -1.0]))
    np.testing.assert_array_equal(leader, [-1, 1])
    np.testing.assert_array_equal(follower, [0, -1])
