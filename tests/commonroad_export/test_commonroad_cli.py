"""``hcomc export trajectories RUN --format commonroad`` end to end: runs of the scenario engine
(C2, a corridor of the paper's layout) and of the corridor engine, the planning problem, the
schema-strict file, and the one-line errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("commonroad")

from commonroad.common.file_reader import CommonRoadFileReader
from commonroad_cli import invoke

import hcomc.commonroad
from hcomc.commonroad.scenario import OBSTACLE_IDS
from hcomc.commonroad.schema import schema_valid
from hcomc.corridor import Corridor
from hcomc.corridor.layout import RAMP_SLOPE
from hcomc.sim.log import SimulationLog


def _export(run: Path, out: Path, *options: str) -> tuple[int, str]:
    return invoke("export", "trajectories", str(run), "--format", "commonroad", "--out",
                  str(out), *options)  # fmt: skip


def _error_line(output: str) -> str:
    lines = [line for line in output.splitlines() if line.strip()]
    assert len(lines) == 1, output
    assert lines[0].startswith("error: ")
    return lines[0]


def test_c2_run_exports_one_obstacle_per_vehicle(c2_run: Path, tmp_path: Path) -> None:
    out = tmp_path / "c2.xml"
    code, output = _export(c2_run, out)
    assert code == 0, output
    assert output.startswith(f"wrote {out}")
    log = SimulationLog.load(c2_run / "log.npz")
    rows = np.asarray(log.active[: log.n_recorded]).sum(axis=0)
    scenario, problems = CommonRoadFileReader(str(out)).open()
    assert len(scenario.dynamic_obstacles) == int(np.count_nonzero(rows >= 2))
    assert sum(1 + len(o.prediction.trajectory.state_list)
               for o in scenario.dynamic_obstacles) == int(rows[rows >= 2].sum())  # fmt: skip
    assert f"{len(scenario.dynamic_obstacles)} dynamic obstacles" in output
    assert "not valid against CommonRoad's 2020a XSD" in output
    assert str(scenario.scenario_id) == "ZAM_hcomcC2-1_1_T-1"
    assert problems.planning_problem_dict == {}


def test_planning_problem_and_strict_give_a_schema_valid_file(c2_run: Path,
                                                              tmp_path: Path) -> None:  # fmt: skip
    out = tmp_path / "vr.xml"
    code, output = _export(c2_run, out, "--planning-problem", "--strict")
    assert code == 0, output
    assert "valid against CommonRoad's XSD" in output
    assert schema_valid(out)
    log = SimulationLog.load(c2_run / "log.npz")
    vr = int(log.meta["key_groups"][0]["VR"])
    assert f"planning problem {OBSTACLE_IDS + vr} for VR (vehicle {vr})" in output
    scenario, problems = CommonRoadFileReader(str(out)).open()
    assert list(problems.planning_problem_dict) == [OBSTACLE_IDS + vr]
    assert OBSTACLE_IDS + vr not in {o.obstacle_id for o in scenario.dynamic_obstacles}
    assert all(o.initial_state.time_step == 0 for o in scenario.dynamic_obstacles)


def test_existing_output_needs_force(c2_run: Path, tmp_path: Path) -> None:
    out = tmp_path / "taken.xml"
    out.write_text("keep me", encoding="utf-8")
    code, output = _export(c2_run, out)
    assert code == 2
    line = _error_line(output)
    assert f"option '--out' = '{out}': already exists" in line
    assert "--force" in line
    assert out.read_text(encoding="utf-8") == "keep me"
    code, output = _export(c2_run, out, "--force")
    assert code == 0, output
    assert CommonRoadFileReader(str(out)).open()[0].dt == pytest.approx(0.1)


def test_strict_needs_the_planning_problem(c2_run: Path, tmp_path: Path) -> None:
    code, output = _export(c2_run, tmp_path / "x.xml", "--strict")
    assert code == 2
    assert "option '--strict' needs '--planning-problem'" in _error_line(output)
    assert not (tmp_path / "x.xml").exists()


def test_commonroad_options_belong_to_the_commonroad_format(c2_run: Path,
                                                            tmp_path: Path) -> None:  # fmt: skip
    code, output = invoke("export", "trajectories", str(c2_run), "--format", "fcd", "--out",
                          str(tmp_path / "f.xml"), "--planning-problem")  # fmt: skip
    assert code == 2
    assert "allowed only with --format commonroad" in _error_line(output)


def test_without_the_extra_one_line_names_the_install(
    c2_run: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(hcomc.commonroad, "find_spec", lambda name: None)
    code, output = _export(c2_run, tmp_path / "x.xml")
    assert code == 2
    line = _error_line(output)
    assert "option '--format' = 'commonroad'" in line
    assert "pip install 'hcomc[commonroad]'" in line


def test_a_run_directory_without_a_log(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    code, output = _export(tmp_path / "empty", tmp_path / "x.xml")
    assert code == 2
    assert "holds no log.npz or log.parquet" in _error_line(output)


def test_paper_corridor_runs_in_the_scenario_engine_and_exports(tmp_path: Path) -> None:
    run = tmp_path / "paper"
    code, output = invoke("simulate", "paper", "--duration", "4", "--out", str(run), "--json")
    assert code == 0, output
    code, output = _export(run, tmp_path / "paper.xml")
    assert code == 0, output
    scenario, _ = CommonRoadFileReader(str(tmp_path / "paper.xml")).open()
    assert len(scenario.lanelet_network.lanelets) == 10
    assert str(scenario.scenario_id).startswith("ZAM_hcomcPaper-1_")


def _corridor(run: Path) -> Corridor:
    import json

    return Corridor.model_validate(
        json.loads((run / "manifest.json").read_text(encoding="utf-8"))["config"]
    )


def test_corridor_run_exports_its_sampled_vehicles(corridor_run: Path, tmp_path: Path) -> None:
    out = tmp_path / "corridor.xml"
    code, output = _export(corridor_run, out)
    assert code == 0, output
    samples = pd.read_csv(corridor_run / "trajectories.csv")
    counts = samples.groupby("id").size()
    scenario, _ = CommonRoadFileReader(str(out)).open()
    assert scenario.dt == pytest.approx(0.5)
    assert sorted(o.obstacle_id - OBSTACLE_IDS for o in scenario.dynamic_obstacles) == sorted(
        counts[counts >= 2].index.tolist()
    )
    corridor = _corridor(corridor_run)
    width, length = corridor.road.lane_width, corridor.vehicles["car"].length
    trips = pd.read_csv(corridor_run / "trips.csv").set_index("id")
    cars = samples[samples["id"].map(trips["vclass"]) == "car"]
    on_main = cars[cars["lane"] >= 0].iloc[len(cars) // 2]
    state = scenario.obstacle_by_id(OBSTACLE_IDS + int(on_main["id"])).state_at_time(
        round(on_main["t"] / 0.5)
    )
    np.testing.assert_allclose(
        state.position, [on_main["x"] - length / 2, (on_main["lane"] + 0.5) * width], atol=1e-5
    )
    assert state.velocity == pytest.approx(on_main["v"], abs=1e-5)
    ramp = corridor.road.on_ramps[0]
    on_ramp_road = cars[(cars["lane"] == -1) & (cars["x"] < ramp.x - 50)].iloc[0]
    state = scenario.obstacle_by_id(OBSTACLE_IDS + int(on_ramp_road["id"])).state_at_time(
        round(on_ramp_road["t"] / 0.5)
    )
    angle = math.atan(RAMP_SLOPE)
    d = ramp.x - on_ramp_road["x"]  # along the slanted ramp road, upstream of its junction
    front = np.array([ramp.x - d * math.cos(angle), -0.5 * width - d * math.sin(angle)])
    centre = front - 0.5 * length * np.array([math.cos(angle), math.sin(angle)])
    np.testing.assert_allclose(state.position, centre, atol=1e-5)
    assert state.orientation == pytest.approx(angle, abs=1e-6)
    # the engine's speed runs along the slanted road already: not divided by cos(angle)
    assert state.velocity == pytest.approx(on_ramp_road["v"], abs=1e-5)


def test_corridor_planning_problem_is_the_first_vehicle_of_the_first_on_ramp(
    corridor_run: Path, tmp_path: Path
) -> None:
    out = tmp_path / "vr.xml"
    code, output = _export(corridor_run, out, "--planning-problem", "--strict")
    assert code == 0, output
    assert schema_valid(out)
    trips = pd.read_csv(corridor_run / "trips.csv")
    first_ramp = _corridor(corridor_run).road.on_ramps[0].id
    vr = int(trips[trips["origin"] == first_ramp].sort_values("insert")["id"].iloc[0])
    _, problems = CommonRoadFileReader(str(out)).open()
    assert list(problems.planning_problem_dict) == [OBSTACLE_IDS + vr]


def test_corridor_run_without_trajectories_is_refused(tmp_path: Path) -> None:
    run = tmp_path / "corridor"
    code, output = invoke("simulate", "corridor", "--duration", "5", "--out", str(run), "--json")
    assert code == 0, output
    code, output = _export(run, tmp_path / "x.xml")
    assert code == 2
    line = _error_line(output)
    assert "no trajectories.csv" in line
    assert "--trajectory-interval" in line
