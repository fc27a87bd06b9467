"""The engine on roads other than the paper's: its lane table (:mod:`hcomc.sim.lane_table`)
drives every kernel, so more mainline lanes, off-ramps, speed zones, lane drops and several
on-ramps run with the paper's physics (Eq. 1-7, Eq. 14) and controllers."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest

from hcomc.config import ScenarioConfig, load_config
from hcomc.corridor import load_corridor
from hcomc.corridor.road import LaneDrop, OffRamp, OnRamp, Road, SpeedLimit
from hcomc.interface import Fleet, MergeGroup, MergePlan, Mode
from hcomc.road import Kind
from hcomc.sim.demand import Demand
from hcomc.sim.engine import Simulation
from hcomc.sim.lane_table import KIND_MAIN, L_CENTRE, L_ENDS, L_EXIT
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.roads import paper_lanes, road_lanes
from hcomc.sim.scene import Scene, SceneMaker
from hcomc.sim.step import loop as step_loop

Release = tuple[float, float, float, int, int]
"""A vehicle of a hand-made demand: release time [s], position [m], speed [m/s], lane code,
route (off-ramp lane code, -1: the mainline's end)."""


def _scene(road: Road, releases: Sequence[Release], slow: dict[int, float] | None = None,
           kind: int = Kind.HDV) -> SceneMaker:  # fmt: skip
    """A scene maker of ``road`` with the vehicles ``releases`` (all of ``kind``), those in
    ``slow`` with their desired speed [m/s] set to the given value."""
    lanes = road_lanes(road)

    def make(config: ScenarioConfig, rng: np.random.Generator) -> Scene:
        rows = np.array(releases, dtype=np.float64)
        order = np.lexsort((-rows[:, 1], rows[:, 0]))
        rows = rows[order]
        n = rows.shape[0]
        demand = Demand(
            t=rows[:, 0], x=rows[:, 1], v=rows[:, 2], lane=rows[:, 3].astype(np.int64),
            kind=np.full(n, kind, dtype=np.int64), scripted=np.zeros(n, dtype=bool),
            route=rows[:, 4].astype(np.int64),
        )  # fmt: skip
        fleet = Fleet.build(config, demand.kind, demand.scripted)
        for original, v0 in (slow or {}).items():
            fleet.matrix[0, int(np.flatnonzero(order == original)[0])] = v0
        return Scene(lanes, demand, fleet)

    return make


def _run(scene: SceneMaker, duration: float, controller: str = "none", **keys: object
         ) -> Simulation:  # fmt: skip
    config = load_config("C1", duration=duration, warmup=0.0, control={"controller": controller},
                         **keys)  # fmt: skip
    sim = Simulation(config, seed=0, scene=scene)
    sim.run()
    return sim


def _road(**keys: object) -> Road:
    """A corridor road of ``keys`` (as its TOML table would give them)."""
    return Road.model_validate(keys)


def _events(log: SimulationLog, kind: EventKind) -> np.ndarray:
    """The events of ``kind`` of a run."""
    return log.events[log.events["kind"] == kind]


def _changes(log: SimulationLog) -> list[tuple[int, int]]:
    """(from lane, to lane) of every lane change the run started."""
    starts = _events(log, EventKind.LANE_CHANGE_START)
    rows = np.searchsorted(log.t, starts["t"] - 1e-9)
    return [(int(log.lane[max(r - 1, 0), v]), int(to))
            for r, v, to in zip(rows, starts["vehicle"], starts["value"], strict=True)]  # fmt: skip


def test_the_paper_road_is_a_preset_of_the_lane_table() -> None:
    """The corridor preset ``paper`` (the paper's road as a corridor) and the conditions'
    ``[road]`` table make one lane table: the same codes, neighbours, centres, lane
    openings, ends, control zone and exits."""
    ours = paper_lanes(load_config("C1").road)
    theirs = road_lanes(load_corridor("paper", {}).road)
    np.testing.assert_array_equal(ours.ints, theirs.ints)
    np.testing.assert_array_equal(ours.floats[: L_EXIT + 1], theirs.floats[: L_EXIT + 1])
    assert np.isinf(ours.main_end).all()
    assert np.isinf(theirs.main_end).all()
    assert list(ours.ints[0]) == [1, KIND_MAIN, KIND_MAIN]  # hcomc.road.Lane's codes


def test_the_lane_table_says_which_lanes_end() -> None:
    """``L_ENDS`` (the step looks for a lane's end only where it is 1): an acceleration lane
    and a mainline lane that a section drops end; an off-ramp's lane and the mainline lanes
    that run to the road's end do not."""
    road = _road(
        lanes=3, length=4000.0, lane_drops=[LaneDrop(x=2500.0, lanes=2)],
        on_ramps=[OnRamp(id="on", x=800.0)], off_ramps=[OffRamp(id="off", x=1800.0)],
    )  # fmt: skip
    table = road_lanes(road)
    assert list(table.ints[L_ENDS]) == [1, 0, 0, 0, 1]  # on, off, then mainline lanes 0-2
    assert list(np.isfinite(table.main_end).any(axis=1)) == [False, False, True]
    assert list(paper_lanes(load_config("C1").road).ints[L_ENDS]) == [1, 0, 0]


def test_a_middle_lane_vehicle_overtakes_on_either_side() -> None:
    """Three lanes (codes 0-2, no ramps): behind a slow vehicle in the middle lane, followers
    change right (keep-right bias) when the right lane is free and left when a slow vehicle
    blocks the right lane too; every change goes to an adjacent lane."""
    road = _road(lanes=3, length=4000.0, speed_limit=40.0)
    free_right = [
        (0.0, 400.0, 15.0, 1, -1),
        *((0.0, 300.0 - 40 * k, 25.0, 1, -1) for k in range(3)),
    ]
    blocked = [(0.0, 2400.0, 15.0, 1, -1), (0.0, 2420.0, 15.0, 0, -1),
               *((0.0, 2300.0 - 40 * k, 25.0, 1, -1) for k in range(3))]  # fmt: skip
    releases = [*free_right, *blocked]
    sim = _run(_scene(road, releases, slow={0: 15.0, 4: 15.0, 5: 15.0}), 40.0)
    changes = _changes(sim.log)
    assert all(abs(a - b) == 1 for a, b in changes), changes
    assert (1, 0) in changes
    assert (1, 2) in changes
    assert sim.collisions == 0


def test_vehicles_bound_for_an_off_ramp_leave_by_it() -> None:
    """An off-ramp (its lane code 0, the mainline 1 and 2): vehicles routed to it move right
    and leave the road at the end of its road (1500 + 200 + 300 m); the others leave at the
    mainline's end."""
    road = _road(lanes=2, length=3000.0, off_ramps=[OffRamp(id="off", x=1500.0)])
    off = 0
    releases = [(2.0 * k, 10.0, 25.0, 1 + k % 2, off if k % 3 == 0 else -1) for k in range(12)]
    sim = _run(_scene(road, releases), 150.0)
    exits = _events(sim.log, EventKind.EXIT)
    assert exits.size == 12
    routed = np.isin(exits["vehicle"], np.flatnonzero(sim.demand.route == off))
    assert routed.sum() == 4
    assert (exits["x"][routed] > 2000.0).all()
    assert (exits["x"][routed] < 2100.0).all()
    assert (exits["x"][~routed] > 3000.0).all()
    assert _events(sim.log, EventKind.MISSED_EXIT).size == 0
    for i in np.flatnonzero(sim.demand.route == off):
        lanes = sim.log.lane[:, i]
        assert lanes[lanes >= 0][-1] == off
    assert sim.collisions == 0


def test_a_speed_zone_caps_the_desired_speed() -> None:
    """A 20 m/s zone from 1000 to 2000 m on a 40 m/s road, vehicles wishing 33.3 m/s: Eq. 1
    with v0 capped by the limit brakes them in the zone and relaxes them to the limit from
    above (within 1 % of it over the zone's second half); past it they speed up again."""
    road = _road(lanes=2, length=3000.0, speed_limit=40.0,
                 speed_limits=[SpeedLimit(x0=1000.0, x1=2000.0, speed=20.0)])  # fmt: skip
    releases = [(3.0 * k, 10.0, 30.0, k % 2, -1) for k in range(8)]
    log = _run(_scene(road, releases), 150.0).log
    x, v = log.x, log.v

    def fastest(x0: float, x1: float) -> float:
        return float(np.nanmax(v[(x > x0) & (x < x1)]))

    assert fastest(500.0, 1000.0) > 30.0
    assert fastest(1500.0, 2000.0) <= 20.0 * 1.01
    assert fastest(2600.0, 3000.0) > 30.0


def test_a_dropped_lane_is_left_before_it_ends() -> None:
    """Three lanes dropping to two at 1500 m: nobody drives in the third lane (code 2) past
    its end, and everyone reaches the mainline's end."""
    road = _road(lanes=3, length=3000.0, lane_drops=[LaneDrop(x=1500.0, lanes=2)])
    releases = [(2.0 * k, 10.0, 25.0, k % 3, -1) for k in range(9)]
    sim = _run(_scene(road, releases), 150.0)
    log = sim.log
    assert not ((log.lane == 2) & (log.x > 1500.0)).any()
    assert _events(sim.log, EventKind.EXIT).size == 9
    assert sim.collisions == 0


@pytest.mark.parametrize("controller", ["fifo", "hcomc"])
def test_each_on_ramp_is_controlled_with_its_own_geometry(controller: str) -> None:
    """Two on-ramps (codes 0 and 1, the mainline 2 and 3): each ramp vehicle is decided for
    in its own ramp's control zone, with key vehicles in the lanes beside its ramp, and
    merges into mainline lane 0 on its own acceleration lane."""
    road = _road(lanes=2, length=3000.0,
                on_ramps=[OnRamp(id="a", x=700.0), OnRamp(id="b", x=1900.0)])  # fmt: skip
    mainline = [(1.5 * k, 10.0, 25.0, 2 + k % 2, -1) for k in range(40)]
    ramps = [(8.0, 250.0, 20.0, 0, -1), (30.0, 1450.0, 20.0, 1, -1)]
    sim = _run(_scene(road, [*mainline, *ramps], kind=Kind.CAV), 90.0, controller)
    vrs = np.flatnonzero(sim.demand.lane < 2)
    assert [p.group.vr for p in sim.decisions[:2]] == vrs.tolist()
    merges = _events(sim.log, EventKind.MERGE)
    assert sorted(merges["vehicle"].tolist()) == vrs.tolist()
    for vr, ramp in zip(vrs, road.on_ramps, strict=True):
        x = float(merges["x"][merges["vehicle"] == vr][0])
        assert ramp.x <= x <= ramp.end
        group = sim.key_groups[int(vr)]
        assert group.vmc < 0 or sim.demand.lane[group.vmc] in (2, 3)
    assert sim.collisions == 0


def test_a_change_that_stands_still_before_the_lane_line_is_given_up() -> None:
    """A vehicle told to change lanes 10 m behind a standing one stops behind it before
    its body reaches the lane line (Eq. 4-6 move it sideways only as it moves along x); once
    its change's duration is over it gives the change up, back on its own lane's centre
    line, instead of blocking both lanes for good."""
    road = _road(lanes=2, length=3000.0)
    releases = [(0.0, 300.0, 0.0, 0, -1), (0.0, 290.0, 5.0, 0, -1)]
    config = load_config("C1", duration=20.0, warmup=0.0, control={"controller": "none"})
    sim = Simulation(config, seed=0, scene=_scene(road, releases))
    sim.command(0, 0.0)  # vehicle 0 stands at 300 m, held in its lane
    sim.run_to(10)
    changer = 1  # released at 290 m
    step_loop.start_lane_changes(sim.core, np.array([changer]), np.array([1]), sim.t,
                                 np.array([np.nan]))  # fmt: skip
    sim.run()
    aborts = _events(sim.log, EventKind.LANE_CHANGE_ABORT)
    assert aborts["vehicle"].tolist() == [changer]
    start = float(_events(sim.log, EventKind.LANE_CHANGE_START)["t"][0])
    assert aborts["t"][0] - start > config.hdv.lane_change_duration
    assert sim.lane[changer] == 0
    assert sim.y[changer] == 0.0
    assert sim.v[changer] < 0.1


def test_a_change_that_stands_still_past_the_lane_line_is_completed() -> None:
    """A changer brought to a stop past the lane line, its body still across both lanes,
    completes the change once its duration is over: on the target lane's centre line, with
    the change's end logged, instead of blocking both lanes for good."""
    road = _road(lanes=2, length=3000.0)
    config = load_config("C1", duration=20.0, warmup=0.0, control={"controller": "none"})
    sim = Simulation(config, seed=0, scene=_scene(road, [(0.0, 290.0, 5.0, 0, -1)]))
    sim.run_to(10)
    changer = 0
    step_loop.start_lane_changes(sim.core, np.array([changer]), np.array([1]), sim.t,
                                 np.array([np.nan]))  # fmt: skip
    x0, xf = float(sim.lc_x0[changer]), float(sim.lc_xf[changer])
    stop = x0 + 0.55 * (xf - x0)  # its centre past the line, its body across it
    sim.command(changer, -(float(sim.v[changer]) ** 2) / (2.0 * (stop - sim.x[changer])))
    sim.run()
    ends = _events(sim.log, EventKind.LANE_CHANGE_END)
    assert ends["vehicle"].tolist() == [changer]
    start = float(_events(sim.log, EventKind.LANE_CHANGE_START)["t"][0])
    assert ends["t"][0] - start > config.hdv.lane_change_duration
    assert float(ends["x"][0]) == pytest.approx(stop, abs=0.1)
    assert sim.lane[changer] == sim.origin[changer] == sim.target[changer] == 1
    assert sim.y[changer] == sim.lanes.floats[L_CENTRE, 1]
    assert _events(sim.log, EventKind.LANE_CHANGE_ABORT).size == 0


def test_a_plan_fails_when_its_ramp_vehicle_waits_at_the_lane_end() -> None:
    """A plan whose VR stands at its acceleration lane's end (a vehicle stands beside the
    end) fails: FALLBACK, and its VMC leaves VV1, which ends on VR's state and would hold VMC
    right behind VR's projection, in the gap VR needs. Once the way is free, VR merges by gap
    acceptance."""
    road = _road(lanes=2, length=3000.0, on_ramps=[OnRamp(id="a", x=700.0, accel_length=250.0)])
    wall, vr, vmc = 0, 1, 2  # released in this order: by time, then downstream first
    releases = [(0.0, 953.0, 0.0, 1, -1), (0.0, 949.0, 0.0, 0, -1), (0.0, 850.0, 5.0, 1, -1)]
    config = load_config("C1", duration=60.0, warmup=0.0, control={"controller": "none"})
    sim = Simulation(config, seed=0, scene=_scene(road, releases))
    sim.command(wall, 0.0)
    sim.run_to(1)
    assert _events(sim.log, EventKind.RAMP_WAIT)["vehicle"].tolist() == [vr]
    plan = MergePlan(MergeGroup(vr=vr, vmc=vmc), Mode.LONGITUDINAL, sim.t, horizon=1.0,
                     vv1=np.array([sim.x[vr], 0.0, 0.0, 0.0]))  # fmt: skip
    sim.execute(plan, 0)
    assert sim.commanded().tolist() == [vmc]
    sim.step()
    fallback = _events(sim.log, EventKind.FALLBACK)
    assert fallback[["vehicle", "other"]].tolist() == [(vr, vmc)]
    assert sim.commanded().size == 0
    sim.command(wall, math.nan)
    sim.run()
    assert _events(sim.log, EventKind.MERGE)["vehicle"].tolist() == [vr]
    assert sim.collisions == 0


def test_a_changer_brakes_from_the_start_for_a_target_leader_that_asks_it_to() -> None:
    """Eq. 14's blend starts at Ψ = 0.01: a changer whose target-lane leader asks for more
    than the safe deceleration brakes for it from its first step (the blend alone would keep
    it accelerating behind its free origin lane until its body reached the target lane)."""
    road = _road(lanes=2, length=3000.0)
    releases = [(0.0, 330.0, 10.0, 1, -1), (0.0, 305.0, 25.0, 0, -1)]
    config = load_config("C1", duration=20.0, warmup=0.0, control={"controller": "none"})
    sim = Simulation(config, seed=0, scene=_scene(road, releases, kind=Kind.CAV))
    slow, changer = 0, 1
    sim.command(slow, 0.0)
    sim.run_to(1)
    step_loop.start_lane_changes(sim.core, np.array([changer]), np.array([1]), sim.t,
                                 np.array([np.nan]))  # fmt: skip
    sim.step()
    assert sim.origin[changer] == 0  # still in its change, its body mostly in lane 0
    assert sim.a[changer] < -config.lane_change.safe_decel
    sim.run()
    assert sim.collisions == 0
