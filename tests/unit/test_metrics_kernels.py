"""The compiled metric kernels against plain numpy computations of the same definitions on
dense (T, N) arrays, on random logs stored in slot columns and with one column per vehicle."""

from __future__ import annotations

import copy
import math
from functools import cache
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import load_config
from hcomc.equations.fuel import fuel_rate
from hcomc.metrics import (
    KEY_ROLES,
    METRICS,
    OUTCOME_FIELDS,
    MetricWindow,
    compute_metrics,
    deviations,
    fuel,
    lane_speed_field,
    low_speed_region_volume,
)
from hcomc.metrics.lane_order import lane_order
from hcomc.metrics.lane_profile import interp_ascending_into, interp_into, lane_knots
from hcomc.metrics.leaders import lane_follower, lane_leaders
from hcomc.metrics.paper import disturbance_metrics
from hcomc.metrics.surrogate import closing_metrics
from hcomc.metrics.window import EPS_T, road_of, window_rows
from hcomc.sim.log import SimulationLog

DT = 0.1  # logging interval of the random logs [s]


@cache
def _config() -> dict[str, Any]:
    return load_config("C1").model_dump(mode="json")  # road 1500 m, control zone from 400 m


def random_logs(
    seed: int, n_rows: int, n_vehicles: int, *, slots: int = 2, nan_x: float = 0.0
) -> tuple[SimulationLog, SimulationLog]:
    """The same random rows recorded into a slot-column log and a log with one column per
    vehicle: each vehicle on the road for one stretch of rows, on a 5 m grid of positions
    (ties) over and beyond the road, in lanes 0-2; ``nan_x``: share of NaN positions."""
    rng = np.random.default_rng(seed)
    first = rng.integers(0, n_rows, n_vehicles)
    end = first + rng.integers(1, n_rows + 1, n_vehicles)
    size = {"kind": rng.integers(0, 2, n_vehicles), "length": rng.uniform(4.0, 6.0, n_vehicles),
            "width": np.full(n_vehicles, 1.8)}  # fmt: skip
    meta = {"config": _config()}
    logs = tuple(
        SimulationLog.allocate(n_rows, n_vehicles, dt=DT, slots=s, meta=copy.deepcopy(meta), **size)
        for s in (slots, None)
    )
    zeros = np.zeros(n_vehicles)
    for k in range(n_rows):
        x = np.round(rng.uniform(-20.0, 1520.0, n_vehicles) / 5.0) * 5.0
        x[rng.random(n_vehicles) < nan_x] = np.nan
        v, a = rng.uniform(0.0, 35.0, n_vehicles), rng.normal(0.0, 1.0, n_vehicles)
        lane, on = rng.integers(0, 3, n_vehicles), (k >= first) & (k < end)
        for log in logs:
            log.record(k, k * DT, x, zeros, v, a, zeros, lane, on)
    return logs[0], logs[1]


def random_window(rng: np.random.Generator, n_rows: int, n_vehicles: int) -> MetricWindow:
    """A group of up to six distinct vehicles (VR first, -1 for missing roles) and window
    times on the rows' times (``t_merge`` NaN now and then)."""
    picked = rng.permutation(n_vehicles)[: rng.integers(0, min(n_vehicles, 6) + 1)].tolist()
    slots = picked + [-1] * (len(KEY_ROLES) - len(picked))
    group = dict(zip(KEY_ROLES, slots, strict=True)) if picked else {}
    t0, t1 = np.sort(rng.integers(0, n_rows, 2)) * DT
    t_merge = math.nan if rng.random() < 0.2 else rng.integers(0, n_rows) * DT
    return MetricWindow(group=group, t_start=float(t0), t_merge=float(t_merge), t_end=float(t1))


def same(got: Any, want: Any) -> None:
    """Equal bit for bit, NaN where NaN."""
    np.testing.assert_array_equal(np.asarray(got), np.asarray(want), strict=True)


def stable_lane(log: SimulationLog, k: int, lane: int) -> np.ndarray:
    """The vehicles of ``lane`` active in row ``k``, sorted stably by position (dense)."""
    on = np.flatnonzero(np.asarray(log.active)[k] & (np.asarray(log.lane)[k] == lane))
    return on[np.argsort(np.asarray(log.x)[k, on].astype(np.float64), kind="stable")]


# ------------------------------------------------------------------- row kernels
_grid = st.integers(0, 20).map(float)


@settings(max_examples=300, deadline=None)
@given(x=st.lists(st.one_of(_grid, st.just(math.nan)), max_size=60), data=st.data())
def test_lane_knots_are_the_lanes_vehicles_in_numpys_stable_order(
    x: list[float], data: st.DataObject
) -> None:
    """Ties in vehicle order and NaN positions last, for few knots (insertion sort) and for
    many (mergesort)."""
    n = len(x)
    x_row = np.array(x, dtype=np.float32)
    lane_row = np.array(data.draw(st.lists(st.integers(0, 2), min_size=n, max_size=n)), np.int8)
    active = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)), dtype=bool)
    candidates = np.flatnonzero(active)
    cols, xs = np.empty(n, dtype=np.int64), np.empty(n)
    m = lane_knots(candidates, x_row, lane_row, 1, cols, xs)
    on = candidates[lane_row[candidates] == 1]
    want = on[np.argsort(x_row[on].astype(np.float64), kind="stable")]
    same(cols[:m], want)
    same(xs[:m], x_row[want].astype(np.float64))


_entry = st.tuples(st.integers(0, 3), st.one_of(_grid, st.just(math.nan)), st.integers(0, 1))
"""A row's entry: lane, position, and whether the vehicle has a second entry."""


@settings(max_examples=300, deadline=None)
@given(rows=st.lists(st.lists(_entry, max_size=40), max_size=6))
def test_lane_order_is_numpys_lexsort(rows: list[list[tuple[int, float, int]]]) -> None:
    """Rows of entries (lane, x, and whether the vehicle has a second entry, as a lane
    changer has in :func:`hcomc.metrics.bodies.body_pairs`), each row's in vehicle order: the
    order of ``np.lexsort`` by row, lane, x (ties and NaN) and vehicle."""
    lane, x, vehicle, row, counts = [], [], [], [], []
    for r, entries in enumerate(rows):
        count = 0
        for i, (g, xi, twice) in enumerate(entries):
            for other in range(1 + twice):  # the second entry in the next lane up
                lane.append((g + other) % 4)
                x.append(xi)
                vehicle.append(i)
                row.append(r)
                count += 1
        counts.append(count)
    start = np.concatenate(([0], np.cumsum(counts))).astype(np.int64)
    lanes, xs = np.array(lane, dtype=np.int64), np.array(x, dtype=np.float64)
    vehicles, row_of = np.array(vehicle, dtype=np.int64), np.array(row, dtype=np.int64)
    same(lane_order(start, lanes, xs, vehicles), np.lexsort((vehicles, xs, lanes, row_of)))


@pytest.mark.parametrize("seed", range(5))
def test_lane_knots_of_a_crowded_lane(seed: int) -> None:
    """Beyond the insertion sort's reach: 200 vehicles, ties and NaN positions."""
    rng = np.random.default_rng(seed)
    x_row = rng.integers(0, 30, 200).astype(np.float32)
    x_row[rng.random(200) < 0.05] = np.nan
    lane_row = np.where(rng.random(200) < 0.9, 1, 2).astype(np.int8)
    candidates = np.flatnonzero(rng.random(200) < 0.95)
    cols, xs = np.empty(200, dtype=np.int64), np.empty(200)
    m = lane_knots(candidates, x_row, lane_row, 1, cols, xs)
    on = candidates[lane_row[candidates] == 1]
    assert m > 40
    same(cols[:m], on[np.argsort(x_row[on].astype(np.float64), kind="stable")])


_coords = st.floats(-50.0, 50.0, allow_nan=False).map(lambda v: round(v, 1))  # many ties


@settings(max_examples=300, deadline=None)
@given(
    xp=st.lists(_coords, min_size=1, max_size=12).map(sorted),
    fp=st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=12, max_size=12),
    x=st.lists(st.one_of(_coords, st.sampled_from([-math.inf, math.inf])), max_size=30),
    clamp=st.booleans(),
    nan_knots=st.integers(0, 2),
)
def test_interp_ascending_into_is_numpy_interp_bit_for_bit(
    xp: list[float], fp: list[float], x: list[float], clamp: bool, nan_knots: int
) -> None:
    """Ascending queries on knots, between them, beyond them; knots with ties. With NaN
    knots (sorted last) numpy's search is undefined: the general loop's values then."""
    xp_a, fp_a, x_a = np.array(xp), np.array(fp[: len(xp)]), np.sort(np.array(x))
    left, right = (fp_a[0], fp_a[-1]) if clamp else (math.nan, math.nan)
    out = np.empty(x_a.size)
    interp_ascending_into(x_a, xp_a, fp_a, left, right, out)
    same(out, np.interp(x_a, xp_a, fp_a, left=left, right=right))
    if nan_knots:
        xp_n = np.concatenate([xp_a, np.full(nan_knots, np.nan)])
        fp_n = np.concatenate([fp_a, fp_a[-1:].repeat(nan_knots)])
        want = np.empty(x_a.size)
        interp_into(x_a, xp_n, fp_n, left, right, want)
        interp_ascending_into(x_a, xp_n, fp_n, left, right, out)
        same(out, want)


# ------------------------------------------------------------------- speed fields, LSRV
def dense_lane_field(
    log: SimulationLog, window: MetricWindow, lane: int, x_edges: np.ndarray, t_edges: np.ndarray
) -> np.ndarray:
    """The definition of :func:`lane_speed_field` on the (T, N) arrays: per window row,
    :func:`numpy.interp` over the lane's vehicles at the bin centres, its finite samples
    averaged per time bin."""
    centres = 0.5 * (x_edges[:-1] + x_edges[1:])
    n_t, dt_bin = t_edges.size - 1, t_edges[1] - t_edges[0]
    sums, counts = np.zeros((n_t, centres.size)), np.zeros((n_t, centres.size))
    rows = window_rows(log, window)
    for k in range(rows.start, rows.stop):
        it = int(np.clip(np.floor((log.t[k] - window.t_start) / dt_bin + 1e-9), 0, n_t - 1))
        on = stable_lane(log, k, lane)
        if on.size == 0:
            continue
        xp = np.asarray(log.x)[k, on].astype(np.float64)
        fp = np.asarray(log.v)[k, on].astype(np.float64)
        samples = np.interp(centres, xp, fp, left=np.nan, right=np.nan)
        finite = np.isfinite(samples)
        sums[it] += np.where(finite, samples, 0.0)
        counts[it] += finite
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(counts > 0, sums / counts, np.nan)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    n_rows=st.integers(1, 30),
    n_vehicles=st.integers(0, 14),
    x_min=st.sampled_from([0.0, 400.0, 1333.0]),
    dx=st.sampled_from([7.0, 10.0, 60.0]),
    dt_bin=st.sampled_from([0.1, 0.3, 0.5]),
)
def test_lane_speed_field_follows_its_definition(
    seed: int, n_rows: int, n_vehicles: int, x_min: float, dx: float, dt_bin: float
) -> None:
    packed, plain = random_logs(seed, n_rows, n_vehicles)
    window = random_window(np.random.default_rng(seed), n_rows, n_vehicles)
    for log in (packed, plain):
        for lane in (1, 2):
            x_edges, t_edges, V = lane_speed_field(log, window, lane=lane, x_min=x_min, dx=dx,
                                                   dt_bin=dt_bin)  # fmt: skip
            same(V, dense_lane_field(plain, window, lane, x_edges, t_edges))


def dense_lsrv(log: SimulationLog, ref: SimulationLog, window: MetricWindow) -> float:
    """:func:`low_speed_region_volume` by its definition on the (T, N) arrays, cell by cell:
    each vehicle against its own reference cell, VR from its merge on against the reference
    lane interpolated (clamped) at its position, weighted by the lane's mean spacing."""
    if not window.group:
        return 0.0
    if not window.merged:
        return math.nan
    road = road_of(log)
    lo, hi = road.control_zone_start, road.length
    rows = range(*window_rows(log, window).indices(log.n_steps))
    x, v, lane, act = (np.asarray(getattr(log, n)) for n in ("x", "v", "lane", "active"))
    x_u, v_u, lane_u, act_u = (np.asarray(getattr(ref, n)) for n in ("x", "v", "lane", "active"))
    spacing = {}
    for k in (1, 2):
        count = sum(int(np.sum(act_u[r] & (lane_u[r] == k) & (x_u[r] >= lo) & (x_u[r] <= hi)))
                    for r in rows)  # fmt: skip
        spacing[k] = (hi - lo) / max(count / max(len(rows), 1), 1.0)
    total = 0.0
    for r in rows:
        for i in range(log.n_vehicles):
            if not (act[r, i] and lane[r, i] in (1, 2) and lo <= float(x[r, i]) <= hi):
                continue
            if i == window.vr:
                if log.t[r] < window.t_merge - EPS_T:
                    continue
                on = stable_lane(ref, r, int(lane[r, i]))
                if on.size == 0:
                    continue
                xp = x_u[r, on].astype(np.float64)
                mine = float(np.interp(float(x[r, i]), xp, v_u[r, on].astype(np.float64)))
            elif act_u[r, i]:
                mine = float(v_u[r, i])
            else:
                continue
            total += spacing[int(lane[r, i])] * max(0.0, mine - float(v[r, i])) * log.dt
    return total


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), n_rows=st.integers(1, 30), n_vehicles=st.integers(0, 14))
def test_lsrv_follows_its_definition(seed: int, n_rows: int, n_vehicles: int) -> None:
    packed, plain = random_logs(seed, n_rows, n_vehicles)
    ref_packed, ref_plain = random_logs(seed + 1, n_rows, n_vehicles, slots=1)
    window = random_window(np.random.default_rng(seed), n_rows, n_vehicles)
    want = dense_lsrv(plain, ref_plain, window)
    for log, ref in ((packed, ref_packed), (plain, ref_plain), (packed, ref_plain)):
        got = low_speed_region_volume(log, window, reference=ref)
        assert got == pytest.approx(want, rel=1e-12, abs=1e-9, nan_ok=True)


# ------------------------------------------------------------------- deviations
def dense_deviations(
    log: SimulationLog, ref: SimulationLog, window: MetricWindow, rows: slice
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`deviations` by its definition on the (T, N) arrays: VR's counterpart is the
    reference's lane at VR's position, :func:`numpy.interp` (clamped) row by row."""
    keys = window.key_vehicles
    a, v, a_u, v_u = (np.asarray(arr)[rows][:, keys].astype(np.float64)
                      for arr in (log.a, log.v, ref.a, ref.v))  # fmt: skip
    valid = np.asarray(log.active)[rows][:, keys] & np.asarray(ref.active)[rows][:, keys]
    vr = window.vr
    if vr in keys.tolist():
        col = keys.tolist().index(vr)
        valid[:, col] = False
        for k, r in enumerate(range(*rows.indices(log.n_steps))):
            lane = int(log.lane[r, vr])
            if not (log.active[r, vr] and log.t[r] >= window.t_merge - EPS_T) or lane not in (1, 2):
                continue
            on = stable_lane(ref, r, lane)
            if on.size == 0:
                continue
            xp = np.asarray(ref.x)[r, on].astype(np.float64)
            x_vr = float(log.x[r, vr])
            v_lane = np.interp(x_vr, xp, np.asarray(ref.v)[r, on].astype(np.float64))
            if np.isfinite(v_lane):
                v_u[k, col] = v_lane
                a_u[k, col] = np.interp(x_vr, xp, np.asarray(ref.a)[r, on].astype(np.float64))
                valid[k, col] = True
    with np.errstate(invalid="ignore"):
        return a - a_u, v - v_u, valid & np.isfinite(a - a_u) & np.isfinite(v - v_u)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), n_rows=st.integers(1, 30), n_vehicles=st.integers(1, 14))
def test_deviations_follow_their_definition(seed: int, n_rows: int, n_vehicles: int) -> None:
    packed, plain = random_logs(seed, n_rows, n_vehicles)
    ref_packed, ref_plain = random_logs(seed + 1, n_rows, n_vehicles, slots=1)
    rng = np.random.default_rng(seed)
    window = random_window(rng, n_rows, n_vehicles)
    r0 = int(rng.integers(0, n_rows + 1))
    rows = slice(r0, int(rng.integers(r0, n_rows + 1)))
    want = dense_deviations(plain, ref_plain, window, rows)
    for log, ref in ((packed, ref_packed), (plain, ref_plain), (packed, ref_plain)):
        for got, expected in zip(deviations(log, window, ref, rows), want, strict=True):
            same(got, expected)


# ------------------------------------------------------------------- leaders, fuel
def dense_leaders(
    log: SimulationLog, rows: slice, vehicles: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`lane_leaders` by its definition, row by row on the (T, N) arrays: the next
    vehicle of the lane in numpy's stable order of positions (NaN last)."""
    r_idx = list(range(*rows.indices(log.n_steps)))
    leader = np.full((len(r_idx), vehicles.size), -1, dtype=np.int64)
    gap = np.full((len(r_idx), vehicles.size), np.nan)
    for q, r in enumerate(r_idx):
        x = np.asarray(log.x)[r].astype(np.float64)
        for j, i in enumerate(vehicles.tolist()):
            if not log.active[r, i]:
                continue
            order = stable_lane(log, r, int(log.lane[r, i]))
            k = order.tolist().index(i)
            if k + 1 < order.size:
                nxt = int(order[k + 1])
                d = x[nxt] - float(log.length[nxt]) - x[i]
                if np.isfinite(d):
                    leader[q, j], gap[q, j] = nxt, d
    return leader, gap


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), n_rows=st.integers(1, 30), n_vehicles=st.integers(1, 14))
def test_lane_leaders_follow_their_definition(seed: int, n_rows: int, n_vehicles: int) -> None:
    """Ties in position and NaN positions included; any vehicle is a leader, key or not."""
    packed, plain = random_logs(seed, n_rows, n_vehicles, nan_x=0.1)
    rng = np.random.default_rng(seed)
    vehicles = rng.permutation(n_vehicles)[: rng.integers(1, n_vehicles + 1)]
    r0 = int(rng.integers(0, n_rows + 1))
    rows = slice(r0, int(rng.integers(r0, n_rows + 1)))
    want = dense_leaders(plain, rows, vehicles)
    for log in (packed, plain):
        for got, expected in zip(lane_leaders(log, rows, vehicles), want, strict=True):
            same(got, expected)
    for r in range(*rows.indices(n_rows)):  # the follower is the one whose leader it is
        lane_1 = stable_lane(plain, r, 1)
        for i in vehicles.tolist():
            if not plain.active[r, i] or plain.lane[r, i] != 1 or np.isnan(plain.x[r, i]):
                continue
            k = lane_1.tolist().index(i)
            want_f = int(lane_1[k - 1]) if k > 0 else -1
            assert lane_follower(packed, r, i, 1) == lane_follower(plain, r, i, 1) == want_f


def dense_fuel(log: SimulationLog, ref: SimulationLog, window: MetricWindow) -> float:
    """:func:`fuel` by its definition on the (T, N) arrays, vehicle by vehicle [L]."""
    if window.group and not window.merged:
        return math.nan
    rows = list(range(*window_rows(log, window).indices(log.n_steps)))
    x, v, a = (np.asarray(getattr(log, n)).astype(np.float64) for n in "xva")
    act, act_u = np.asarray(log.active), np.asarray(ref.active)
    x_u, v_u = np.asarray(ref.x).astype(np.float64), np.asarray(ref.v).astype(np.float64)
    road_end = road_of(log).length

    def cruise(rest: float, speed: float) -> float:
        speed = max(speed, 1.0)
        return float(fuel_rate(speed, 0.0)) * rest / speed if rest > 0 else 0.0

    total = 0.0
    for i in range(log.n_vehicles):
        on_u = [r for r in rows if act_u[r, i]]
        on = [r for r in rows if act[r, i]]
        distance = float(x_u[on_u[-1], i]) - float(x_u[on_u[0], i]) if on_u else math.nan
        if not on:
            total += cruise(distance, float(v_u[on_u[0], i])) if on_u else 0.0
            continue
        x0 = x[on[0], i]
        target = distance if on_u else road_end - x0
        spent = 0.0
        for j, r in enumerate(on):
            covered = x[r, i] - x0
            if covered >= target:
                break
            if j + 1 == len(on):
                spent += cruise(target - covered, v[r, i])
                break
            rate = float(fuel_rate(v[r, i], a[r, i])) * log.dt
            step = x[on[j + 1], i] - x[r, i]
            if covered + step >= target:
                spent += rate * (target - covered) / step
                break
            spent += rate
        total += spent
    return total / 1000.0


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), n_rows=st.integers(1, 30), n_vehicles=st.integers(0, 14))
def test_fuel_follows_its_definition(seed: int, n_rows: int, n_vehicles: int) -> None:
    packed, plain = random_logs(seed, n_rows, n_vehicles)
    ref_packed, ref_plain = random_logs(seed + 1, n_rows, n_vehicles, slots=1)
    window = random_window(np.random.default_rng(seed), n_rows, n_vehicles)
    want = dense_fuel(plain, ref_plain, window)
    for log, ref in ((packed, ref_packed), (plain, ref_plain), (packed, ref_plain)):
        got = fuel(log, window, reference=ref)
        assert got == pytest.approx(want, rel=1e-12, abs=1e-15, nan_ok=True)


# ------------------------------------------------------------------- shared tables
@pytest.mark.parametrize("seed", range(12))
def test_compute_metrics_gives_what_each_metric_function_returns(seed: int) -> None:
    """Metrics computed from shared tables equal their functions' values exactly, on the
    slot-column log and its one-column-per-vehicle twin alike."""
    rng = np.random.default_rng(seed)
    n_rows, n_vehicles = int(rng.integers(1, 40)), int(rng.integers(1, 14))
    packed, plain = random_logs(seed, n_rows, n_vehicles)
    ref_packed, _ = random_logs(seed + 1, n_rows, n_vehicles, slots=1)
    window = random_window(rng, n_rows, n_vehicles)
    for reference in (ref_packed, None):
        values = compute_metrics(packed, window, reference=reference)
        twin = compute_metrics(plain, window, reference=reference)
        same([values[name] for name in METRICS], [twin[name] for name in METRICS])
        for name in OUTCOME_FIELDS:
            same(values[name], twin[name])
        for name, spec in METRICS.items():
            kwargs = {"reference": reference} if spec.needs_reference else {}
            same(values[name], float(spec.func(packed, window, **kwargs)))
        shared = {**disturbance_metrics(packed, window, reference),
                  **closing_metrics(packed, window)}  # fmt: skip
        for func, value in shared.items():
            same(value, values[next(n for n, s in METRICS.items() if s.func is func)])


@pytest.mark.parametrize("slots", [None, 2])
def test_empty_logs_and_windows(slots: int | None) -> None:
    """No row logged, no vehicle on the road in the window, a window without times: the
    kernels see empty rosters and row ranges."""
    size = {"kind": np.zeros(3, dtype=int), "length": np.full(3, 5.0), "width": np.full(3, 2.0)}
    log = SimulationLog.allocate(4, 3, dt=DT, slots=slots, meta={"config": _config()}, **size)
    empty = MetricWindow(group={}, t_start=math.nan, t_merge=math.nan, t_end=math.nan)
    group = dict(zip(KEY_ROLES, [0, 1, 2, -1, -1, -1], strict=True))
    unlogged = MetricWindow(group=group, t_start=0.0, t_merge=0.0, t_end=0.3)
    for window in (empty, unlogged):
        assert np.isnan(lane_speed_field(log, window, lane=1)[2]).all()
        assert fuel(log, window, reference=log) == 0.0
        assert low_speed_region_volume(log, window, reference=log) == 0.0
    da, dv, valid = deviations(log, unlogged, log, slice(0, 0))
    assert da.shape == dv.shape == valid.shape == (0, 3)
    values = compute_metrics(log, unlogged, reference=log)
    assert math.isnan(values["average_acceleration"])  # no valid cell
    assert values["fuel"] == values["lsrv"] == 0.0
