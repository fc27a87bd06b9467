"""An :class:`~hcomc.commonroad.run.ExportRun` as a CommonRoad scenario, and its file.

:func:`build_scenario` makes the commonroad-io objects: one lanelet per strip, one dynamic
obstacle per track (a rectangle of the vehicle's length and width; its initial state at its
first time step, a trajectory of the states after it) and, asked for, VR's planning problem.
:func:`write_scenario` writes them with ``CommonRoadFileWriter`` as XML.

Identifiers: lanelet ids count from 1; obstacle ids are ``OBSTACLE_IDS + hcomc vehicle id``;
VR's planning problem has the id VR would have as an obstacle (and VR is not an obstacle: in
CommonRoad the planning problem is the vehicle to be planned for).

With a planning problem the scenario starts at VR's first state (CommonRoad's planning
problems start at time step 0), and every other vehicle's track is cut there. Its goal is
VR's merge: its centre in the lane it merges into, beside its acceleration lane, at a time
step up to its last one in the run.

CommonRoad's XML schema (version 2020a) requires every obstacle to start at time step 0 and
a file to hold a planning problem. A run's vehicles enter over time: those that enter after
the first time step are kept (commonroad-io reads and writes them; the CommonRoad dataset
converters write them too) unless ``strict``, which leaves them out so that the file passes
the schema check.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from commonroad.common.common_lanelet import LaneletType, LineMarking
from commonroad.common.file_writer import CommonRoadFileWriter
from commonroad.common.util import FileFormat, Interval
from commonroad.common.writer.file_writer_interface import OverwriteExistingFile
from commonroad.geometry.shape import Rectangle, ShapeGroup
from commonroad.planning.goal import GoalRegion
from commonroad.planning.planning_problem import PlanningProblem, PlanningProblemSet
from commonroad.prediction.prediction import TrajectoryPrediction
from commonroad.scenario.lanelet import Lanelet
from commonroad.scenario.obstacle import DynamicObstacle, ObstacleType
from commonroad.scenario.scenario import Location, Scenario, ScenarioID, Tag
from commonroad.scenario.state import CustomState, ExtendedPMState, InitialState
from commonroad.scenario.trajectory import Trajectory

from hcomc.commonroad.lanes import Strip, StripKind
from hcomc.commonroad.run import ExportRun
from hcomc.commonroad.tracks import Track
from hcomc.sim.manifest import atomic_paths

__all__ = ["OBSTACLE_IDS", "BuiltScenario", "build_scenario", "write_scenario"]

OBSTACLE_IDS = 1_000_000
"""Obstacle id of hcomc vehicle i: ``OBSTACLE_IDS + i`` (lanelet ids stay below it)."""

DECIMALS = 6
"""Decimals written for every number ([m], [rad], [m/s], ...)."""

_LANELET_TYPES = {
    StripKind.MAIN: {LaneletType.HIGHWAY, LaneletType.MAIN_CARRIAGE_WAY},
    StripKind.RAMP: {LaneletType.HIGHWAY, LaneletType.ACCESS_RAMP},
    StripKind.ACCEL: {LaneletType.HIGHWAY, LaneletType.ACCESS_RAMP},
    StripKind.DECEL: {LaneletType.HIGHWAY, LaneletType.EXIT_RAMP},
    StripKind.EXIT: {LaneletType.HIGHWAY, LaneletType.EXIT_RAMP},
}


@dataclass(frozen=True)
class BuiltScenario:
    """The commonroad-io objects of an export and what went into them: hcomc's vehicle ids
    of the obstacles, of VR (None without a planning problem) and of the vehicles left out
    by ``strict``; ``first_row`` is the run's row (sample) of time step 0."""

    scenario: Scenario
    problems: PlanningProblemSet
    obstacles: tuple[int, ...]
    vr: int | None
    left_out: tuple[int, ...]
    first_row: int
    tags: frozenset[Tag]


def build_scenario(run: ExportRun, *, planning_problem: bool = False,
                   strict: bool = False) -> BuiltScenario:  # fmt: skip
    """The scenario of ``run`` (module docstring); ``ValueError`` naming the reason when a
    planning problem is asked for a run without VR."""
    tracks, ego, start = list(run.tracks), None, 0
    if planning_problem:
        vr_track = run.track_of(run.vr) if run.vr is not None else None
        if vr_track is None:
            raise ValueError(f"no planning problem for VR: {run.no_vr}")
        start = vr_track.first_step
        ego = vr_track.from_step(start)
        cut = (t.from_step(start) for t in tracks if t.vehicle != run.vr)
        tracks = [t for t in cut if t is not None]
    left_out = tuple(t.vehicle for t in tracks if strict and t.first_step > 0)
    tracks = [t for t in tracks if t.vehicle not in left_out]
    tags = _tags(run)
    scenario = Scenario(dt=run.dt, scenario_id=_scenario_id(run), tags=set(tags))
    for strip in run.strips:
        scenario.add_objects(_lanelet(strip))
    for track in tracks:
        scenario.add_objects(_obstacle(track))
    problems = PlanningProblemSet()
    if ego is not None:
        problems.add_planning_problem(_planning_problem(scenario, run, ego))
    return BuiltScenario(
        scenario=scenario, problems=problems, obstacles=tuple(t.vehicle for t in tracks),
        vr=ego.vehicle if ego else None, left_out=left_out, first_row=start, tags=tags,
    )  # fmt: skip


def write_scenario(built: BuiltScenario, path: Path, *, source: str, author: str = "hcomc",
                   affiliation: str = "hcomc contributors") -> Path:  # fmt: skip
    """Write ``built`` as CommonRoad XML to ``path`` (atomically: an interrupted write
    leaves an existing file as it was)."""
    writer = CommonRoadFileWriter(
        built.scenario, built.problems, author=author, affiliation=affiliation, source=source,
        tags=set(built.tags), location=Location(), decimal_precision=DECIMALS,
        file_format=FileFormat.XML,
    )  # fmt: skip
    with atomic_paths(path) as (tmp,):
        tmp.unlink()  # the writer asks before replacing a file
        writer.write_to_file(str(tmp), OverwriteExistingFile.ALWAYS)
    return path


def _scenario_id(run: ExportRun) -> ScenarioID:
    """``ZAM_hcomc<Name>-1_<seed + 1>_T-1``: ZAM is CommonRoad's country code of made-up
    places, T says the obstacles follow trajectories."""
    name = "".join(part[:1].upper() + part[1:] for part in re.split(r"[^A-Za-z0-9]+", run.name))
    return ScenarioID(country_id="ZAM", map_name=f"hcomc{name}", map_id=1,
                      configuration_id=run.seed + 1, obstacle_behavior="T",
                      prediction_id=1)  # fmt: skip


def _tags(run: ExportRun) -> frozenset[Tag]:
    tags = {Tag.HIGHWAY, Tag.MULTI_LANE, Tag.MERGING_LANES, Tag.SLIP_ROAD, Tag.SIMULATED,
            Tag.NO_ONCOMING_TRAFFIC, Tag.PARALLEL_LANES}  # fmt: skip
    if not run.corridor:
        tags.add(Tag.TWO_LANE)
    return frozenset(tags)


def _lanelet(strip: Strip) -> Lanelet:
    return Lanelet(
        left_vertices=strip.left, center_vertices=strip.centre, right_vertices=strip.right,
        lanelet_id=strip.id, predecessor=list(strip.predecessors),
        successor=list(strip.successors),
        adjacent_left=strip.left_neighbour or None,
        adjacent_left_same_direction=True if strip.left_neighbour else None,
        adjacent_right=strip.right_neighbour or None,
        adjacent_right_same_direction=True if strip.right_neighbour else None,
        line_marking_left_vertices=LineMarking(strip.left_marking.value),
        line_marking_right_vertices=LineMarking(strip.right_marking.value),
        lanelet_type=set(_LANELET_TYPES[strip.kind]),
    )  # fmt: skip


def _obstacle(track: Track) -> DynamicObstacle:
    shape = Rectangle(length=track.length, width=track.width)
    states = [_state(track, k) for k in range(1, track.n_states)]
    return DynamicObstacle(
        obstacle_id=OBSTACLE_IDS + track.vehicle,
        obstacle_type=ObstacleType(track.vehicle_class),
        obstacle_shape=shape,
        initial_state=InitialState(**_values(track, 0)),
        prediction=TrajectoryPrediction(Trajectory(track.first_step + 1, states), shape),
    )


def _values(track: Track, k: int) -> dict[str, object]:
    s = track.states
    return {
        "position": np.array([s.x[k], s.y[k]]),
        "orientation": float(s.orientation[k]),
        "velocity": float(s.velocity[k]),
        "acceleration": float(s.acceleration[k]),
        "time_step": track.first_step + k,
    }


def _state(track: Track, k: int) -> ExtendedPMState:
    return ExtendedPMState(**_values(track, k))


def _planning_problem(scenario: Scenario, run: ExportRun, ego: Track) -> PlanningProblem:
    """VR's planning problem: from its first state to its merge (module docstring)."""
    values = _values(ego, 0)
    yaw_rate = float(ego.states.orientation[1] - ego.states.orientation[0]) / run.dt
    initial = InitialState(**values, yaw_rate=yaw_rate, slip_angle=0.0)
    goal_ids = list(run.goal_lanelets())
    if not goal_ids:
        raise ValueError(f"no lanelet beside the acceleration lane of VR (vehicle {ego.vehicle})")
    network = scenario.lanelet_network
    area = ShapeGroup([network.find_lanelet_by_id(i).polygon for i in goal_ids])
    goal_state = CustomState(time_step=Interval(0, ego.last_step), position=area)
    goal = GoalRegion([goal_state], lanelets_of_goal_position={0: goal_ids})
    return PlanningProblem(OBSTACLE_IDS + ego.vehicle, initial, goal)
