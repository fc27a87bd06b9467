"""A corridor on the engine (:mod:`hcomc.sim.corridor_scene`): the ``corridor`` preset (three
lanes, five on-ramps, four off-ramps, a speed zone, cars and trucks) driven with the paper's
physics, read back from the run's log."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.corridor import load_corridor
from hcomc.interface import Fleet
from hcomc.road import Kind
from hcomc.sim.corridor_scene import corridor_config, corridor_scene
from hcomc.sim.demand import Demand
from hcomc.sim.engine import Simulation
from hcomc.sim.lane_table import KIND_MAIN, KIND_OFF, KIND_ON, L_CENTRE, L_EXIT, L_KIND
from hcomc.sim.log import EventKind
from hcomc.sim.roads import paper_lanes
from hcomc.sim.scene import Scene


@pytest.fixture(scope="module")
def run() -> Simulation:
    c = load_corridor("corridor", {"corridor.duration": 300.0})
    sim = Simulation(corridor_config(c, control={"controller": "none"}), seed=0,
                     scene=corridor_scene(c))  # fmt: skip
    sim.run()
    return sim


def _events(sim: Simulation, kind: EventKind) -> np.ndarray:
    events = sim.log.events
    return events[events["kind"] == kind]


def test_the_run_has_the_corridor_s_model_parameters() -> None:
    """Step, duration and the lane-change and route tables are the corridor's; the human
    drivers keep the paper's perception (Eq. 2)."""
    c = load_corridor("corridor", {})
    config = corridor_config(c)
    assert (config.dt, config.duration, config.warmup) == (0.1, 3600.0, 0.0)
    assert config.hdv.lane_change_duration == c.corridor.lane_change_duration == 3.0
    assert config.lane_change.exit_lookahead == c.routes.exit_lookahead
    assert config.lane_change.urgent_distance == c.routes.urgent_distance
    assert config.hdv.reaction_time_gap > 0
    assert config.hdv.estimation_errors


def test_its_vehicles_are_the_corridor_s(run: Simulation) -> None:
    """The corridor's classes (cars 5 m, trucks 16.5 m) and about its CAV share (0.2), each
    released at its origin: the mainline's start or its on-ramp road's, its front one length
    in; routes lead to off-ramp lanes."""
    lengths = set(np.round(run.fleet.length, 2).tolist())
    assert lengths == {5.0, 16.5}
    share = float(np.mean(run.fleet.kind == Kind.CAV))
    assert 0.1 < share < 0.3
    kinds = run.lanes.ints[L_KIND]
    assert set(kinds[run.demand.lane].tolist()) == {KIND_MAIN, KIND_ON}
    assert set(kinds[run.demand.route[run.demand.route >= 0]].tolist()) == {KIND_OFF}
    main = kinds[run.demand.lane] == KIND_MAIN
    np.testing.assert_array_equal(run.demand.x[main], run.fleet.length[main])


def test_it_drives_with_the_paper_s_physics(run: Simulation) -> None:
    """HDVs perceive with delays and errors (Eq. 2); lane changes move along the quintic
    path (Eq. 4-6: logged between two lane centres, headed off the x axis); collisions are
    Eq. 7's (none in these five minutes)."""
    assert run.perception.errors
    assert max(run.perception.taus) > 0
    log = run.log
    centres = run.lanes.floats[L_CENTRE]
    y = log.y[log.lane >= 0]
    between = np.min(np.abs(y[:, None] - centres[None, :]), axis=1) > 0.5
    assert between.sum() > 100
    assert (np.abs(log.heading[log.lane >= 0][between]) > 1e-3).all()
    assert run.collisions == 0
    assert _events(run, EventKind.COLLISION).size == 0


def test_ramp_vehicles_merge_on_their_own_acceleration_lane(run: Simulation) -> None:
    """Every merge of the first on-ramps lies on that ramp's acceleration lane."""
    merges = _events(run, EventKind.MERGE)
    assert merges.size > 20
    for ramp in load_corridor("corridor", {}).road.on_ramps[:2]:
        here = (merges["x"] >= ramp.x) & (merges["x"] <= ramp.end + 60.0)
        assert here.any()


def test_vehicles_leave_by_their_off_ramp(run: Simulation) -> None:
    """A vehicle that left the road by an off-ramp did so at the end of that ramp's road
    (its rear past it)."""
    exits = _events(run, EventKind.EXIT)
    routed = exits[run.demand.route[exits["vehicle"]] >= 0]
    assert routed.size > 0
    far = run.lanes.floats[L_EXIT, run.demand.route[routed["vehicle"]]]
    length = run.fleet.length[routed["vehicle"]]
    assert (routed["x"] - length > far).all()
    assert (routed["x"] - length < far + 5.0).all()


def test_a_scene_with_lanes_the_road_lacks_is_refused() -> None:
    """A demand lane or route that is not a code of the road's table is a clear error."""
    config = load_config("C1")
    kind, scripted = np.zeros(1, dtype=np.int64), np.zeros(1, dtype=bool)
    one = {"t": np.zeros(1), "x": np.zeros(1), "v": np.zeros(1), "kind": kind,
           "scripted": scripted}  # fmt: skip
    lanes, fleet = paper_lanes(config.road), Fleet.build(config, kind, scripted)
    with pytest.raises(ValueError, match=r"demand lanes \[3\]"):
        Scene(lanes, Demand(lane=np.array([3]), route=np.array([-1]), **one), fleet)
    with pytest.raises(ValueError, match=r"demand routes \[1\]"):
        Scene(lanes, Demand(lane=np.array([1]), route=np.array([1]), **one), fleet)
