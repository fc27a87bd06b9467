"""hcomc's corridor engine (hcomc.metrics.corridor) on small corridors with known answers:
free-flow travel times, detector and Edie measures of one vehicle in closed form, vehicles
conserved, exits taken, merges on the acceleration lane, lane drops respected, the insertion
backlog reported, determinism, and the command line."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.corridor import Corridor, load_corridor
from hcomc.corridor.layout import lane_numbers
from hcomc.corridor.schedule import departure_times
from hcomc.metrics.corridor import simulate_corridor
from hcomc.metrics.detectors import vehicle_rows

CAR = {"length": 5.0, "desired_speed": 30.0, "max_speed": 50.0, "cav": {}}


def corridor(road: dict[str, Any], demand: dict[str, Any], **tables: Any) -> Corridor:
    """A corridor of cars only (30 m/s), detectors only where ``tables`` put them."""
    data: dict[str, Any] = {
        "corridor": {"duration": 300.0, "seed": 1},
        "road": road,
        "demand": {o: {"classes": {"car": 1.0}, **d} for o, d in demand.items()},
        "vehicles": {"car": CAR},
        "detectors": {"spacing": 0.0, "around_ramps": False, "period": 60.0},
    }
    for key, value in tables.items():
        data[key] = {**data.get(key, {}), **value}
    return Corridor.model_validate(data)


def one_vehicle(**road: Any) -> Corridor:
    """A single vehicle (the first of a 12 veh/h flow departs at 150 s)."""
    return corridor({"lanes": 2, "length": 3000.0, **road}, {"main": {"flow": 12.0}},
                    detectors={"positions": [1000.0]}, corridor={"duration": 450.0})  # fmt: skip


def test_a_lone_vehicle_takes_its_free_flow_time():
    run = simulate_corridor(one_vehicle())
    trip = run.trips.iloc[0]
    assert len(run.trips) == 1
    assert trip.outcome == "arrived"
    # it enters with its front one length in, at its desired speed, and leaves when its rear
    # passes the end: its front drives 3000 m
    exact = 3000.0 / 30.0
    assert trip.travel_time == pytest.approx(exact, abs=0.1 + 1e-9)
    assert trip.delay == pytest.approx(0.0, abs=0.1 + 1e-9)
    assert trip.route_length == pytest.approx(3000.0)


def test_a_speed_zone_adds_its_time():
    run = simulate_corridor(one_vehicle(speed_limits=[{"x0": 1000.0, "x1": 2000.0, "speed": 20.0}]))
    trip = run.trips.iloc[0]
    exact = 995.0 / 30.0 + 1000.0 / 20.0 + 1005.0 / 30.0
    assert trip.delay == pytest.approx(trip.travel_time - exact)
    # the IDM approaches the lower limit from above and leaves it accelerating: a few seconds
    assert 0.0 <= trip.travel_time - exact < 8.0


def test_one_vehicle_on_a_loop_and_in_edies_cells():
    run = simulate_corridor(one_vehicle())
    det = run.detectors
    counted = det[det["count"] > 0]
    assert len(counted) == 1
    assert int(counted["count"].iloc[0]) == 1
    row = counted.iloc[0]
    assert row.speed == pytest.approx(30.0)
    assert row.harmonic_speed == pytest.approx(30.0)
    # occupancy: the body (5 m) covers the loop for 5 / 30 s of the 60 s period
    assert row.occupancy == pytest.approx(100.0 * (5.0 / 30.0) / 60.0, rel=1e-6)
    assert row.mean_length == pytest.approx(5.0)
    grid = run.grid
    # the log's rows from the insertion to the last before the exit (one step less)
    assert grid.distance.sum() == pytest.approx(2995.0, abs=3.0 + 1e-9)
    assert grid.time.sum() == pytest.approx(run.trips.travel_time.iloc[0] - 0.1, abs=1e-6)
    busy = grid[grid.time > 0]
    assert np.allclose(busy.distance / busy.time, 30.0)


def test_edies_cells_sum_every_move_on_the_mainline_once():
    # the oracle: numpy's bincount of each move of a vehicle from one logged row to its next
    # on a mainline lane, into the cell of its midpoint and the period of its start
    c = load_corridor("corridor")
    c = c.model_copy(update={"corridor": c.corridor.model_copy(update={"duration": 300.0})})
    run = simulate_corridor(c)
    rows = vehicle_rows(run.log)
    cell, period = c.detectors.cell_length, c.detectors.period
    n_cells = int(np.ceil(c.road.length / cell))
    n_periods = int(np.ceil(300.0 / period - 1e-9))
    main = lane_numbers(c.road) >= 0
    k = np.flatnonzero(rows.next_is_same() & main[rows.lane[:-1]])
    where = np.clip((0.5 * (rows.x[k] + rows.x[k + 1]) / cell).astype(np.int64), 0, n_cells - 1)
    when = np.clip((rows.t[k] / period).astype(np.int64), 0, n_periods - 1)
    index, size = where * n_periods + when, n_cells * n_periods
    distance = np.bincount(index, rows.x[k + 1] - rows.x[k], size)
    spent = np.bincount(index, rows.t[k + 1] - rows.t[k], size)
    assert k.size > 100_000  # a corridor's five minutes
    np.testing.assert_array_equal(run.grid.distance.to_numpy(), distance)
    np.testing.assert_array_equal(run.grid.time.to_numpy(), spent)


def test_every_vehicle_is_accounted_for_and_counted_once_per_loop():
    demand = {"main": {"flow": 1800.0, "cav_share": 0.3}}
    loops = {"positions": [500.0, 1500.0]}
    c = corridor(
        {"lanes": 2, "length": 2000.0}, demand, detectors=loops, corridor={"duration": 600.0}
    )
    run = simulate_corridor(c)
    schedule = departure_times(c, 600.0)
    assert len(run.trips) == schedule.time.size
    assert np.array_equal(run.trips.depart.to_numpy(), schedule.time)
    assert run.trips.outcome.isin(["arrived", "on_road"]).all()
    assert len(run.collisions) == 0
    for x in (500.0, 1500.0):  # crossed by every vehicle whose front passed x
        passed = run.trips["insert"].notna() & (run.trips.outcome == "arrived")
        counted = run.detectors[run.detectors.x == x]["count"].sum()
        assert counted >= passed.sum()
        on_road_past = len(run.trips) - passed.sum()
        assert counted <= passed.sum() + on_road_past


def test_vehicles_bound_for_an_off_ramp_take_it():
    road = {
        "lanes": 3,
        "length": 4000.0,
        "off_ramps": [{"id": "off", "x": 2500.0, "decel_length": 200.0, "ramp_length": 300.0}],
    }
    c = corridor(road, {"main": {"flow": 2400.0, "destinations": {"exit": 0.7, "off": 0.3}}},
                 corridor={"duration": 600.0})  # fmt: skip
    run = simulate_corridor(c)
    done = run.trips[run.trips.outcome != "on_road"]
    to_off = done[done.destination == "off"]
    assert len(to_off) > 80
    assert (to_off.outcome == "arrived").all()  # none missed its exit
    # the front from one length in to one length past the end of the off-ramp's road
    assert to_off.route_length.to_numpy() == pytest.approx(2700.0 + 300.0)
    assert len(run.collisions) == 0


def test_ramp_vehicles_merge_on_the_acceleration_lane():
    road = {
        "lanes": 2,
        "length": 3000.0,
        "on_ramps": [{"id": "on", "x": 1000.0, "accel_length": 250.0, "ramp_length": 400.0}],
    }
    c = corridor(road, {"main": {"flow": 2000.0}, "on": {"flow": 500.0}},
                 corridor={"duration": 600.0})  # fmt: skip
    run = simulate_corridor(c)
    ramp = run.trips[(run.trips.origin == "on") & run.trips["insert"].notna()]
    merged = ramp[ramp.merge_time.notna()]
    assert len(merged) >= len(ramp) - 3  # the last few may still be on the ramp
    assert merged.merge_x.between(1000.0, 1250.0 + 30.0).all()  # a change ends past its start
    summary = run.summary()["on_ramps"]["on"]
    assert summary["merged"] == len(merged)
    assert summary["entered"] == len(ramp)
    assert len(run.collisions) == 0


def test_nobody_drives_in_a_dropped_lane():
    road = {"lanes": 3, "length": 3000.0, "lane_drops": [{"x": 1500.0, "lanes": 2}]}
    c = corridor(road, {"main": {"flow": 2400.0}}, corridor={"duration": 400.0})
    run = simulate_corridor(c, trajectory_interval=0.5)
    traj = run.trajectories
    assert traj is not None
    assert (traj.lane == 2).any()
    assert not ((traj.lane == 2) & (traj.x > 1500.0)).any()
    assert len(run.collisions) == 0


def test_a_blocked_entrance_is_a_backlog_not_a_loss():
    c = corridor({"lanes": 1, "length": 1500.0}, {"main": {"flow": 4000.0}},
                 corridor={"duration": 300.0})  # fmt: skip
    run = simulate_corridor(c)
    assert len(run.trips) == departure_times(c, 300.0).time.size
    waiting = (run.trips.outcome == "not_inserted").sum()
    assert waiting > 0
    assert run.backlog["main"].max() >= waiting
    inserted = run.trips["insert"].dropna()
    assert (inserted.to_numpy() >= run.trips.depart[inserted.index].to_numpy() - 1e-9).all()


def test_same_seed_same_run_other_seed_other_vehicles():
    c = load_corridor("corridor")
    a, b = simulate_corridor(c, duration=120.0), simulate_corridor(c, duration=120.0)
    assert a.trips.equals(b.trips)
    assert a.detectors.equals(b.detectors)
    other = simulate_corridor(c, seed=7, duration=120.0)
    assert not a.trips.vclass.equals(other.trips.vclass)


def test_the_preset_corridor_runs_without_collisions():
    """A quarter of an hour of the preset: no collision, everyone inserted, and at every
    on-ramp most of the vehicles that entered have merged (the rest queue on the
    acceleration lane or its ramp road)."""
    run = simulate_corridor(load_corridor("corridor"), duration=900.0)
    summary = run.summary()
    assert summary["collisions"] == 0
    assert summary["arrived"] > 500
    assert summary["not_inserted"] == 0
    assert all(r["merged_share"] > 0.75 for r in summary["on_ramps"].values())


def test_simulate_runs_a_corridor_and_refuses_a_controller(tmp_path):
    runner = CliRunner()
    done = runner.invoke(app, ["simulate", "corridor", "--duration", "60", "--json",
                               "--out", str(tmp_path / "run")])  # fmt: skip
    assert done.exit_code == 0, done.output
    summary = json.loads(done.stdout)
    assert summary["corridor"] == "corridor"
    assert summary["duration"] == 60.0
    assert {"origins", "on_ramps", "detectors", "collisions"} <= set(summary)
    for name in ("trips.csv", "detectors.csv", "grid.csv", "manifest.json", "corridor.toml",
                 "corridor.html", "speed_heatmap.png"):  # fmt: skip
        assert (tmp_path / "run" / name).is_file()
    assert (tmp_path / "run" / "speed_heatmap.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    manifest = json.loads((tmp_path / "run" / "manifest.json").read_text())
    assert manifest["seed"] == 0
    assert manifest["config"]["road"]["lanes"] == 3
    assert manifest["trajectory_interval"] == 0.0  # none sampled: the replay says how to
    again = runner.invoke(app, ["simulate", "corridor", "--duration", "60",
                                "--out", str(tmp_path / "run")])  # fmt: skip
    assert again.exit_code == 2
    huge = runner.invoke(app, ["simulate", "corridor", "--duration", "1e12"])
    assert huge.exit_code == 2
    assert "allowed: 0 < duration <= 86400" in huge.stderr
    assert "Traceback" not in huge.output
    scenario = runner.invoke(app, ["simulate", "C1", "--trajectory-interval", "1"])
    assert scenario.exit_code == 2
    assert "option '--trajectory-interval'" in scenario.stderr
    refused = runner.invoke(app, ["simulate", "corridor", "--engine", "sumo"])
    assert refused.exit_code == 2
    assert "option '--engine'" in refused.stderr
