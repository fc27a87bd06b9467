"""A C2 run exported to CommonRoad reads back with commonroad-io, its numbers are the log's
converted (front bumper -> body centre, longitudinal speed -> speed along the heading), and
CommonRoad's XML schema accepts the strict export with VR's planning problem."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("commonroad")

from commonroad.common.file_reader import CommonRoadFileReader
from commonroad.scenario.state import CustomState

from hcomc.commonroad.export import export_commonroad
from hcomc.commonroad.scenario import OBSTACLE_IDS
from hcomc.commonroad.schema import schema_errors, schema_valid
from hcomc.road import Lane
from hcomc.sim.log import SimulationLog

TOLERANCE = 2e-6  # the file's 6 decimals of numbers the log stores as float32


def _log(run: Path) -> SimulationLog:
    return SimulationLog.load(run / "log.npz")


def _cells(log: SimulationLog) -> dict[str, np.ndarray]:
    n = log.n_recorded
    names = ("active", "x", "y", "heading", "v", "a", "lane")
    return {name: np.asarray(getattr(log, name)[:n]) for name in names}


def _expected(log: SimulationLog, i: int, rows: np.ndarray) -> dict[str, np.ndarray]:
    """CommonRoad's states of vehicle i at ``rows``, in closed form from the log."""
    c = _cells(log)
    h = c["heading"][rows, i].astype(np.float64)
    half = 0.5 * float(log.length[i])
    return {
        "x": c["x"][rows, i] - half * np.cos(h),
        "y": c["y"][rows, i] - half * np.sin(h),
        "orientation": h,
        "velocity": c["v"][rows, i] / np.cos(h),
    }


def _states(obstacle: Any) -> dict[str, np.ndarray]:
    """Time steps, centre, orientation and speed of an obstacle's initial state and
    trajectory, as read from the file."""
    states = [obstacle.initial_state, *obstacle.prediction.trajectory.state_list]
    return {
        "step": np.array([s.time_step for s in states]),
        "x": np.array([s.position[0] for s in states]),
        "y": np.array([s.position[1] for s in states]),
        "orientation": np.array([s.orientation for s in states]),
        "velocity": np.array([s.velocity for s in states]),
    }


@pytest.fixture(scope="module")
def exported(c2_run: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("export") / "c2.xml"
    export_commonroad(c2_run, out)
    return out


def test_one_obstacle_per_vehicle_with_its_states(c2_run: Path, exported: Path) -> None:
    log = _log(c2_run)
    active = _cells(log)["active"]
    scenario, problems = CommonRoadFileReader(str(exported)).open()
    on_road = np.flatnonzero(active.sum(axis=0) >= 2)
    assert on_road.size > 10
    assert sorted(o.obstacle_id for o in scenario.dynamic_obstacles) == [
        OBSTACLE_IDS + int(i) for i in on_road
    ]
    assert problems.planning_problem_dict == {}
    assert scenario.dt == pytest.approx(log.dt)
    for obstacle in scenario.dynamic_obstacles:
        i = obstacle.obstacle_id - OBSTACLE_IDS
        rows = np.flatnonzero(active[:, i])
        read = _states(obstacle)
        assert read["step"].tolist() == rows.tolist()  # time step k is row k
        assert obstacle.obstacle_shape.length == pytest.approx(float(log.length[i]))
        assert obstacle.obstacle_shape.width == pytest.approx(float(log.width[i]))
        expected = _expected(log, i, rows)
        for name, values in expected.items():
            np.testing.assert_allclose(read[name], values, rtol=0, atol=TOLERANCE, err_msg=name)


def test_a_lane_change_moves_the_centre_behind_the_front_along_the_heading(
    c2_run: Path, exported: Path
) -> None:
    """Where the heading is not 0, the centre lies L/2 behind the front bumper along it and
    the speed along the heading exceeds the longitudinal one."""
    log = _log(c2_run)
    c = _cells(log)
    row, i = (int(k) for k in np.unravel_index(np.argmax(np.abs(np.nan_to_num(c["heading"]))),
                                               c["heading"].shape))  # fmt: skip
    h = float(c["heading"][row, i])
    assert abs(h) > 0.02  # a vehicle in the middle of a lane change
    scenario, _ = CommonRoadFileReader(str(exported)).open()
    state = scenario.obstacle_by_id(OBSTACLE_IDS + i).state_at_time(row)
    length = float(log.length[i])
    front = state.position + 0.5 * length * np.array([np.cos(state.orientation),
                                                      np.sin(state.orientation)])  # fmt: skip
    np.testing.assert_allclose(front, [c["x"][row, i], c["y"][row, i]], atol=1e-5)
    assert state.velocity == pytest.approx(float(c["v"][row, i]) / np.cos(h), abs=1e-5)
    assert state.velocity > float(c["v"][row, i])


def test_the_plain_export_fails_the_schema_for_the_two_documented_reasons(exported: Path) -> None:
    """Vehicles entering after time step 0 and no planning problem: CommonRoad's 2020a XSD
    rejects both, and nothing else."""
    assert not schema_valid(exported)
    errors = schema_errors(exported)
    late = [e for e in errors if "maxInclusive" in e and "('0')" in e]
    others = [e for e in errors if e not in late]
    assert late
    assert len(others) == 1
    assert "planningProblem" in others[0]


def test_strict_export_with_planning_problem_passes_the_schema(
    c2_run: Path, tmp_path: Path
) -> None:
    log = _log(c2_run)
    c = _cells(log)
    out = tmp_path / "strict.xml"
    summary = export_commonroad(c2_run, out, planning_problem=True, strict=True)
    assert schema_valid(out), schema_errors(out)
    assert summary.schema_errors == ()
    first = np.argmax(c["active"], axis=0)  # each vehicle's first row
    on_ramp = [i for i in np.flatnonzero(c["active"].any(axis=0)).tolist()
               if c["lane"][first[i], i] == Lane.RAMP]  # fmt: skip
    vr = min(on_ramp, key=lambda i: (first[i], i))
    assert summary.vr == vr == log.meta["key_groups"][0]["VR"]
    start = int(first[vr])
    assert summary.first_row == start > 0
    # obstacles: every other vehicle on the road at VR's first row and the row after it
    here = c["active"][start] & c["active"][start + 1]
    here[vr] = False
    scenario, problems = CommonRoadFileReader(str(out)).open()
    assert sorted(o.obstacle_id - OBSTACLE_IDS for o in scenario.dynamic_obstacles) == sorted(
        np.flatnonzero(here).tolist()
    )
    entering = (first > start) & (c["active"].sum(axis=0) >= 2)
    assert list(summary.left_out) == np.flatnonzero(entering).tolist() != []
    for obstacle in scenario.dynamic_obstacles:
        i = obstacle.obstacle_id - OBSTACLE_IDS
        rows = np.flatnonzero(c["active"][:, i])
        rows = rows[rows >= start]
        read = _states(obstacle)
        assert read["step"].tolist() == (rows - start).tolist()
        np.testing.assert_allclose(read["x"], _expected(log, i, rows)["x"], atol=TOLERANCE)
    problem = problems.find_planning_problem_by_id(OBSTACLE_IDS + vr)
    initial = _expected(log, vr, np.array([start]))
    assert problem.initial_state.time_step == 0
    np.testing.assert_allclose(problem.initial_state.position,
                               [initial["x"][0], initial["y"][0]], atol=TOLERANCE)  # fmt: skip
    assert problem.initial_state.velocity == pytest.approx(initial["velocity"][0], abs=TOLERANCE)
    last = int(np.flatnonzero(c["active"][:, vr])[-1])
    goal = problem.goal
    assert (goal.state_list[0].time_step.start, goal.state_list[0].time_step.end) == (
        0,
        last - start,
    )
    (lanelet_id,) = goal.lanelets_of_goal_position[0]
    lanelet = scenario.lanelet_network.find_lanelet_by_id(lanelet_id)
    road = log.meta["config"]["road"]
    np.testing.assert_allclose(
        lanelet.center_vertices, [[road["accel_lane_start"], 0.0], [road["accel_lane_end"], 0.0]]
    )
    # VR as the run drove it reaches its goal, once its centre is in lane 1
    rows = np.flatnonzero(c["active"][:, vr])
    driven = _expected(log, vr, rows)
    reached = [
        int(row - start)
        for k, row in enumerate(rows)
        if goal.is_reached(CustomState(time_step=int(row - start), position=np.array(
            [driven["x"][k], driven["y"][k]]), orientation=float(driven["orientation"][k])))
    ]  # fmt: skip
    assert reached
    merged = rows[np.flatnonzero(driven["y"] > -0.5 * road["lane_width"])[0]] - start
    assert reached[0] == merged


def test_the_road_becomes_ten_linked_lanelets(exported: Path) -> None:
    scenario, _ = CommonRoadFileReader(str(exported)).open()
    network = scenario.lanelet_network
    assert len(network.lanelets) == 10
    ramp = [la for la in network.lanelets if la.center_vertices[0, 1] == pytest.approx(-3.75)]
    assert [(la.center_vertices[0, 0], la.center_vertices[-1, 0]) for la in ramp] == [
        (250.0, 700.0),
        (700.0, 950.0),
    ]
    road, accel = ramp
    assert road.successor == [accel.lanelet_id]
    assert accel.successor == []
    beside = network.find_lanelet_by_id(accel.adj_left)
    assert accel.adj_left_same_direction
    assert beside.adj_right == accel.lanelet_id
    assert beside.center_vertices[0].tolist() == [700.0, 0.0]
    assert accel.line_marking_left_vertices.value == "broad_dashed"
    assert road.line_marking_left_vertices.value == "solid"
