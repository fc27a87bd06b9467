"""The merge metrics measure what the paper's metrics mean, on hand-built logs with closed-form
answers: stabilisation is the final settling on a common clock, the integrated disturbance
needs no clock, the critical distance is kept to the actual leader, U_safe is Eq. 15 at the
merge, LSRV weighs each vehicle against itself, fuel is counted over a common distance, and a
merge that never happened is an outcome."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_metrics import PLATOON_GROUP, braking, build, cruise, cruising, merge_scene, roles

from hcomc.equations.fuel import fuel_rate
from hcomc.metrics import (
    METRICS,
    MetricWindow,
    compute_metrics,
    critical_distance,
    fuel,
    integrated_disturbance,
    low_speed_region_volume,
    merge_outcome,
    merge_window,
    stabilisation_time,
    stabilisation_time_from_merge,
    u_safe_at_merge,
)
from hcomc.metrics.leaders import lane_follower, lane_leaders
from hcomc.sim.log import EventKind, SimulationLog


def cruise_rate(v: float) -> float:
    """Eq. 16 at constant speed [mL/s]."""
    return float(fuel_rate(v, 0.0))


# ------------------------------------------------------------------- stabilisation time
def test_a_second_disturbance_after_a_quiet_spell_counts() -> None:
    """Vehicle 2 brakes (logged a = -1 m/s²) for t in [5, 5.5) and again in [10, 11); the
    merge is at t = 5 s. Settled for good from t = 11 s: 11 s after VR's entry at t = 0, 6 s
    after the merge (the first quiet 2 s after the merge would say 0.5 s)."""
    log = braking(a_rows=[*range(50, 55), *range(100, 110)], slows=False)
    w = merge_window(log, 0, PLATOON_GROUP)
    assert (w.t_start, w.t_merge) == (0.0, 5.0)
    assert stabilisation_time(log, w, reference=cruising()) == pytest.approx(11.0)
    assert stabilisation_time_from_merge(log, w, reference=cruising()) == pytest.approx(
        6.0, abs=1e-9
    )


def test_braking_before_the_merge_counts_from_entry() -> None:
    """Vehicle 2 brakes for t in [1, 3), before the merge at t = 5 s: 3 s from VR's entry
    into the control zone, but nothing to settle after the merge."""
    log = braking(a_rows=range(10, 30), slows=False)
    w = merge_window(log, 0, PLATOON_GROUP)
    assert stabilisation_time(log, w, reference=cruising()) == pytest.approx(3.0)
    assert stabilisation_time_from_merge(log, w, reference=cruising()) == 0.0


@pytest.mark.parametrize("t_merge", [3.0, 5.0, 9.0])
def test_the_entry_clock_does_not_reward_a_late_merge(t_merge: float) -> None:
    """The traffic settles for good at t = 12 s (vehicle 2 brakes for t in [5, 12)) whatever
    the merge time: from VR's entry that is 12 s for every controller; from the merge it is
    12 - t_merge, shorter the later VR merges."""
    log = braking(a_rows=range(50, 120), slows=False)
    w = MetricWindow(group=PLATOON_GROUP, t_start=0.0, t_merge=t_merge, t_end=15.0)
    assert stabilisation_time(log, w, reference=cruising()) == pytest.approx(12.0)
    assert stabilisation_time_from_merge(log, w, reference=cruising()) == pytest.approx(
        12.0 - t_merge
    )


@pytest.mark.parametrize(
    ("last_row", "after_entry", "after_merge"),
    [
        (129, 13.0, 8.0),  # settled from t = 13 s: the 2 s hold ends exactly at t_end = 15 s
        (135, 15.0, 10.0),  # settled from 13.6 s: 1.4 s observed, censored at the window end
        (150, 15.0, 10.0),  # unsettled in the last row: censored
    ],
)
def test_a_short_settled_tail_is_censored(
    last_row: int, after_entry: float, after_merge: float
) -> None:
    log = braking(a_rows=range(50, last_row + 1), slows=False)
    w = merge_window(log, 0, PLATOON_GROUP)
    assert stabilisation_time(log, w, reference=cruising()) == pytest.approx(after_entry)
    assert stabilisation_time_from_merge(log, w, reference=cruising()) == pytest.approx(after_merge)


# ------------------------------------------------------------------- integrated disturbance
def test_integrated_disturbance_is_the_hand_integral() -> None:
    """Against the cruising platoon (25 m/s), merge at t = 5 s, log every 0.1 s: vehicle 3 (VMR)
    drives 2 m/s too fast for t in [5, 8) (∫ |dv| dt = 2 x 3 = 6 m, the sign does not matter);
    VR (0) 1 m/s too slow for t in [0, 7), of which only [5, 7) counts, from its merge on
    (1 x 2 = 2 m). Its counterpart is the undisturbed lane at its position: the reference's
    own vehicle 0, there at 25 m/s."""
    log, ref = cruising(), cruising()
    t = np.arange(151) * 0.1
    log.v[(t > 5.0 - 1e-9) & (t < 8.0 - 1e-9), 3] = 27.0
    log.v[t < 7.0 - 1e-9, 0] = 24.0
    w = merge_window(log, 0, PLATOON_GROUP)
    assert integrated_disturbance(log, w, reference=ref) == pytest.approx(6.0 + 2.0)
    # a non-key vehicle's deviation does not count
    log.v[:, 7] = 20.0
    assert integrated_disturbance(log, w, reference=ref) == pytest.approx(8.0)
    # no undisturbed run, no merge: NaN; no ramp vehicle: 0
    assert math.isnan(integrated_disturbance(log, w))
    never = MetricWindow(group=PLATOON_GROUP, t_start=0.0, t_merge=math.nan, t_end=15.0)
    assert math.isnan(integrated_disturbance(log, never, reference=ref))
    nobody = MetricWindow(group={}, t_start=0.0, t_merge=math.nan, t_end=15.0)
    assert integrated_disturbance(log, nobody, reference=ref) == 0.0


def test_integrated_disturbance_of_a_ramp_of_speed() -> None:
    """:func:`braking`: vehicle 2 slows from 25 m/s by 1 m/s² for t in [5, 8), then cruises
    3 m/s slow. Deficit s(t) = clip(t - 5, 0, 3); the rectangle rule over the rows t = 0.1 k,
    k = 0 .. 150: 0.1 x (0.1 x (0 + 1 + ... + 30) + 70 x 3) = 25.65 m (the integral over
    [0, 15] is 25.5 m; the rows each stand for 0.1 s)."""
    log = braking()
    w = merge_window(log, 0, PLATOON_GROUP)
    assert integrated_disturbance(log, w, reference=cruising()) == pytest.approx(25.65, rel=1e-5)


# ------------------------------------------------------------------- critical distance
def test_a_non_key_vehicle_between_key_vehicles_sets_the_critical_distance() -> None:
    """Lane 1 at t: VMC (1) 540 + 20 t, a non-key vehicle (6) 560 + 20 t, VMF (2) 600 + 20 t;
    VR (0) merges at t = 1 s into lane 1 at 640 + 20 t. Lane 2: VNR (5) 520 + 20 t and a
    non-key vehicle (7) 527 + 20 t. The key pair VMC -> VMF is 55 m apart, but VMC keeps
    15 m to vehicle 6 and VNR only 2 m to vehicle 7."""
    t = np.arange(21) * 0.1
    x, v = cruise([640.0, 540.0, 600.0, 0.0, 0.0, 520.0, 560.0, 527.0], [20.0] * 8, t)
    lane = np.array([1, 1, 1, 1, 2, 2, 1, 2])[None].repeat(t.size, axis=0)
    lane[:10, 0] = 0
    active = np.ones(x.shape, dtype=bool)
    active[:, [3, 4]] = False  # VMR and VNF missing
    log = build(x, v, lane, active=active)
    log.add_event(1.0, EventKind.MERGE, 0)
    w = merge_window(log, 0, roles(0, 1, 2, -1, -1, 5))
    assert critical_distance(log, w) == pytest.approx(2.0, abs=1e-4)
    leader, gap = lane_leaders(log, slice(10, 12), w.key_vehicles)  # keys 0, 1, 2, 5
    assert leader.tolist() == [[-1, 6, 0, 7]] * 2
    np.testing.assert_allclose(gap[0], [np.nan, 15.0, 35.0, 2.0], atol=1e-4)
    # without vehicle 7 the smallest gap is VMC's 15 m to vehicle 6
    log.active[:, 7] = False
    assert critical_distance(log, w) == pytest.approx(15.0, abs=1e-4)


def test_overlapping_vehicles_are_leader_and_follower() -> None:
    """Two lane-1 vehicles at the same position: the later one in vehicle order leads, with a
    negative gap (the overlap), instead of both skipping to the vehicle ahead."""
    t = np.arange(3) * 0.1
    x, v = cruise([600.0, 600.0, 650.0], [20.0] * 3, t)
    log = build(x, v, np.ones(x.shape, dtype=np.int64))
    leader, gap = lane_leaders(log, slice(0, 3), np.array([0, 1]))
    assert leader.tolist() == [[1, 2]] * 3
    np.testing.assert_allclose(gap, [[-5.0, 45.0]] * 3)
    assert lane_follower(log, 0, 1, 1) == 0
    assert lane_follower(log, 0, 0, 1) == -1


# ------------------------------------------------------------------- U_safe at the merge
def eq15(d: float, v_r: float, v_f: float, delay: float) -> float:
    """Eq. 15 by hand with the C1 control table: D = 2 m, a_merg = 7.5 m/s²."""
    return v_r**2 / (2.0 * (d - 2.0 - v_r * delay + v_f**2 / (2.0 * 7.5)))


def test_u_safe_at_merge_is_eq15_of_vrs_new_follower() -> None:
    """:func:`merge_scene` at the MERGE row (t = 1.5 s): lane 1 holds VMR (3) at 730 m, VMC
    (1) at 760 m, VR (0) at 790 m, VMF (2) at 850 m, all at 20 m/s. VR's new follower is VMC,
    25 m behind VR's rear."""
    log = merge_scene()
    w = merge_window(log, 0, roles(0, 1, 2, 3, 4, 5))
    assert u_safe_at_merge(log, w) == pytest.approx(eq15(25.0, 20.0, 20.0, 0.5))  # a CAV
    log.kind[1] = 0  # an HDV follower reacts later: T = 1 s
    assert u_safe_at_merge(log, w) == pytest.approx(eq15(25.0, 20.0, 20.0, 1.0))
    # the follower's speed is v_r, VR's v_f
    log.v[15, 1], log.v[15, 0] = 24.0, 18.0
    assert u_safe_at_merge(log, w) == pytest.approx(eq15(25.0, 24.0, 18.0, 1.0))
    # the follower need not be a key vehicle
    assert u_safe_at_merge(log, merge_window(log, 0, roles(0))) == pytest.approx(
        eq15(25.0, 24.0, 18.0, 1.0)
    )
    # no deceleration avoids the crash: infinite
    log.x[15, 1] = 783.0  # 2 m gap: 2 - 2 - 24 + 21.6 < 0
    assert u_safe_at_merge(log, w) == np.inf


def test_u_safe_at_merge_needs_a_merge_and_a_follower() -> None:
    log = merge_scene()
    w = merge_window(log, 0, roles(0, 1, 2, 3, 4, 5))
    no_merge = MetricWindow(group=w.group, t_start=0.0, t_merge=math.nan, t_end=4.0)
    assert math.isnan(u_safe_at_merge(log, no_merge))
    late = MetricWindow(group=w.group, t_start=0.0, t_merge=4.5, t_end=4.0)
    assert math.isnan(u_safe_at_merge(log, late))  # merged after the last row
    log.active[:, [1, 3]] = False  # nobody behind VR in lane 1 (lane 2's 5 does not count)
    assert math.isnan(u_safe_at_merge(log, w))


# ------------------------------------------------------------------- LSRV
def standing(xs: list[float], lanes: list[int], speeds: np.ndarray) -> SimulationLog:
    """Vehicles standing at ``xs`` in ``lanes`` whose logged speeds are the rows of
    ``speeds`` (rows every 0.1 s)."""
    x = np.broadcast_to(np.asarray(xs, dtype=float), speeds.shape).copy()
    lane = np.broadcast_to(np.asarray(lanes), speeds.shape).copy()
    return build(x, speeds.astype(float), lane)


# Lane 1: vehicles 0-4 at 420, 430, 440, 740 and 1040 m (gaps of 10 m around vehicle 1,
# of 300 m around vehicle 3); VR (5) waits on the ramp. Merge area 400-1500 m: lane 1's mean
# spacing is 1100 / 5 = 220 m.
GAPS_X = [420.0, 430.0, 440.0, 740.0, 1040.0, 800.0]
GAPS_LANE = [1, 1, 1, 1, 1, 0]
GAPS_WINDOW = MetricWindow(group=roles(5, 0), t_start=0.0, t_merge=1.0, t_end=4.0)


@pytest.mark.parametrize("slow", [1, 3])
def test_lsrv_of_a_vehicle_does_not_depend_on_its_gaps(slow: int) -> None:
    """One vehicle 5 m/s below its undisturbed 25 m/s for 1 s scores 5 x 1 x 220 = 1100 m²,
    inside a 20 m gap as inside a 600 m one (interpolating the speed between vehicles made
    it 50 and 1500 m²)."""
    speeds = np.full((41, 6), 25.0)
    speeds[10:20, slow] = 20.0
    log = standing(GAPS_X, GAPS_LANE, speeds)
    ref = standing(GAPS_X, GAPS_LANE, np.full((41, 6), 25.0))
    assert low_speed_region_volume(log, GAPS_WINDOW, reference=ref) == pytest.approx(1100.0)


def test_lsrv_compares_each_vehicle_with_itself() -> None:
    """Undisturbed, vehicle 0 drives 30 m/s at 500 m and vehicle 1 20 m/s at 1000 m; in the
    factual run vehicle 1 is at 600 m, at its own undisturbed speed: no low-speed region
    (a space-time field would compare vehicle 1 with the undisturbed vehicle 0 nearby)."""
    speeds = np.broadcast_to([30.0, 20.0, 25.0], (41, 3))
    ref = standing([500.0, 1000.0, 800.0], [1, 1, 0], speeds)
    log = standing([500.0, 600.0, 800.0], [1, 1, 0], speeds)
    w = MetricWindow(group=roles(2), t_start=0.0, t_merge=1.0, t_end=4.0)
    assert low_speed_region_volume(log, w, reference=ref) == 0.0


def test_lsrv_spacing_is_the_lanes_mean_undisturbed_spacing() -> None:
    """Undisturbed lane 2 holds vehicles 0 and 1 in the merge area in every row, vehicle 2 in
    the second half of the rows only (it stands upstream at 300 m before: not in the area),
    so 2.5 vehicles on average: spacing 1100 / 2.5 = 440 m. Vehicle 0 is 4 m/s slow for 2 s:
    4 x 2 x 440 = 3520 m². A lane-2 vehicle upstream of the area (3) and the ramp (VR, 4) do
    not count however slow they are."""
    n = 40
    x = np.broadcast_to([600.0, 900.0, 300.0, 350.0, 800.0], (n, 5)).copy()
    x[n // 2 :, 2] = 1200.0
    lane = np.broadcast_to([2, 2, 2, 2, 0], (n, 5)).copy()
    ref = build(x, np.full((n, 5), 25.0), lane)
    speeds = np.full((n, 5), 25.0)
    speeds[5:25, 0] = 21.0
    speeds[:, 3:] = 5.0
    log = build(x, speeds, lane)
    w = MetricWindow(group=roles(4), t_start=0.0, t_merge=0.5, t_end=3.9)
    assert low_speed_region_volume(log, w, reference=ref) == pytest.approx(3520.0)


def test_lsrv_counts_vr_from_its_merge_against_the_undisturbed_lane() -> None:
    """VR (2) drives 20 m/s in lane 1 between vehicles 0 (30 m/s at 500 m) and 1 (30 m/s at
    1000 m), which drive the same undisturbed: VR's counterpart is 30 m/s there, and it counts
    from its merge at t = 2 s on (rows 20-40, 21 rows x 0.1 s): 10 x 2.1 x (1100 / 2) m²."""
    speeds = np.broadcast_to([30.0, 30.0, 20.0], (41, 3)).copy()
    lane = [1, 1, 1]
    log = standing([500.0, 1000.0, 700.0], lane, speeds)
    active = np.ones((41, 3), dtype=bool)
    active[:, 2] = False  # the undisturbed run never releases VR
    x = np.broadcast_to([500.0, 1000.0, 700.0], (41, 3))
    ref = build(x, speeds, np.broadcast_to(lane, (41, 3)).copy(), active=active)
    w = MetricWindow(group=roles(2, 0), t_start=0.0, t_merge=2.0, t_end=4.0)
    assert low_speed_region_volume(log, w, reference=ref) == pytest.approx(10 * 2.1 * 550.0)


# ------------------------------------------------------------------- fuel
def cruising_log(
    x0: list[float], v: list[float], active: np.ndarray | None = None
) -> SimulationLog:
    """Vehicles cruising in lane 1 from ``x0`` at speeds ``v`` for 10 s (101 rows)."""
    t = np.arange(101) * 0.1
    x, speed = cruise(x0, v, t)
    return build(x, speed, np.ones(x.shape, dtype=int), active=active)


NO_RAMP = MetricWindow(group={}, t_start=0.0, t_merge=math.nan, t_end=10.0)


@pytest.mark.parametrize("v", [20.0, 25.0, 30.0])
def test_fuel_is_counted_over_the_undisturbed_distance(v: float) -> None:
    """Undisturbed, vehicle 1 drives 25 m/s for 10 s: 250 m. Whatever its factual constant
    speed v, its fuel is that of 250 m at v, f(v) 250 / v: slower, it burns the rest of the
    way at its cruise rate after the window; faster, it is done before the window ends.
    Vehicle 0 drives 25 m/s in both runs: f(25) 250 / 25."""
    ref = cruising_log([500.0, 600.0], [25.0, 25.0])
    log = cruising_log([500.0, 600.0], [25.0, v])
    expected = (cruise_rate(25.0) * 10.0 + cruise_rate(v) * 250.0 / v) / 1000.0
    assert fuel(log, NO_RAMP, reference=ref) == pytest.approx(expected, rel=1e-6)


def test_vr_burns_fuel_to_the_road_end() -> None:
    """VR (1) is not in the undisturbed run: it is measured from its position at the window
    start to the road end (1500 m), at 20 m/s 1100 m: f(20) 1100 / 20, finished at cruise
    after the window; a VR that reaches the road end inside the window (from 1300 m at
    25 m/s) burns f(25) 200 / 25. Vehicle 0: f(25) 250 / 25."""
    gone = np.ones((101, 2), dtype=bool)
    gone[:, 1] = False
    for x_vr, v_vr, litres in ((400.0, 20.0, cruise_rate(20.0) * 55.0),
                               (1300.0, 25.0, cruise_rate(25.0) * 8.0)):  # fmt: skip
        log = cruising_log([500.0, x_vr], [25.0, v_vr])
        ref = cruising_log([500.0, x_vr], [25.0, v_vr], active=gone)
        w = MetricWindow(group=roles(1, 0), t_start=0.0, t_merge=2.0, t_end=10.0)
        expected = (cruise_rate(25.0) * 10.0 + litres) / 1000.0
        assert fuel(log, w, reference=ref) == pytest.approx(expected, rel=1e-6)


def test_a_vehicle_kept_off_the_road_still_burns_its_distance() -> None:
    """Undisturbed, vehicle 1 enters at t = 5 s at 25 m/s and drives 125 m by the window end;
    in the factual run it never enters: it burns f(25) 125 / 25 nonetheless."""
    late = np.ones((101, 2), dtype=bool)
    late[:50, 1] = False
    never = late.copy()
    never[:, 1] = False
    ref = cruising_log([500.0, -125.0], [25.0, 25.0], active=late)
    log = cruising_log([500.0, -125.0], [25.0, 25.0], active=never)
    expected = (cruise_rate(25.0) * 10.0 + cruise_rate(25.0) * 5.0) / 1000.0
    assert fuel(log, NO_RAMP, reference=ref) == pytest.approx(expected, rel=1e-6)


def test_fuel_needs_the_reference_and_a_merge() -> None:
    log = cruising_log([500.0, 600.0], [25.0, 25.0])
    assert math.isnan(fuel(log, NO_RAMP))
    never = MetricWindow(group=roles(1, 0), t_start=0.0, t_merge=math.nan, t_end=10.0)
    assert math.isnan(fuel(log, never, reference=log))


# ------------------------------------------------------------------- outcome
DISTURBANCE = ("average_acceleration", "stabilisation_time", "stabilisation_time_from_merge",
               "integrated_disturbance", "lsrv", "fuel", "critical_distance", "u_safe_at_merge",
               "pet")  # fmt: skip


def test_a_ramp_vehicle_that_never_merged_is_no_undisturbed_run() -> None:
    """The mainline is undisturbed (the log is its own reference) but VR never merged: no
    disturbance metric may score it as perfect."""
    log = merge_scene()
    group = roles(0, 1, 2, 3, 4, 5)
    w = MetricWindow(group=group, t_start=0.0, t_merge=math.nan, t_end=4.0)
    values = compute_metrics(log, w, reference=log)
    for name in DISTURBANCE:
        assert math.isnan(values[name]), name  # type: ignore[arg-type]
    assert values["merged"] is False
    assert math.isnan(values["merge_time"])  # type: ignore[arg-type]
    assert values["sequence"] == ""
    for name, spec in METRICS.items():  # each function says the same
        kwargs = {"reference": log} if spec.needs_reference else {}
        got = spec.func(log, w, **kwargs)
        assert got == values[name] or (math.isnan(got) and name in DISTURBANCE), name


def test_merge_outcome_of_a_merge() -> None:
    """VR merges at t = 1.5 s, 1.5 s after entering the control zone, ahead of VMC (1) and
    behind VMF (2)."""
    log = merge_scene()
    w = merge_window(log, 0, roles(0, 1, 2, 3, 4, 5))
    outcome = merge_outcome(log, w)
    assert (outcome.merged, outcome.sequence, outcome.ramp_wait) == (True, "ahead", 0.0)
    assert outcome.merge_time == pytest.approx(1.5)
    behind = merge_window(log, 0, roles(0, 2, 1))
    assert merge_outcome(log, behind).sequence == "behind"
    assert merge_outcome(log, merge_window(log, 0, roles(0))).sequence == ""  # no VMC


@pytest.mark.parametrize(("start", "wait"), [(7.5, 4.5), (None, 12.0)])
def test_ramp_wait_runs_from_the_stop_to_the_lane_change(start: float | None, wait: float) -> None:
    """VR (0) stops at the acceleration-lane end at t = 3 s (RAMP_WAIT) and starts its merge
    at t = 7.5 s: 4.5 s of waiting; if it never starts, it waits until the last row (15 s)."""
    log = braking()
    log.add_event(1.0, EventKind.LANE_CHANGE_START, 0)  # before the stop: not the way out
    log.add_event(3.0, EventKind.RAMP_WAIT, 0)
    if start is not None:
        log.add_event(start, EventKind.LANE_CHANGE_START, 0)
    w = merge_window(log, 0, PLATOON_GROUP)
    assert merge_outcome(log, w).ramp_wait == pytest.approx(wait)
    other = merge_window(log, 1, roles(1, 2))
    assert merge_outcome(log, other).ramp_wait == 0.0  # vehicle 1 never waited


def test_runner_reads_the_sequence_from_the_metrics() -> None:
    from hcomc.experiments import results_row
    from hcomc.metrics.outcome import realised_sequence

    assert results_row.realised_sequence is realised_sequence
