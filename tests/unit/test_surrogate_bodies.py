"""PET, least TTC and largest DRAC follow the vehicles' bodies through lane changes, on
hand-built logs with closed-form answers (hcomc.metrics.surrogate), and the pairs they read
against their definition on random logs (hcomc.metrics.bodies).

Road of preset C1: lane width W = 3.75 m, lane centres y = -W (ramp), 0 (lane 1), W (lane 2);
every vehicle 5 m long and 1.8 m wide, so a body overlaps a lane while
``abs(y - y_lane) < (3.75 + 1.8) / 2 = 2.775 m``. Rows every 0.1 s for t = 0 .. 4 s.
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Iterable
from functools import cache
from typing import Any

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.metrics import KEY_ROLES, MetricWindow, max_drac, min_ttc, pet_at_merge
from hcomc.metrics.bodies import body_pairs
from hcomc.metrics.surrogate import closing_metrics
from hcomc.sim.log import EventKind, SimulationLog

W = 3.75  # lane width of C1 [m]
T = np.arange(41) * 0.1  # row times [s]


@cache
def _config() -> dict[str, Any]:
    return load_config("C1").model_dump(mode="json")


def roles(*idx: int) -> dict[str, int]:
    """Group dict from slots in role order VR, VMC, VMF, VMR, VNF, VNR (missing -> -1)."""
    full = list(idx) + [-1] * (len(KEY_ROLES) - len(idx))
    return dict(zip(KEY_ROLES, full, strict=True))


def lane_of(y: np.ndarray) -> np.ndarray:
    """The logged lane of a lateral position: the nearest centre line (a changer's logged
    lane switches at the lane line, the middle of its change)."""
    return np.rint(y / W).astype(int) + 1


def build(
    x0: list[float], v0: list[float], y: list[np.ndarray | float], *,
    changes: Iterable[tuple[int, float, float, int]] = (), slots: int | None = None,
) -> SimulationLog:  # fmt: skip
    """Constant-speed vehicles x = x0 + v0 t with lateral positions ``y`` (a constant or one
    value per row), logged lane from y; ``changes``: (vehicle, t_start, t_end, target) lane
    changes (``t_end`` NaN: still changing at the end of the log)."""
    n = len(x0)
    x = np.asarray(x0, dtype=float) + np.outer(T, v0)
    v = np.broadcast_to(np.asarray(v0, dtype=float), x.shape)
    ys = np.stack([np.broadcast_to(np.asarray(yi, dtype=float), T.shape) for yi in y], axis=1)
    lane = lane_of(ys)
    log = SimulationLog.allocate(
        T.size, n, dt=0.1, kind=np.ones(n, dtype=np.int64), length=np.full(n, 5.0),
        width=np.full(n, 1.8), meta={"config": copy.deepcopy(_config())}, slots=slots,
    )  # fmt: skip
    zeros, on = np.zeros(n), np.ones(n, dtype=bool)
    for k, t in enumerate(T):
        log.record(k, float(t), x[k], ys[k], v[k], zeros, zeros, lane[k], on)
    for i, t_s, t_e, target in changes:
        log.add_event(t_s, EventKind.LANE_CHANGE_START, i, x=float(x[0, i]), value=target)
        if math.isfinite(t_e):
            log.add_event(t_e, EventKind.LANE_CHANGE_END, i, value=target)
    return log


def ramp(t_s: float, y0: float, y1: float, duration: float = 3.0) -> np.ndarray:
    """Lateral position of a change from y0 to y1, linear over [t_s, t_s + duration]."""
    s = np.clip((T - t_s) / duration, 0.0, 1.0)
    return y0 + (y1 - y0) * s


# ------------------------------------------------------------------- PET
# VR (0) at 760 + 20 t: on the ramp (y = -W) until t = 1 s, in lane 1 from then on, so the
# merge point is x_c = 780 m (row 10) and VR's rear 755 + 20 t clears it at t = 1.25 s.
# Vehicle 1 drives in lane 1 at 730 + 20 t: it passes x_c at t = 2.5 s, PET 1.25 s.
VR_Y = np.where(T < 1.0 - 1e-9, -W, 0.0)
X0, V0 = [760.0, 730.0], [20.0, 20.0]
PET_WINDOW = MetricWindow(group=roles(0, 1), t_start=0.0, t_merge=1.5, t_end=4.0)


@pytest.mark.parametrize("slots", [None, 2])
def test_a_vehicle_changing_away_from_vrs_lane_is_not_the_follower(slots: int | None) -> None:
    """Vehicle 2 at 750 + 20 t changes from lane 1 to lane 2 over t = 0.5 .. 3.5 s; it is
    VR's nearest lane-1 vehicle behind x_c at t = 1 s (y = 0.625 m) and passes x_c at
    t = 1.5 s still logged in lane 1 (y = 1.25 m): by logged lane PET would be 0.25 s. It
    heads for lane 2, so the PET is vehicle 1's, 1.25 s; alone, it leaves no PET."""
    away = [(2, 0.5, 3.5, 2)]
    log = build([*X0, 750.0], [*V0, 20.0], [VR_Y, 0.0, ramp(0.5, 0.0, W)], changes=away,
                slots=slots)  # fmt: skip
    assert log.lane[15, 2] == 1  # logged in lane 1 when it passes x_c
    assert pet_at_merge(log, PET_WINDOW) == pytest.approx(1.25, abs=1e-6)
    alone = build([760.0, 750.0], [20.0, 20.0], [VR_Y, ramp(0.5, 0.0, W)],
                  changes=[(1, 0.5, 3.5, 2)], slots=slots)  # fmt: skip
    assert math.isnan(pet_at_merge(alone, PET_WINDOW))


@pytest.mark.parametrize("slots", [None, 2])
def test_a_vehicle_changing_into_vrs_lane_counts_once_its_body_is_in_it(
    slots: int | None,
) -> None:
    """Vehicle 2 at 740 + 20 t changes from lane 2 to lane 1 and passes x_c at t = 2 s.
    Starting at t = 0.5 s its body is at y = 1.875 m then, in lane 1: PET = 2 - 1.25 =
    0.75 s (logged in lane 2 at t = 1 s, the logged-lane follower was vehicle 1: 1.25 s).
    Starting at t = 1.9 s it is at y = 3.625 m, not yet in lane 1: vehicle 1's 1.25 s."""

    def pet(t_s: float) -> float:
        log = build([*X0, 740.0], [*V0, 20.0], [VR_Y, 0.0, ramp(t_s, W, 0.0)],
                    changes=[(2, t_s, t_s + 3.0, 1)], slots=slots)  # fmt: skip
        return pet_at_merge(log, PET_WINDOW)

    assert pet(0.5) == pytest.approx(0.75, abs=1e-6)
    assert pet(1.9) == pytest.approx(1.25, abs=1e-6)


def test_a_lane_2_vehicle_passing_the_merge_point_is_not_the_follower() -> None:
    """Vehicle 2 in lane 2 at 750 + 20 t passes x_c first (t = 1.5 s), in lane 2."""
    log = build([*X0, 750.0], [*V0, 20.0], [VR_Y, 0.0, W])
    assert pet_at_merge(log, PET_WINDOW) == pytest.approx(1.25, abs=1e-6)


# ------------------------------------------------------------------- TTC, DRAC
# A leader at 600 + 20 t and a follower at 545 + 25 t: gap 600 - 5 - (545 + 25 t) + 20 t =
# 50 - 5 t, closing speed 5 m/s; TTC = (50 - 5 t) / 5, DRAC = 25 / (2 (50 - 5 t)). Vehicle 0
# is VR, far away on the ramp.
PAIR_X0, PAIR_V0 = [300.0, 600.0, 545.0], [20.0, 20.0, 25.0]
PAIR_GROUP = roles(0, 1, -1, -1, -1, 2)


def pair_window(t_end: float) -> MetricWindow:
    return MetricWindow(group=PAIR_GROUP, t_start=0.0, t_merge=math.nan, t_end=t_end)


# (leader y, follower y, lane change (vehicle, start, end, target), first row in both lanes)
Case = tuple[np.ndarray | float, np.ndarray | float, tuple[int, float, float, int], float]
CASES: dict[str, Case] = {
    # the leader changes 1 -> 2 from t = 0 (y = 0.4 t): still logged in lane 1 at t = 4 s
    # (y = 1.6 m), its body enters lane 2 at y > 0.975 m, from the row t = 2.5 s on
    "leader entering the follower's lane": (0.4 * T, W, (1, 0.0, math.nan, 2), 2.5),
    # the leader changes 1 -> 2, already logged in lane 2 (y = 1.9 + 0.2 t >= 1.875 m) but
    # its body is still in lane 1 (y < 2.775 m): it is the leader of its lane-1 follower
    "leader still in its origin lane": (1.9 + 0.2 * T, 0.0, (1, -1.0, math.nan, 2), 0.0),
    # the follower changes 2 -> 1 (y = W - 0.4 t), logged in lane 2 throughout; its body
    # enters lane 1 (y < 2.775 m) from the row t = 2.5 s on
    "follower entering the leader's lane": (0.0, W - 0.4 * T, (2, 0.0, math.nan, 1), 2.5),
}


@pytest.mark.parametrize("slots", [None, 2])
@pytest.mark.parametrize("case", CASES)
def test_a_body_over_two_lanes_counts_in_both(case: str, slots: int | None) -> None:
    y_leader, y_follower, change, first = CASES[case]
    log = build(PAIR_X0, PAIR_V0, [-W, y_leader, y_follower], changes=[change], slots=slots)
    assert log.lane[-1, 1] != log.lane[-1, 2]  # never in the same logged lane
    for t_end in (4.0, 3.0, first):
        gap = 50.0 - 5.0 * t_end  # the last row has the smallest gap
        w = pair_window(t_end)
        assert min_ttc(log, w) == pytest.approx(gap / 5.0, rel=1e-5)
        assert max_drac(log, w) == pytest.approx(25.0 / (2.0 * gap), rel=1e-5)
        assert closing_metrics(log, w) == {min_ttc: min_ttc(log, w), max_drac: max_drac(log, w)}
    if first > 0.0:  # before its body reaches the other lane the pair does not exist
        before = pair_window(first - 0.1)
        assert (min_ttc(log, before), max_drac(log, before)) == (math.inf, 0.0)


def test_a_lateral_offset_without_a_lane_change_counts_in_the_logged_lane_only() -> None:
    """The same leader as in the first case but no LANE_CHANGE_START event: no lane change
    is in progress, so it stays in its logged lane (hand-built logs log y = 0 everywhere)."""
    log = build(PAIR_X0, PAIR_V0, [-W, 0.4 * T, W])
    assert (min_ttc(log, pair_window(4.0)), max_drac(log, pair_window(4.0))) == (math.inf, 0.0)


def test_a_finished_lane_change_leaves_one_lane() -> None:
    """The leader's change 1 -> 2 (y = 0.4 t) ended at t = 2 s by its event: from then on
    it counts in its logged lane only, so the lane-2 follower never has it as leader."""
    log = build(PAIR_X0, PAIR_V0, [-W, 0.4 * T, W], changes=[(1, 0.0, 2.0, 2)])
    assert min_ttc(log, pair_window(4.0)) == math.inf


@pytest.mark.parametrize("slots", [None, 2])
def test_a_vehicle_that_is_not_key_counts_against_a_key_vehicle(slots: int | None) -> None:
    """Only vehicle 1 (VMC, leader at 600 + 20 t) and VR are key vehicles. A non-key vehicle
    3 at 570 + 20 t drives between VMC and the follower 2 (545 + 25 t, not key): the pair
    (2, 3) has no key vehicle, (3, 1) does not close, so no TTC. Made key, the follower 2
    closes on vehicle 3, its actual leader: gap 570 - 5 - 545 - 5 t = 20 - 5 t, TTC
    (20 - 5 t) / 5 at the last row, not VMC's (50 - 5 t) / 5."""
    log = build([*PAIR_X0, 570.0], [*PAIR_V0, 20.0], [-W, 0.0, 0.0, 0.0], slots=slots)
    w = MetricWindow(group=roles(0, 1), t_start=0.0, t_merge=math.nan, t_end=4.0)
    assert (min_ttc(log, w), max_drac(log, w)) == (math.inf, 0.0)
    w = MetricWindow(group=roles(0, 1, -1, 2), t_start=0.0, t_merge=math.nan, t_end=4.0)
    assert min_ttc(log, w) == pytest.approx((20.0 - 5.0 * 4.0 + 1e-9) / 5.0, abs=1e-5)
    w = MetricWindow(group=roles(0, 1, -1, 2), t_start=0.0, t_merge=math.nan, t_end=3.0)
    assert min_ttc(log, w) == pytest.approx(5.0 / 5.0, rel=1e-5)
    assert max_drac(log, w) == pytest.approx(25.0 / (2.0 * 5.0), rel=1e-5)


@pytest.mark.parametrize("slots", [None, 2])
def test_a_car_cutting_in_that_is_not_key_counts_while_its_body_is_in_the_lane(
    slots: int | None,
) -> None:
    """The key follower 2 (545 + 25 t, lane 1) and a non-key car 3 at 575 + 20 t changing
    from lane 2 to lane 1 (y = W - 0.4 t from t = 0): its body enters lane 1 (y < 2.775 m)
    from the row t = 2.5 s on, while it is still logged in lane 2. From then on it is the
    follower's leader: gap 575 - 5 - 545 - 5 t = 25 - 5 t; at t = 4 s, 5 m and TTC 1 s."""
    log = build([*PAIR_X0, 575.0], [*PAIR_V0, 20.0], [-W, 0.0, 0.0, W - 0.4 * T],
                changes=[(3, 0.0, math.nan, 1)], slots=slots)  # fmt: skip
    assert log.lane[-1, 3] == 2
    group = roles(0, 1, -1, 2)
    at = {t: MetricWindow(group=group, t_start=0.0, t_merge=math.nan, t_end=t) for t in (2.4, 4)}
    assert min_ttc(log, at[2.4]) == pytest.approx((50.0 - 5.0 * 2.4) / 5.0, rel=1e-5)  # VMC's
    assert min_ttc(log, at[4]) == pytest.approx(5.0 / 5.0, rel=1e-5)
    assert max_drac(log, at[4]) == pytest.approx(25.0 / (2.0 * 5.0), rel=1e-5)


def _random_body_log(seed: int, slots: int | None) -> tuple[SimulationLog, np.ndarray]:
    """Random vehicles, each on the road for one stretch of rows, over lanes 0-2 with lateral
    positions near and between the centre lines, logged lane from y, positions on a 5 m grid
    (ties) with NaN now and then, and random lane changes (some never ended); and a random
    set of key vehicles."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 12))
    x = np.round(rng.uniform(0.0, 200.0, (T.size, n)) / 5.0) * 5.0
    x[rng.random(x.shape) < 0.05] = np.nan
    y = rng.uniform(-W - 1.0, W + 1.0, (T.size, n))
    v = rng.uniform(0.0, 30.0, (T.size, n))
    first = rng.integers(0, T.size, n)  # each vehicle on the road for one stretch of rows
    end = first + rng.integers(1, T.size + 1, n)
    on = (np.arange(T.size)[:, None] >= first) & (np.arange(T.size)[:, None] < end)
    log = SimulationLog.allocate(
        T.size, n, dt=0.1, kind=np.ones(n, dtype=np.int64), length=rng.uniform(4.0, 6.0, n),
        width=np.full(n, 1.8), meta={"config": copy.deepcopy(_config())}, slots=slots,
    )  # fmt: skip
    zeros = np.zeros(n)
    for k, t in enumerate(T):
        log.record(k, float(t), x[k], y[k], v[k], zeros, zeros, lane_of(y[k]).clip(0, 2), on[k])
    for i in range(n):
        t_s = float(T[0])
        for _ in range(int(rng.integers(0, 3))):
            t_s = float(rng.choice(T[t_s <= T]))
            log.add_event(t_s, EventKind.LANE_CHANGE_START, i, value=int(rng.integers(0, 3)))
            if rng.random() < 0.7:
                t_s = float(rng.choice(T[t_s <= T]))
                log.add_event(t_s, EventKind.LANE_CHANGE_END, i, value=0)
    return log, rng.permutation(n)[: rng.integers(1, n + 1)]


def _dense_body_pairs(log: SimulationLog, rows: slice, keys: np.ndarray) -> np.ndarray:
    """Row by row from the definition: each lane's occupants (logged lane; a changer's second
    lane on the side of its offset while its body overlaps it) in stable order of position,
    NaN last; (gap, closing) of each neighbour pair with a key vehicle, sorted."""
    starts = log.events_of(EventKind.LANE_CHANGE_START)
    ends = log.events_of(EventKind.LANE_CHANGE_END)
    out = []
    for r in range(*rows.indices(log.n_steps)):
        t = float(log.t[r])
        lanes: dict[int, list[int]] = {0: [], 1: [], 2: []}
        for i in np.flatnonzero(np.asarray(log.active)[r]).tolist():
            lane, y = int(log.lane[r, i]), float(log.y[r, i])
            lanes[lane].append(i)
            begun = np.count_nonzero((starts["vehicle"] == i) & (starts["t"] <= t + 1e-6))
            ended = np.count_nonzero((ends["vehicle"] == i) & (ends["t"] < t - 1e-6))
            side = int(np.sign(y - (lane - 1) * W))
            other = lane + side
            if begun > ended and side and 0 <= other <= 2 and abs(y - (other - 1) * W) < 2.775:
                lanes[other].append(i)
        for members in lanes.values():
            xs = np.array([float(log.x[r, i]) for i in sorted(members)])
            order = [sorted(members)[k] for k in np.argsort(xs, kind="stable")]
            for f, ld in itertools.pairwise(order):
                if f in keys or ld in keys:
                    gap = float(log.x[r, ld]) - float(log.length[ld]) - float(log.x[r, f])
                    if math.isfinite(gap):
                        out.append((gap, float(log.v[r, f]) - float(log.v[r, ld])))
    return np.array(sorted(out)).reshape(-1, 2)


@pytest.mark.parametrize("seed", range(30))
def test_body_pairs_follow_their_definition(seed: int) -> None:
    for slots in (None, 12):
        log, keys = _random_body_log(seed, slots)
        rows = slice(seed % 7, T.size - seed % 5)
        gap, closing = body_pairs(log, rows, keys)
        got = np.array(sorted(zip(gap.tolist(), closing.tolist(), strict=True))).reshape(-1, 2)
        np.testing.assert_array_equal(got, _dense_body_pairs(log, rows, keys))
