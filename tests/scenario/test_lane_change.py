"""Closed-loop lane changes and merges (quintic path, lane switch, Eq. 14 blend, stop line).

Timing convention of the engine (read from ``Simulation.step``): a LANE_CHANGE_START event at
time t is decided from the state logged at t (row ``t/dt``), with ``x`` = that position; the
LANE_CHANGE_END and MERGE events of a step starting at t describe the state reached at
``t + dt`` (row ``t/dt + 1``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import pytest

from hcomc.config import ScenarioConfig, load_config
from hcomc.equations.lane_change import lateral_offset
from hcomc.equations.transition import transition_weight
from hcomc.road import Kind, Lane, lane_centre
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.step import loop as step_loop

SEEDS = [1, 2, 3]
TOL_Y = 1e-4  # [m], float32 log of |y| <= 3.75 m is good to ~5e-7


def _config(duration: float = 300.0, **demand) -> ScenarioConfig:
    base = load_config("C1").demand.model_dump()
    return load_config("C1", duration=duration, demand={**base, "ramp": "flow", **demand})


# denser mainline and ramp flow: ramp vehicles queue at the end of the acceleration lane
DENSE = {"mean_headway_main_1": 1.6, "mean_headway_main_2": 2.0, "ramp_mean_headway": 5.0}


@cache
def _cached_run(seed: int, dense: bool) -> tuple[Simulation, SimulationLog]:
    sim = Simulation(_config(**(DENSE if dense else {})), seed=seed)
    return sim, sim.run()


def _run(seed: int, dense: bool = False) -> tuple[Simulation, SimulationLog]:
    """One 300 s run per (seed, demand), shared by the tests of this module."""
    return _cached_run(seed, dense)


@dataclass(frozen=True)
class Change:
    vehicle: int
    t_start: float
    x_start: float
    target: int
    t_end: float | None  # None: not completed (run ended or the vehicle left)
    aborted: bool = False  # given up standing before the lane line (t_end: then)


_ENDS = (EventKind.LANE_CHANGE_END, EventKind.LANE_CHANGE_ABORT)


def _changes(log: SimulationLog) -> list[Change]:
    """Pair every LANE_CHANGE_START with the next LANE_CHANGE_END or LANE_CHANGE_ABORT of
    the same vehicle."""
    ev = log.events
    out = []
    for i in np.unique(ev["vehicle"][ev["kind"] == EventKind.LANE_CHANGE_START]).tolist():
        mine = ev[(ev["vehicle"] == i) & np.isin(ev["kind"], [EventKind.LANE_CHANGE_START, *_ENDS])]
        kinds = mine["kind"].tolist()
        # starts and ends alternate, beginning with a start
        assert kinds[::2] == [EventKind.LANE_CHANGE_START] * len(kinds[::2]), i
        assert all(k in _ENDS for k in kinds[1::2]), i
        for k in range(0, len(mine), 2):
            start = mine[k]
            end = mine[k + 1] if k + 1 < len(mine) else None
            if end is not None:
                assert end["value"] == start["value"]
            out.append(
                Change(
                    vehicle=i,
                    t_start=float(start["t"]),
                    x_start=float(start["x"]),
                    target=int(start["value"]),
                    t_end=None if end is None else float(end["t"]),
                    aborted=end is not None and end["kind"] == EventKind.LANE_CHANGE_ABORT,
                )
            )
    return out


def _row(log: SimulationLog, t: float) -> int:
    return round((t - log.t[0]) / log.dt)


def _logged_changes(log: SimulationLog) -> list[tuple[Change, int, int]]:
    """Completed changes entirely inside the log, with their first and last row."""
    out = []
    for ch in _changes(log):
        if ch.t_end is None or ch.aborted or ch.t_start < log.t[0]:
            continue
        k0, k1 = _row(log, ch.t_start), _row(log, ch.t_end) + 1
        if k1 < log.n_recorded:
            out.append((ch, k0, k1))
    return out


def _released_at(log: SimulationLog, i: int) -> float:
    ins = log.events_of(EventKind.INSERTION)
    return float(ins["t"][ins["vehicle"] == i][0])


@pytest.mark.parametrize("seed", SEEDS)
def test_every_change_follows_the_quintic_path_and_switches_lane_once(seed):
    sim, log = _run(seed)
    config = sim.config
    width = config.road.lane_width
    changes = _logged_changes(log)
    assert len(changes) >= 20
    assert any(ch.target == Lane.MAIN_2 for ch, _, _ in changes)
    assert any(ch.target == Lane.MAIN_1 and log.lane[k0, ch.vehicle] == 0 for ch, k0, _ in changes)
    for ch, k_start, k1 in changes:
        i, k0 = ch.vehicle, k_start
        if log.active[k0, i]:
            origin = int(log.lane[k0, i])
            v0 = float(log.v[k0, i])
        else:  # released in the step that decided the change: not yet in row k0
            assert _released_at(log, i) == ch.t_start
            origin, v0 = int(sim.demand.lane[i]), float(sim.demand.v[i])
            assert ch.x_start == pytest.approx(sim.demand.x[i], abs=1e-9)
            k0 += 1
        assert abs(ch.target - origin) == 1
        y0, y1 = float(lane_centre(origin, width)), float(lane_centre(ch.target, width))
        sign = np.sign(y1 - y0)
        rows = slice(k0, k1 + 1)
        y, x = log.y[rows, i].astype(np.float64), log.x[rows, i].astype(np.float64)
        heading, lane = log.heading[rows, i], log.lane[rows, i]
        assert log.active[rows, i].all()
        # ends on the target centre, straight
        assert y[-1] == pytest.approx(y1, abs=TOL_Y)
        assert heading[-1] == 0.0
        first = int(_row(log, ch.t_start) == k0)  # row 0 is the decision row
        if first:  # starts on the origin centre, straight
            assert x[0] == pytest.approx(ch.x_start, abs=1e-3)
            assert y[0] == pytest.approx(y0, abs=TOL_Y)
            assert heading[0] == 0.0
        # y stays between the two centres
        assert (np.minimum(y0, y1) - TOL_Y <= y).all()
        assert (y <= np.maximum(y0, y1) + TOL_Y).all()
        # heading points towards the target lane and stays moderate
        assert (sign * heading >= 0).all()
        assert (np.abs(heading) < 0.5).all()
        # the path is Eq. 4-6 between x0 and the predicted end x0 + max(v T_lc, 3 L)
        xf = ch.x_start + max(v0 * sim.fleet.lc_duration[i], 3.0 * sim.fleet.length[i])
        inner = slice(first, -1)
        y_path, slope, _ = lateral_offset(x[inner], ch.x_start, xf, y0, y1)
        np.testing.assert_allclose(y[inner], y_path, rtol=0, atol=1e-3)
        np.testing.assert_allclose(heading[inner], np.arctan(slope), rtol=0, atol=1e-3)
        assert (x[inner] < xf + 1e-3).all()
        assert x[-1] >= xf - 1e-3
        # the lane switches exactly once, when the centre crosses the lane line
        assert lane[0] == origin
        assert lane[-1] == ch.target
        assert set(lane.tolist()) <= {origin, ch.target}
        switch = np.flatnonzero(lane[1:] != lane[:-1])
        assert switch.size == 1
        m = switch[0] + 1  # first row in the target lane
        line = 0.5 * (y0 + y1)
        assert sign * (y[m] - line) >= -TOL_Y
        assert sign * (y[m - 1] - line) < TOL_Y


@pytest.mark.parametrize("seed", SEEDS)
def test_merges_go_from_the_ramp_to_lane_1(seed):
    sim, log = _run(seed)
    road = sim.config.road
    ev = log.events
    merges = ev[ev["kind"] == EventKind.MERGE]
    ends = ev[ev["kind"] == EventKind.LANE_CHANGE_END]
    assert merges.size >= 5
    for e in merges:
        i = int(e["vehicle"])
        assert sim.demand.lane[i] == Lane.RAMP
        # a merge is the completion of a change into lane 1
        assert ((ends["vehicle"] == i) & (ends["t"] == e["t"]) & (ends["value"] == 1)).any()
        if e["t"] >= log.t[0] and _row(log, e["t"]) + 1 < log.n_recorded:
            k = _row(log, e["t"]) + 1
            assert log.lane[k, i] == Lane.MAIN_1
            assert log.y[k, i] == pytest.approx(0.0, abs=TOL_Y)
        # it started on the acceleration lane
        start = [ch for ch in _changes(log) if ch.vehicle == i and ch.t_end == float(e["t"])]
        assert len(start) == 1
        assert road.accel_lane_start <= start[0].x_start <= road.accel_lane_end
    # every ramp change ends in lane 1: no vehicle enters the ramp from the mainline
    lane = log.lane.astype(int)
    entered_ramp = (lane[1:] == Lane.RAMP) & (lane[:-1] != Lane.RAMP) & (lane[:-1] >= 0)
    assert not entered_ramp.any()


def _in_manoeuvre(log: SimulationLog) -> np.ndarray:
    """(T, N) mask of rows in which a vehicle is on a lane-change path."""
    mask = np.zeros(log.x.shape, dtype=bool)
    for ch in _changes(log):
        k0 = max(_row(log, ch.t_start), -1) + 1
        k1 = log.n_recorded if ch.t_end is None else _row(log, ch.t_end) + 1
        if k1 >= 0:
            mask[max(k0, 0) : k1 + 1, ch.vehicle] = True
    return mask


@pytest.mark.parametrize(("seed", "dense"), [(1, False), (2, False), (1, True), (3, True)])
def test_ramp_vehicles_stop_at_the_end_of_the_acceleration_lane(seed, dense):
    sim, log = _run(seed, dense)
    end = sim.config.road.accel_lane_end
    on_ramp = log.active & (log.lane == Lane.RAMP)
    keeping = on_ramp & ~_in_manoeuvre(log)
    assert keeping.any()
    assert np.nanmax(np.where(keeping, log.x, np.nan)) <= end + 1e-3
    if dense:  # the dense runs really test the stop line: vehicles wait at it
        waits = log.events_of(EventKind.RAMP_WAIT)
        assert waits.size >= 1
        assert (waits["x"] <= end + 1e-9).all()
        assert (waits["x"] > end - 20.0).all()
    # a vehicle in its manoeuvre may still be in lane 0 past the end, but only by half
    # of its path (it crosses the lane line at xi = 1/2 of at most max(v T_lc, 3 L))
    changing_on_ramp = on_ramp & _in_manoeuvre(log)
    if changing_on_ramp.any():
        v_max = np.nanmax(log.v)
        half = 0.5 * max(v_max * float(sim.fleet.lc_duration.max()), 15.0)
        assert np.nanmax(np.where(changing_on_ramp, log.x, np.nan)) <= end + half


# ---------------------------------------------------------------- Eq. 14 blend
def _overlaps(sim: Simulation, lane: np.ndarray | int) -> np.ndarray:
    """Whether each vehicle's body overlaps ``lane`` laterally."""
    reach = 0.5 * (sim.config.road.lane_width + sim.fleet.width)
    return np.abs(sim.y - lane_centre(lane, sim.config.road.lane_width)) < reach


def _leader(sim: Simulation, i: int, lane: int, active: np.ndarray) -> int:
    """Brute force: nearest active vehicle ahead of i that occupies ``lane``: its current
    lane, the target lane of a change from its start, the origin lane of a change while
    its body still overlaps it."""
    changing = sim.origin != sim.target
    occupies = active & (
        (sim.lane == lane)
        | (changing & (sim.target == lane))
        | (changing & (sim.origin == lane) & _overlaps(sim, lane))
    )
    occupies[i] = False
    ahead = np.flatnonzero(occupies & (sim.x > sim.x[i]))
    return int(ahead[np.argmin(sim.x[ahead])]) if ahead.size else -1


def test_changing_vehicles_apply_the_eq14_blend():
    """Step a run by hand; before every step recompute, for each vehicle in a lane change,
    a_ori (origin-lane leader) and a_new (target-lane leader) with ``sim._follow`` and
    check the applied acceleration is Psi a_new + (1 - Psi) a_ori, capped by a_ori while
    the body overlaps the origin lane and by a_new while it overlaps the target lane."""
    config = _config(duration=60.0, main_speed=30.0)  # traffic with HDV lane changes
    sim = Simulation(config, seed=1)  # a seed in which HDVs and CAVs change lanes
    tol = config.lane_change.transition_tolerance
    checked, kinds, psis = 0, set(), []
    for _ in range(sim.n_warmup + sim.n_steps):
        t = sim.t
        step_loop.release(sim.core, t)  # step() releases first; releasing twice is a no-op
        active = sim.active.copy()
        changing = np.flatnonzero(active & (sim.origin != sim.target))
        expected = {}
        for i in changing.tolist():
            lo = _leader(sim, i, int(sim.origin[i]), active)
            ln = _leader(sim, i, int(sim.target[i]), active)
            ids = np.array([i])
            a_ori = float(sim.follow(ids, np.array([lo]))[0])
            a_new = float(sim.follow(ids, np.array([ln]))[0])
            psi = float(transition_weight(t - sim.lc_t0[i], sim.lc_dur[i], tol))
            blend = psi * a_new + (1.0 - psi) * a_ori
            if _overlaps(sim, int(sim.origin[i]))[i]:
                blend = min(blend, a_ori)
            if _overlaps(sim, int(sim.target[i]))[i]:
                blend = min(blend, a_new)
            a_tar = max(blend, -config.lane_change.emergency_decel)
            if sim.v[i] + a_tar * sim.dt >= 0.0:  # else the ballistic stop overrides a
                expected[i] = (a_tar, psi, int(sim.fleet.kind[i]))
        sim.step()
        for i, (a_tar, psi, kind) in expected.items():
            assert sim.a[i] == pytest.approx(a_tar, abs=1e-9), (i, t)
            checked += 1
            kinds.add(kind)
            psis.append(psi)
    assert checked >= 200
    assert kinds == {0, 1}  # HDVs (delayed, noisy perception) and CAVs
    assert min(psis) < 0.1
    assert max(psis) > 0.9


# ------------------------------------------------------ merge out of a ramp queue
def _staged(vehicles: list[tuple[int, float, float]]) -> Simulation:
    """A C1 simulation (all CAVs: exact perception) holding only ``vehicles`` (lane, x, v).

    The demand is not released; slots 0.. are overwritten with the given states.
    """
    base = load_config("C1").demand.model_dump()
    config = load_config(
        "C1", warmup=0.0, duration=30.0, demand={**base, "ramp": "none", "cav_penetration": 1.0}
    )
    sim = Simulation(config, seed=0)
    assert sim.demand.n >= len(vehicles)
    assert (sim.fleet.kind == Kind.CAV).all()
    sim.arrays.queue_pos[:] = np.diff(sim.arrays.queue_start)  # release nothing
    for i, (lane, x, v) in enumerate(vehicles):
        sim.x[i], sim.v[i] = x, v
        sim.lane[i] = sim.origin[i] = sim.target[i] = lane
        sim.y[i] = lane_centre(lane, config.road.lane_width)
        sim.active[i] = True
    sim.perception.fill(np.arange(len(vehicles)), sim.x, sim.v)
    return sim


# A (0) waits at the end of the acceleration lane, B (1) is queued 2 m behind it; the
# lane-1 vehicle C (2) beside A makes A's gap unsafe but leaves a gap for B.
RAMP_QUEUE = [(Lane.RAMP, 948.0, 0.0), (Lane.RAMP, 941.0, 0.0), (Lane.MAIN_1, 951.0, 0.0)]


def test_queued_ramp_vehicle_does_not_start_towards_a_standing_leader():
    """B has a gap in lane 1 but A stands 2 m ahead: its path (>= 3 L) is not clear."""
    sim = _staged(RAMP_QUEUE)
    sim.step()
    assert sim.log.events_of(EventKind.LANE_CHANGE_START).size == 0
    assert sim.x[0] - sim.fleet.length[0] - sim.x[1] == pytest.approx(2.0, abs=1e-6)


def test_merge_begun_behind_a_vehicle_that_then_stops_respects_it():
    """B starts merging behind a slow A that then stops: while B's body overlaps the ramp
    lane it still follows A (the cap on the Eq. 14 blend), so it never hits A."""
    sim = _staged([(Lane.RAMP, 930.0, 3.0), (Lane.RAMP, 915.0, 8.0), (Lane.MAIN_1, 980.0, 0.0)])
    started = False
    for _ in range(200):
        sim.step()
        started |= bool(sim.origin[1] != sim.target[1])
        # while B still overlaps the ramp lane laterally, it must stay behind A
        if abs(sim.y[1] - sim.y[0]) < sim.fleet.width[0]:
            assert sim.x[0] - sim.fleet.length[0] - sim.x[1] > 0.0
    assert started
    assert sim.log.events_of(EventKind.COLLISION).size == 0
