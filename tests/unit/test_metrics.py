"""Tests of hcomc.metrics on synthetic logs with hand-computed answers."""

from __future__ import annotations

import copy
import math
from collections.abc import Iterable
from functools import cache
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import load_config
from hcomc.metrics import (
    KEY_ROLES,
    METRICS,
    OUTCOME_FIELDS,
    MetricWindow,
    average_acceleration,
    collisions,
    compute_metrics,
    critical_distance,
    deviations,
    fuel,
    key_collisions,
    key_window,
    lane_speed_field,
    low_speed_region_volume,
    max_drac,
    merge_window,
    min_ttc,
    pet_at_merge,
    reference_speed,
    speed_field,
    stabilisation_time,
    stabilisation_time_from_merge,
)
from hcomc.metrics.speed_field import interp_into, lane_profile_of
from hcomc.sim.log import EventKind, SimulationLog

LENGTH = 5.0  # vehicle length [m]
# C1 road: control zone starts at 700 - 300 = 400 m, road length 1500 m.


@cache
def _config() -> dict[str, Any]:
    return load_config("C1").model_dump(mode="json")


def build(
    x: np.ndarray,
    v: np.ndarray,
    lane: np.ndarray,
    a: np.ndarray | None = None,
    active: np.ndarray | None = None,
    *,
    dt: float = 0.1,
    n_steps: int | None = None,
) -> SimulationLog:
    """A log whose row k is at t = k dt, from (T, N) arrays."""
    n_rows, n = x.shape
    log = SimulationLog.allocate(
        n_rows if n_steps is None else n_steps,
        n,
        dt=dt,
        kind=np.ones(n, dtype=np.int64),
        length=np.full(n, LENGTH),
        width=np.full(n, 1.8),
        meta={"config": copy.deepcopy(_config())},
    )
    a = np.zeros_like(x) if a is None else a
    active = np.ones(x.shape, dtype=bool) if active is None else active
    zeros = np.zeros(n)
    for k in range(n_rows):
        log.record(k, k * dt, x[k], zeros, v[k], a[k], zeros, lane[k], active[k])
    return log


def roles(*idx: int) -> dict[str, int]:
    """Group dict from slots in role order VR, VMC, VMF, VMR, VNF, VNR (missing -> -1)."""
    full = list(idx) + [-1] * (len(KEY_ROLES) - len(idx))
    return dict(zip(KEY_ROLES, full, strict=True))


def cruise(x0: list[float], v0: list[float], t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Constant-speed trajectories: x = x0 + v0 t."""
    x0a, v0a = np.asarray(x0, dtype=float), np.asarray(v0, dtype=float)
    return x0a + np.outer(t, v0a), np.broadcast_to(v0a, (t.size, v0a.size)).copy()


# ------------------------------------------------------------------- scenarios
PLATOON_X0 = [500.0, 530.0, 570.0, 620.0, 680.0, 750.0]  # bumper gaps 25, 35, 45, 55, 65 m
PLATOON_GROUP = roles(0, 1, 2, 3, 4, 5)


def platoon(n_rows: int = 101) -> SimulationLog:
    """Six key vehicles in lane 1 at 25 m/s plus two lane-2 vehicles upstream of x = 400."""
    t = np.arange(n_rows) * 0.1
    x, v = cruise([*PLATOON_X0, 50.0, 100.0], [25.0] * 8, t)
    lane = np.array([1] * 6 + [2, 2])[None].repeat(n_rows, axis=0)
    return build(x, v, lane)


def braking(
    a_rows: Iterable[int] = range(50, 80), n_rows: int = 151, *, slows: bool = True
) -> SimulationLog:
    """The platoon over 15 s; vehicle 2 brakes at -1 m/s^2 for t in [5, 8), then cruises.

    ``a_rows`` are the rows logged with a = -1 m/s^2; with ``slows=False`` only the logged
    acceleration changes, speeds and positions stay those of the cruising platoon.
    """
    t = np.arange(n_rows) * 0.1
    x, v = cruise([*PLATOON_X0, 50.0, 100.0], [25.0] * 8, t)
    s = np.clip(t - 5.0, 0.0, 3.0) if slows else np.zeros_like(t)
    v[:, 2] = 25.0 - s
    x[:, 2] -= s * s / 2 + 3.0 * np.maximum(t - 8.0, 0.0)
    a = np.zeros_like(x)
    a[list(a_rows), 2] = -1.0
    lane = np.array([1] * 6 + [2, 2])[None].repeat(n_rows, axis=0)
    log = build(x, v, lane, a)
    log.add_event(5.0, EventKind.MERGE, 0)
    return log


def merge_scene() -> SimulationLog:
    """VR (0) switches from the ramp to lane 1 at t = 1 s at x_c = 780 m, all at 20 m/s.

    Lane 1: VMR (3) at 700 + 20 t, VMC (1) at 730 + 20 t (VR's new follower), VMF (2) at
    820 + 20 t. Lane 2: VNR (5) at 720 + 20 t, VNF (4) at 755 + 20 t (nearer to x_c than
    VMC, but in the wrong lane). Vehicle 6 is an upstream lane-2 vehicle at 25 m/s.
    """
    t = np.arange(41) * 0.1
    x, v = cruise([760.0, 730.0, 820.0, 700.0, 755.0, 720.0, 100.0], [20.0] * 6 + [25.0], t)
    lane = np.array([1, 1, 1, 1, 2, 2, 2])[None].repeat(t.size, axis=0)
    lane[:10, 0] = 0
    log = build(x, v, lane)
    log.add_event(1.5, EventKind.MERGE, 0, x=790.0)
    return log


# ------------------------------------------------------------------- window
def test_merge_window_picks_control_zone_entry_and_merge_event() -> None:
    n_rows = 150
    t = np.arange(n_rows) * 0.1
    x, v = cruise([301.0, 200.0], [20.0, 25.0], t)
    lane = np.array([0, 1])[None].repeat(n_rows, axis=0)
    active = np.ones((n_rows, 2), dtype=bool)
    active[:3, 0] = False
    x[:3, 0] = 1000.0  # ignored: inactive
    log = build(x, v, lane, active=active, n_steps=200)  # 50 rows never recorded
    log.add_event(3.0, EventKind.MERGE, 1)
    log.add_event(12.3, EventKind.MERGE, 0)
    log.add_event(13.0, EventKind.MERGE, 0)
    w = merge_window(log, 0, roles(0, 1))
    # VR at 301 + 20 t reaches the control-zone start 400 m first at row 50 (x = 401 m).
    assert w.t_start == pytest.approx(5.0)
    assert w.t_merge == pytest.approx(12.3)
    assert w.t_end == pytest.approx(14.9)
    assert w.group == roles(0, 1)
    assert w.key_vehicles.tolist() == [0, 1]
    assert w.merged

    log2 = build(x, v, lane, active=active)
    w2 = merge_window(log2, 0, roles(0, 1))
    assert math.isnan(w2.t_merge)
    assert not w2.merged


def test_metrics_need_road_geometry() -> None:
    log = platoon(3)
    log.meta = {}
    with pytest.raises(ValueError, match="road"):
        merge_window(log, 0, PLATOON_GROUP)


# ------------------------------------------------------------------- platoon
def test_constant_speed_platoon() -> None:
    log = platoon()
    log.add_event(2.0, EventKind.MERGE, 0)
    w = merge_window(log, 0, PLATOON_GROUP)
    assert (w.t_start, w.t_merge, w.t_end) == pytest.approx((0.0, 2.0, 10.0))
    assert reference_speed(log, w) == pytest.approx(25.0)
    # compared with itself (no disturbance) every disturbance metric is exactly 0
    assert average_acceleration(log, w, reference=log) == 0.0
    assert low_speed_region_volume(log, w, reference=log) == 0.0
    assert stabilisation_time(log, w, reference=log) == pytest.approx(0.0, abs=1e-9)
    # without the undisturbed run they are undefined
    assert math.isnan(average_acceleration(log, w))
    assert math.isnan(low_speed_region_volume(log, w))
    assert math.isnan(stabilisation_time(log, w))
    assert math.isnan(fuel(log, w))
    assert critical_distance(log, w) == pytest.approx(25.0, abs=1e-4)
    assert min_ttc(log, w) == math.inf
    assert max_drac(log, w) == 0.0
    assert collisions(log, w) == 0.0
    # Fuel: 8 vehicles, each over the 250 m it covers undisturbed in the 10 s window, at
    # f(25, 0) = 1.23955625 mL/s: 1.23955625 x 250 / 25 mL each.
    assert fuel(log, w, reference=log) == pytest.approx(8 * 10.0 * 1.23955625e-3, rel=1e-6)


def test_missing_roles_are_ignored() -> None:
    log = platoon()
    log.add_event(2.0, EventKind.MERGE, 0)
    # Without vehicle 1 the key vehicles are 0 and 2, but vehicle 1 still drives between
    # them: it is 0's actual leader (gap 530 - 5 - 500 = 25 m), not 2 (65 m); 2's leader is
    # vehicle 3 (620 - 5 - 570 = 45 m).
    w = merge_window(log, 0, roles(0, -1, 2))
    assert critical_distance(log, w) == pytest.approx(25.0, abs=1e-4)
    # Only one key vehicle: its leader still counts.
    assert critical_distance(log, merge_window(log, 0, roles(0))) == pytest.approx(25.0, abs=1e-4)


# ------------------------------------------------------------------- braking
def cruising(n_rows: int = 151) -> SimulationLog:
    """The undisturbed run of :func:`braking`: the same platoon, nobody brakes."""
    return braking(a_rows=[], n_rows=n_rows, slows=False)


def test_braking_against_the_undisturbed_platoon() -> None:
    log, ref = braking(), cruising()
    w = merge_window(log, 0, PLATOON_GROUP)
    assert (w.t_start, w.t_merge, w.t_end) == pytest.approx((0.0, 5.0, 15.0))
    # Vehicle 2 ends 3 m/s below its undisturbed 25 m/s: never back within 0.5 m/s, so the
    # stabilisation time is censored at the window end: 15 s after VR's entry, 10 s after
    # its merge.
    assert stabilisation_time(log, w, reference=ref) == pytest.approx(15.0)
    assert stabilisation_time_from_merge(log, w, reference=ref) == pytest.approx(10.0)
    # 30 cells with |a - 0| = 1. Cells: VMC..VNR 5 x 151 rows, VR (0) only from its merge
    # at t = 5 s: rows 50..150 = 101 cells.
    assert average_acceleration(log, w, reference=ref) == pytest.approx(30.0 / (755 + 101))
    # Vehicle 1 (25 m/s) closes on vehicle 2 (22 m/s); the gap 35 - 4.5 - 3 (t - 8)
    # is smallest at t = 15 s: 9.5 m.
    assert min_ttc(log, w) == pytest.approx(9.5 / 3.0, rel=1e-4)
    assert max_drac(log, w) == pytest.approx(3.0**2 / (2 * 9.5), rel=1e-4)
    assert critical_distance(log, w) == pytest.approx(9.5, abs=1e-3)


def test_stabilisation_needs_the_full_hold() -> None:
    # Speeds undisturbed; |a| = 1 in rows 50-59 and 75-79: settled for 1.5 s (rows 60-74)
    # only, then from t = 8 s on.
    log, ref = braking(a_rows=[*range(50, 60), *range(75, 80)], slows=False), cruising()
    w = merge_window(log, 0, PLATOON_GROUP)
    assert stabilisation_time(log, w, reference=ref) == pytest.approx(8.0, abs=1e-9)
    assert stabilisation_time_from_merge(log, w, reference=ref) == pytest.approx(3.0, abs=1e-9)
    # The 1.5 s quiet spell would meet a 1 s hold, but the braking after it counts: the
    # final settling is at t = 8 s whatever the hold.
    assert stabilisation_time(log, w, reference=ref, hold=1.0) == pytest.approx(8.0, abs=1e-9)
    # A 7.5 s hold no longer fits after t = 8 s: censored at the window end.
    assert stabilisation_time(log, w, reference=ref, hold=7.5) == pytest.approx(15.0)
    assert stabilisation_time_from_merge(log, w, reference=ref, hold=7.5) == pytest.approx(10.0)


def test_stabilisation_speed_criterion() -> None:
    # Vehicle 3 drives 1 m/s slower than undisturbed for t in [5, 9), then 0.4 m/s slower
    # (inside the 0.5 m/s tolerance); accelerations stay undisturbed.
    log, ref = cruising(), cruising()
    t = np.arange(151) * 0.1
    log.v[:, 3] = np.where(t < 9.0 - 1e-9, 24.0, 24.6)
    w = merge_window(log, 0, PLATOON_GROUP)
    assert stabilisation_time(log, w, reference=ref) == pytest.approx(9.0, abs=1e-9)
    assert stabilisation_time_from_merge(log, w, reference=ref) == pytest.approx(4.0, abs=1e-9)
    assert stabilisation_time(log, w, reference=ref, v_tol=1.5) == pytest.approx(0.0, abs=1e-9)
    assert average_acceleration(log, w, reference=ref) == 0.0


def test_stabilisation_is_censored_at_window_end() -> None:
    # Still braking 1.2 s before the end: only 0.8 s of settling is observed.
    log = braking(a_rows=range(50, 142), slows=False)
    w = merge_window(log, 0, PLATOON_GROUP)
    assert stabilisation_time(log, w, reference=cruising()) == pytest.approx(15.0)
    assert stabilisation_time_from_merge(log, w, reference=cruising()) == pytest.approx(10.0)


def test_vr_counterpart_is_the_undisturbed_lane_at_its_position() -> None:
    """VR (0) merges into lane 1 at t = 1 s; the undisturbed run has no VR. Its counterpart
    is the reference's lane-1 traffic interpolated at VR's x (clamped beyond the ends)."""
    t = np.arange(31) * 0.1
    x, v = cruise([600.0, 500.0, 700.0], [20.0, 20.0, 30.0], t)
    a = np.zeros_like(x)
    a[:, 0] = 0.3
    lane = np.broadcast_to([1, 1, 1], x.shape).copy()
    lane[:10, 0] = 0
    log = build(x, v, lane, a)
    log.add_event(1.0, EventKind.MERGE, 0)
    ref_x, ref_v = cruise([500.0, 700.0], [20.0, 30.0], t)
    ref_x = np.concatenate([np.zeros((t.size, 1)), ref_x], axis=1)
    ref_v = np.concatenate([np.zeros((t.size, 1)), ref_v], axis=1)
    ref_a = np.zeros_like(ref_x)
    ref_a[:, 2] = 0.1
    active = np.ones(ref_x.shape, dtype=bool)
    active[:, 0] = False  # no VR in the undisturbed run
    ref = build(ref_x, ref_v, lane, ref_a, active=active)
    w = merge_window(log, 0, roles(0, 1, 2))
    da, dv, valid = deviations(log, w, ref, slice(0, 31))
    assert valid[:, 0].tolist() == [False] * 10 + [True] * 21  # VR from its merge on
    assert valid[:, 1:].all()
    # VR at 600 + 20 t between 500 + 20 t (20 m/s) and 700 + 30 t (30 m/s): weight
    # (100) / (200 + 10 t) of the leader.
    w_lead = 100.0 / (200.0 + 10.0 * t[10:])
    np.testing.assert_allclose(dv[10:, 0], 20.0 - (20.0 + 10.0 * w_lead), rtol=1e-5)
    np.testing.assert_allclose(da[10:, 0], 0.3 - 0.1 * w_lead, rtol=1e-5)
    np.testing.assert_allclose(da[:, 2], -0.1)
    expected = (np.abs(0.3 - 0.1 * w_lead).sum() + 31 * 0.1) / (21 + 2 * 31)
    assert average_acceleration(log, w, reference=ref) == pytest.approx(expected, rel=1e-5)


def test_reference_must_match_the_log() -> None:
    log = platoon()
    w = merge_window(log, 0, PLATOON_GROUP)
    with pytest.raises(ValueError, match="reference log has 51 rows"):
        average_acceleration(log, w, reference=platoon(51))


# ------------------------------------------------------------------- speed field (plots)
def test_speed_field_crawler_one_cell_per_bin() -> None:
    """Log interval = time bin: each row of the crawler is one (t, x) bin."""
    dt, n_rows = 0.5, 21  # t = 0 .. 10 s
    k = np.arange(n_rows)
    x = np.stack([500.0 + 7.5 * (k - 2), 50.0 + 12.5 * k], axis=1)
    v = np.broadcast_to([15.0, 25.0], x.shape).copy()
    lane = np.broadcast_to([1, 2], x.shape).copy()
    active = np.ones(x.shape, dtype=bool)
    active[:, 0] = (k >= 2) & (k <= 11)  # 10 rows
    log = build(x, v, lane, active=active, dt=dt)
    w = MetricWindow(group=roles(0), t_start=0.0, t_merge=math.nan, t_end=10.0)
    assert reference_speed(log, w) == pytest.approx(25.0)
    x_edges, t_edges, V = speed_field(log, w, lane=1)
    np.testing.assert_allclose(x_edges, np.arange(151) * 10.0)
    np.testing.assert_allclose(t_edges, np.arange(22) * 0.5)  # covers [0, t_end + dt)
    assert V.shape == (21, 150)
    filled = np.argwhere(np.isfinite(V))
    expected = [(kk, int((500.0 + 7.5 * (kk - 2)) // 10)) for kk in range(2, 12)]
    assert [tuple(p) for p in filled.tolist()] == expected
    assert np.all(V[np.isfinite(V)] == 15.0)


def test_speed_field_crawler_spans_bins() -> None:
    """15 m/s from x = 500 m at dt = 0.1 s, rows 0-10 (t = 0 .. 1 s): bins (t, x)
    (0-0.5, 500-510) rows 0-4; (0.5-1.0, 500-510) rows 5-6; (0.5-1.0, 510-520) rows 7-9;
    (1.0-1.1, 510-520) row 10, the last time bin 0.1 s wide."""
    t = np.arange(11) * 0.1
    x, v = cruise([500.0, 100.0], [15.0, 25.0], t)
    lane = np.broadcast_to([1, 2], x.shape).copy()
    log = build(x, v, lane)
    w = MetricWindow(group=roles(0), t_start=0.0, t_merge=math.nan, t_end=1.0)
    _, t_edges, V = speed_field(log, w, lane=1)
    np.testing.assert_allclose(t_edges, [0.0, 0.5, 1.0, 1.1])
    assert np.argwhere(np.isfinite(V)).tolist() == [[0, 50], [1, 50], [1, 51], [2, 51]]


def test_speed_field_bin_speed_is_cell_mean() -> None:
    x = np.array([[502.0, 509.0, 100.0]])
    v = np.array([[15.0, 25.0, 25.0]])
    lane = np.array([[1, 1, 2]])
    log = build(x, v, lane, dt=0.5)
    w = MetricWindow(group=roles(0, 1), t_start=0.0, t_merge=math.nan, t_end=0.0)
    assert speed_field(log, w, lane=1)[2][0, 50] == pytest.approx(20.0)


def test_reference_speed_falls_back_to_all_mainline_cells() -> None:
    x = np.array([[502.0, 900.0, 600.0]])
    v = np.array([[15.0, 25.0, 10.0]])
    lane = np.array([[1, 2, 0]])  # the ramp cell does not count
    log = build(x, v, lane)
    w = MetricWindow(group=roles(0), t_start=0.0, t_merge=math.nan, t_end=0.0)
    assert reference_speed(log, w) == pytest.approx(20.0)


# ------------------------------------------------------------------- LSRV
def _static(xs: list[float], lanes: list[int], speeds: np.ndarray, dt: float) -> SimulationLog:
    """Vehicles standing at ``xs`` whose logged speeds are the rows of ``speeds``."""
    x = np.broadcast_to(np.asarray(xs, dtype=float), speeds.shape).copy()
    lane = np.broadcast_to(np.asarray(lanes), speeds.shape).copy()
    return build(x, speeds.astype(float), lane, dt=dt)


def test_lsrv_slow_second_on_the_control_zone() -> None:
    """Lane-1 vehicles at 450 and 1050 m, 5 m/s below their undisturbed 25 m/s for 1 s; VR
    (2) waits on the ramp. Lane 1's mean spacing over the 1100 m merge area: 1100 / 2 =
    550 m. LSRV = 2 vehicles x 5 m/s x 1 s x 550 m = 5500 m²."""
    speeds = np.full((41, 3), 25.0)
    speeds[10:20, :2] = 20.0  # t in [1, 2)
    log = _static([450.0, 1050.0, 800.0], [1, 1, 0], speeds, 0.1)
    ref = _static([450.0, 1050.0, 800.0], [1, 1, 0], np.full((41, 3), 25.0), 0.1)
    w = MetricWindow(group=roles(2, 0), t_start=0.0, t_merge=1.0, t_end=4.0)
    assert low_speed_region_volume(log, w, reference=ref) == pytest.approx(5500.0)
    assert low_speed_region_volume(ref, w, reference=ref) == 0.0
    # faster than undisturbed counts 0
    assert low_speed_region_volume(ref, w, reference=log) == 0.0


def test_lsrv_sums_lanes_each_with_its_spacing() -> None:
    """One 0.5 s row. Lane 1: 450 m at 20 instead of 26 m/s, 1050 m at 26 (2 vehicles:
    spacing 550 m): 6 x 550 x 0.5 = 1650 m². Lane 2: 500 and 700 m at 20 instead of 25 m/s
    and one more lane-2 vehicle at 900 m (3 vehicles: spacing 1100 / 3 m): 2 x 5 x 1100 / 3
    x 0.5 = 5500 / 3 m². Traffic upstream of the control zone (x < 400 m) does not count.
    VR (0) is compared with the undisturbed lane 1 at its position: 26 m/s there too."""
    xs = [450.0, 1050.0, 500.0, 700.0, 900.0, 300.0]
    lanes = [1, 1, 2, 2, 2, 1]
    log = _static(xs, lanes, np.array([[20.0, 26.0, 20.0, 20.0, 25.0, 1.0]]), 0.5)
    ref = _static(xs, lanes, np.array([[26.0, 26.0, 25.0, 25.0, 25.0, 26.0]]), 0.5)
    w = MetricWindow(group=roles(0), t_start=0.0, t_merge=0.0, t_end=0.0)
    assert low_speed_region_volume(log, w, reference=ref) == pytest.approx(1650.0 + 5500 / 3)
    x_edges, t_edges, V = lane_speed_field(log, w, lane=2, x_min=400.0)
    assert x_edges[0] == 400.0
    assert x_edges[-1] == 1500.0
    np.testing.assert_allclose(t_edges, [0.0, 0.5])
    assert np.isfinite(V[0]).sum() == 40


# ------------------------------------------------------------------- TTC, DRAC, crit. dist.
def _pair(v_leader: float, v_follower: float, x_follower: float) -> SimulationLog:
    """Leader VMF (0) at 600 + v_l t and follower VMC (1) in lane 1; VR (2) on the ramp
    between them; a non-key lane-1 vehicle (3) between them too; t = 0 .. 4 s."""
    t = np.arange(41) * 0.1
    x, v = cruise([600.0, x_follower, 560.0, 575.0], [v_leader, v_follower, 20.0, 21.5], t)
    lane = np.broadcast_to([1, 1, 0, 1], x.shape).copy()
    return build(x, v, lane)


def test_ttc_drac_on_closing_pair() -> None:
    # VMC's actual leader is the non-key vehicle 3: gap 575 + 21.5 t - 5 - (545 + 25 t) =
    # 25 - 3.5 t, closing at 3.5 m/s, smallest at t = 4 s (11 m): TTC 11 / 3.5 s, DRAC
    # 3.5² / 22 m/s², and the critical distance 11 m. Vehicle 3 behind VMF (a pair with a key
    # vehicle too): gap 600 + 20 t - 5 - (575 + 21.5 t) = 20 - 1.5 t, 14 m and TTC 9.3 s at
    # t = 4 s, DRAC 1.5² / 28 m/s²: not the extreme. VR (2) on the ramp has no leader.
    log = _pair(20.0, 25.0, 545.0)
    w = MetricWindow(group=roles(2, 1, 0), t_start=0.0, t_merge=2.0, t_end=4.0)
    assert min_ttc(log, w) == pytest.approx(11.0 / 3.5, rel=1e-5)
    assert max_drac(log, w) == pytest.approx(3.5**2 / (2 * 11.0), rel=1e-5)
    assert critical_distance(log, w) == pytest.approx(11.0, abs=1e-4)
    # without vehicle 3 (off the road) the key pair VMC -> VMF: gap 50 - 5 t, 30 m at t = 4 s
    log.active[:, 3] = False
    assert min_ttc(log, w) == pytest.approx(30.0 / 5.0, rel=1e-5)
    assert max_drac(log, w) == pytest.approx(5.0**2 / (2 * 30.0), rel=1e-5)


def test_critical_distance_starts_at_merge() -> None:
    # VMC's actual leader is the non-key vehicle 3: gap 575 + 21.5 t - 5 - (565 + 20 t)
    # = 5 + 1.5 t, so 5 m at t = 0 but 6.5 m at the merge (t = 1 s). The key pair VMC -> VMF
    # (30 + 5 t) opens: no TTC, no DRAC.
    log = _pair(25.0, 20.0, 565.0)
    w = MetricWindow(group=roles(2, 1, 0), t_start=0.0, t_merge=1.0, t_end=4.0)
    assert critical_distance(log, w) == pytest.approx(6.5, abs=1e-4)
    assert min_ttc(log, w) == math.inf
    assert max_drac(log, w) == 0.0
    no_merge = MetricWindow(group=w.group, t_start=0.0, t_merge=math.nan, t_end=4.0)
    assert math.isnan(critical_distance(log, no_merge))


# ------------------------------------------------------------------- PET
def test_pet_at_merge() -> None:
    log = merge_scene()
    group = roles(0, 1, 2, 3, 4, 5)
    w = merge_window(log, 0, group)
    # x_c = 780 m at t = 1 s. VR's rear 755 + 20 t reaches 780 at t = 1.25 s; the
    # follower VMC's front 730 + 20 t at t = 2.5 s.
    assert pet_at_merge(log, w) == pytest.approx(1.25, abs=1e-9)
    # The follower does not have to be a key vehicle.
    assert pet_at_merge(log, merge_window(log, 0, roles(0, -1, 2))) == pytest.approx(1.25)
    # Window ends before the follower reaches x_c; no merge.
    early = MetricWindow(group=group, t_start=0.0, t_merge=1.5, t_end=2.0)
    assert math.isnan(pet_at_merge(log, early))
    no_merge = MetricWindow(group=group, t_start=0.0, t_merge=math.nan, t_end=4.0)
    assert math.isnan(pet_at_merge(log, no_merge))


# ------------------------------------------------------------------- collisions
def test_collisions_counted_only_inside_window() -> None:
    log = platoon()
    log.add_event(0.5, EventKind.COLLISION, 0, other=1)  # before the window
    log.add_event(2.0, EventKind.COLLISION, 0, other=1)  # key
    log.add_event(3.0, EventKind.COLLISION, 6, other=7)  # non-key pair
    log.add_event(5.0, EventKind.COLLISION, 6, other=2)  # key through `other`
    log.add_event(9.5, EventKind.COLLISION, 3, other=4)  # after the window
    log.add_event(4.0, EventKind.MERGE, 0)  # not a collision
    w = MetricWindow(group=PLATOON_GROUP, t_start=1.0, t_merge=4.0, t_end=9.0)
    assert collisions(log, w) == 3.0
    assert key_collisions(log, w) == 2.0


# ------------------------------------------------------------------- registry
def test_registry_specs() -> None:
    expected = {
        "critical_distance": ("m", "larger"),
        "u_safe_at_merge": ("m/s²", "smaller"),
        "average_acceleration": ("m/s²", "smaller"),
        "stabilisation_time": ("s", "smaller"),
        "stabilisation_time_from_merge": ("s", "smaller"),
        "integrated_disturbance": ("m", "smaller"),
        "lsrv": ("m²", "smaller"),
        "fuel": ("L", "smaller"),
        "min_ttc": ("s", "larger"),
        "max_drac": ("m/s²", "smaller"),
        "pet": ("s", "larger"),
        "collisions": ("count", "smaller"),
        "key_collisions": ("count", "smaller"),
    }
    assert {name: (s.unit, s.better) for name, s in METRICS.items()} == expected
    assert all(name == spec.name and spec.description for name, spec in METRICS.items())


def _is_nan(value: object) -> bool:
    return isinstance(value, float) and math.isnan(value)


REFERENCED = {"average_acceleration", "stabilisation_time", "stabilisation_time_from_merge",
              "integrated_disturbance", "lsrv", "fuel"}  # fmt: skip
"""The metrics that compare with the undisturbed run."""


def test_compute_metrics_floats_and_documented_nans() -> None:
    log = merge_scene()
    w = merge_window(log, 0, roles(0, 1, 2, 3, 4, 5))
    values = compute_metrics(log, w, reference=log)
    assert list(values) == [*METRICS, *OUTCOME_FIELDS]
    assert all(type(values[name]) is float for name in METRICS)
    assert not any(math.isnan(values[name]) for name in METRICS)
    for name, spec in METRICS.items():
        kwargs = {"reference": log} if spec.needs_reference else {}
        assert spec.func(log, w, **kwargs) == pytest.approx(values[name])
    assert {name for name, spec in METRICS.items() if spec.needs_reference} == REFERENCED
    # Lane 1: VMR-VMC and VMC-VR gaps 25 m; lane 2: 30 m.
    assert values["critical_distance"] == pytest.approx(25.0, abs=1e-4)
    # VMC (a CAV, T = 0.5 s) 25 m behind VR at the merge row, both at 20 m/s; D = 2 m,
    # a_merg = 7.5 m/s²
    assert values["u_safe_at_merge"] == pytest.approx(20.0**2 / (2 * (25 - 2 - 10 + 20.0**2 / 15)))
    assert values["pet"] == pytest.approx(1.25)
    # compared with itself: no disturbance
    assert values["stabilisation_time"] == 0.0
    assert values["stabilisation_time_from_merge"] == pytest.approx(0.0, abs=1e-9)
    assert values["integrated_disturbance"] == 0.0
    assert values["average_acceleration"] == 0.0
    assert values["lsrv"] == 0.0
    # the key vehicles do not close on each other; the upstream vehicle 6 closes on VNR at
    # 5 m/s: gap 720 + 20 t - 5 - (100 + 25 t) = 615 - 5 t, 595 m at t = 4 s
    assert values["min_ttc"] == pytest.approx(595.0 / 5.0, rel=1e-6)
    assert values["collisions"] == 0.0
    # the outcome: VR merged 1.5 s after its entry, ahead of VMC, without waiting
    assert (values["merged"], values["sequence"], values["ramp_wait"]) == (True, "ahead", 0.0)
    assert values["merge_time"] == pytest.approx(1.5)
    # without the undisturbed run the metrics that compare with it are NaN
    nan = {name for name, val in compute_metrics(log, w).items() if _is_nan(val)}
    assert nan == REFERENCED

    no_merge = MetricWindow(group=w.group, t_start=w.t_start, t_merge=math.nan, t_end=w.t_end)
    values = compute_metrics(log, no_merge, reference=log)
    assert all(type(values[name]) is float for name in METRICS)
    nan = {name for name, val in values.items() if _is_nan(val)}
    assert nan == {*REFERENCED, "critical_distance", "u_safe_at_merge", "pet", "merge_time"}
    assert (values["merged"], values["sequence"]) == (False, "")


def test_key_window_reads_the_engine_key_group() -> None:
    log = merge_scene()
    log.meta["key_groups"] = [{"t": 0.0, **roles(0, 1, 2, 3, 4, 5)}]
    w = key_window(log)
    assert w == merge_window(log, 0, roles(0, 1, 2, 3, 4, 5))
    assert compute_metrics(log, reference=log) == compute_metrics(log, w, reference=log)


def test_run_without_ramp_vehicle_scores_zero_disturbance() -> None:
    log = platoon()  # no key group recorded: nothing merges
    w = key_window(log)
    assert w.group == {}
    assert (w.t_start, w.t_end) == (0.0, 10.0)
    assert not w.merged
    values = compute_metrics(log, reference=log)
    for name in ("average_acceleration", "stabilisation_time", "stabilisation_time_from_merge",
                 "integrated_disturbance", "lsrv"):  # fmt: skip
        assert values[name] == 0.0, name
    # every vehicle over the 250 m it covers in the 10 s, at 25 m/s
    assert values["fuel"] == pytest.approx(8 * 10.0 * 1.23955625e-3, rel=1e-6)
    assert (values["merged"], values["sequence"]) == (False, "")
    assert math.isnan(values["merge_time"])
    assert math.isnan(values["ramp_wait"])


# ------------------------------------------------------------- lane profile (compiled)
_coords = st.floats(-50.0, 50.0, allow_nan=False).map(lambda v: round(v, 1))  # many ties


@settings(max_examples=300, deadline=None)
@given(
    xp=st.lists(_coords, min_size=1, max_size=12).map(sorted),
    fp=st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=12, max_size=12),
    x=st.lists(st.one_of(_coords, st.just(math.nan)), min_size=1, max_size=20),
    clamp=st.booleans(),
)
def test_interp_into_is_numpy_interp_bit_for_bit(
    xp: list[float], fp: list[float], x: list[float], clamp: bool
) -> None:
    """Knots with ties, queries on knots, outside the range and NaN: the compiled
    interpolation the lane profiles use gives numpy's values exactly."""
    xp_a, fp_a, x_a = np.array(xp), np.array(fp[: len(xp)]), np.array(x)
    left, right = (fp_a[0], fp_a[-1]) if clamp else (math.nan, math.nan)
    out = np.empty(x_a.size)
    interp_into(x_a, xp_a, fp_a, left, right, out)
    np.testing.assert_array_equal(out, np.interp(x_a, xp_a, fp_a, left=left, right=right))


@settings(max_examples=200, deadline=None)
@given(
    x=st.lists(st.integers(0, 40).map(float), min_size=1, max_size=15),
    data=st.data(),
)
def test_lane_profile_is_numpys_interpolation_between_the_lanes_vehicles(
    x: list[float], data: st.DataObject
) -> None:
    """One row of float32 cells: the profile equals np.interp over the active vehicles of the
    lane, sorted stably by position (the definition, written in numpy)."""
    n = len(x)
    active = np.array(data.draw(st.lists(st.booleans(), min_size=n, max_size=n)))
    lanes = np.array(data.draw(st.lists(st.integers(0, 2), min_size=n, max_size=n)), np.int8)
    v = np.array(data.draw(st.lists(st.floats(0, 40, width=32), min_size=n, max_size=n)),
                 dtype=np.float32)  # fmt: skip
    xs = np.array(x, dtype=np.float32)
    at = np.linspace(-5.0, 45.0, 23)
    for clamp in (False, True):
        (got,) = lane_profile_of(xs, active, lanes, 1, at, clamp, v)
        on = np.flatnonzero(active & (lanes == 1))
        if on.size == 0:
            assert np.isnan(got).all()
            continue
        order = np.argsort(xs[on].astype(np.float64), kind="stable")
        xp, fp = xs[on].astype(np.float64)[order], v[on].astype(np.float64)[order]
        edge = {} if clamp else {"left": math.nan, "right": math.nan}
        np.testing.assert_array_equal(got, np.interp(at, xp, fp, **edge))
