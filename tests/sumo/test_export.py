"""`hcomc export sumo`: the network's geometry, the vTypes and a clean SUMO run."""

from __future__ import annotations

import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from hcomc.config import ScenarioConfig
from hcomc.rng import make_rng
from hcomc.road import Kind, Lane, lane_centre
from hcomc.sim.demand import generate_demand

sumolib = pytest.importorskip("sumolib")


def test_network_lanes_lie_on_our_lane_centres(c1: ScenarioConfig, c1_scenario: Path) -> None:
    net = sumolib.net.readNet(str(c1_scenario.parent / "road.net.xml"))
    road, width = c1.road, c1.road.lane_width
    expected = {  # edge -> (x0, x1, our lanes by SUMO index)
        "main_up": (0.0, road.ramp_start, (Lane.MAIN_1, Lane.MAIN_2)),
        "ramp": (road.ramp_start, road.accel_lane_start, tuple(Lane)),
        "accel": (road.accel_lane_start, road.accel_lane_end, tuple(Lane)),
        "main_down": (road.accel_lane_end, road.length, (Lane.MAIN_1, Lane.MAIN_2)),
    }
    for edge_id, (x0, x1, lanes) in expected.items():
        edge = net.getEdge(edge_id)
        assert edge.getLaneNumber() == len(lanes)
        for sumo_lane, ours in zip(edge.getLanes(), lanes, strict=True):
            (xa, ya), (xb, yb) = sumo_lane.getShape()[0], sumo_lane.getShape()[-1]
            assert (xa, xb) == pytest.approx((x0, x1), abs=1e-2)
            assert ya == pytest.approx(float(lane_centre(ours, width)), abs=1e-2)
            assert yb == pytest.approx(ya, abs=1e-9)
            assert sumo_lane.getWidth() == pytest.approx(width)
    # the acceleration lane ends: nothing leaves accel_0 downstream
    assert not net.getLane("accel_0").getOutgoing()


def test_vtypes_and_vehicles_come_from_config_and_seeded_demand(
    c1: ScenarioConfig, c1_scenario: Path
) -> None:
    root = ET.parse(c1_scenario.parent / "vehicles.rou.xml").getroot()
    types = {t.get("id"): t.attrib for t in root.iter("vType")}
    for kind, params in (("hdv", c1.hdv), ("cav", c1.cav)):
        t = types[kind]
        assert t["carFollowModel"] == "IDM"
        assert float(t["maxSpeed"]) == pytest.approx(params.desired_speed)
        assert float(t["tau"]) == pytest.approx(params.time_headway)
        assert float(t["minGap"]) == pytest.approx(params.min_gap)
        assert float(t["accel"]) == pytest.approx(params.max_accel)
        assert float(t["decel"]) == pytest.approx(params.comfort_decel)
        assert float(t["delta"]) == pytest.approx(params.exponent)
        assert float(t["length"]) == pytest.approx(c1.road.vehicle_length)
    demand = generate_demand(c1, make_rng(0))
    vehicles = list(root.iter("vehicle"))
    assert len(vehicles) == demand.n
    kinds = np.array([Kind.CAV if v.get("type") == "cav" else Kind.HDV for v in vehicles])
    ids = np.array([int(v.get("id")[1:]) for v in vehicles])
    np.testing.assert_array_equal(kinds, demand.kind[ids])
    depart = np.array([float(v.get("depart")) for v in vehicles])
    np.testing.assert_allclose(depart, demand.t[ids] + c1.warmup, atol=1e-3)
    assert np.all(np.diff(depart) >= 0)  # SUMO needs departures sorted


def test_departures_keep_our_release_positions(c1: ScenarioConfig) -> None:
    from hcomc.sumo.network import road_edges
    from hcomc.sumo.routes import departures

    demand = generate_demand(c1, make_rng(0))
    start = {f"from_{e.id}": e.x0 for e in road_edges(c1)}
    for d in departures(c1, demand):
        x = float(demand.x[d.slot])
        front = start[d.route] + d.pos
        if x - start[d.route] >= c1.road.vehicle_length:
            assert front == pytest.approx(x)  # SUMO's x is ours
        else:  # a front within one length of an edge start moves forward to one length
            assert front - x == pytest.approx(c1.road.vehicle_length - (x - start[d.route]))
        assert d.speed == demand.v[d.slot]
        assert d.depart == pytest.approx(demand.t[d.slot] + c1.warmup)


def test_sumo_runs_the_export_unchanged_without_warnings(c1_scenario: Path, tmp_path: Path) -> None:
    from hcomc.sumo import sumo_binary

    stats = tmp_path / "stats.xml"
    done = subprocess.run(
        [sumo_binary("sumo"), "-c", str(c1_scenario), "--no-step-log", "true",
         "--statistic-output", str(stats), "--tripinfo-output", str(tmp_path / "trips.xml")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "Warning" not in done.stderr, done.stderr
    assert "Error" not in done.stderr, done.stderr
    root = ET.parse(stats).getroot()
    assert int(root.find("teleports").get("total")) == 0
    assert int(root.find("safety").get("collisions")) == 0
    # the ramp vehicle entered on the ramp lane and left the road on the mainline
    trips = {t.get("id"): t for t in ET.parse(tmp_path / "trips.xml").getroot()}
    ramp = [t for t in trips.values() if t.get("departLane") == "ramp_0"]
    assert len(ramp) == 1
    assert ramp[0].get("arrivalLane", "").startswith("main_down")


def test_cli_export_refuses_to_overwrite(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from hcomc.cli import app

    target = tmp_path / "scn"
    first = CliRunner().invoke(app, ["export", "sumo", "C1", "--out", str(target)])
    assert first.exit_code == 0, first.output
    assert (target / "C1.sumocfg").is_file()
    again = CliRunner().invoke(app, ["export", "sumo", "C1", "--out", str(target)])
    assert again.exit_code == 2
    assert "--force" in again.output
