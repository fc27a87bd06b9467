"""A corridor of the paper's layout runs in hcomc's engine (hcomc.corridor.engine) and, exported,
in SUMO: without a merge controller the two agree on the mean travel time of each origin and
on the cross-section flows within 10 %; other corridors are refused with the key that does
not fit (hcomc simulate runs them in the corridor engine, without merge controllers)."""

from __future__ import annotations

import json
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ConfigError, load_config
from hcomc.corridor import load_corridor
from hcomc.corridor.engine import scenario_of

WARM = 120.0  # [s] both roads start empty: flows are compared after this


def test_the_paper_corridor_is_the_road_of_the_conditions():
    scenario = scenario_of(load_corridor("paper", {}))
    assert scenario.road == load_config("C1").road
    assert scenario.demand.mean_headway_main_1 == scenario.demand.mean_headway_main_2 == 5.0
    assert (scenario.demand.ramp, scenario.demand.ramp_mean_headway) == ("flow", 20.0)
    assert scenario.warmup == 0.0


@pytest.mark.parametrize(
    ("change", "key"),
    [({"road": {"lanes": 3}}, "road.lanes"),
     ({"demand": {"main": {"flow": [[0.0, 1440.0], [300.0, 2000.0]]}}}, "demand.main.flow"),
     ({"demand": {"ramp": {"cav_share": 0.5}}}, "demand.ramp.cav_share")],
)  # fmt: skip
def test_other_corridors_are_refused_naming_the_key(change, key, tmp_path: Path):
    import tomli_w

    path = tmp_path / "other.toml"
    path.write_text('base = "paper"\n' + tomli_w.dumps(change), encoding="utf-8")
    with pytest.raises(ConfigError, match=f"key '{key}'"):
        scenario_of(load_corridor(str(path), {}))
    # hcomc simulate runs it in the corridor engine, whose loops come from [detectors]
    refused = CliRunner().invoke(app, ["simulate", str(path), "--detectors", "500"])
    assert refused.exit_code == 2
    assert "option '--detectors'" in refused.stderr
    assert f"key '{key}'" in refused.stderr


@pytest.mark.slow
def test_our_engine_and_sumo_agree_on_travel_times_and_flows(tmp_path: Path):
    from hcomc.sumo import sumo_binary
    from hcomc.sumo.corridor import export_corridor

    ours = CliRunner().invoke(
        app, ["simulate", "paper", "--json", "--detectors", "650,1000", "--detector-interval",
              str(WARM)],
    )  # fmt: skip
    assert ours.exit_code == 0, ours.output
    summary = json.loads(ours.stdout)
    exported = export_corridor(load_corridor("paper", {}), tmp_path / "sumo")
    trips = tmp_path / "trips.xml"
    subprocess.run(
        [sumo_binary("sumo"), "-c", str(exported.sumocfg), "--no-step-log", "true",
         "--tripinfo-output", str(trips)],
        check=True, capture_output=True, timeout=600,
    )  # fmt: skip
    durations: dict[str, list[float]] = {"main": [], "ramp": []}
    for trip in ET.parse(trips).getroot().iter("tripinfo"):
        durations[str(trip.get("id")).split("_")[0]].append(float(str(trip.get("duration"))))
    for origin, values in durations.items():
        mine = summary["travel_times"][origin]
        assert mine["trips"] >= 0.8 * len(values) > 10, origin
        assert mine["mean_s"] == pytest.approx(sum(values) / len(values), rel=0.1), origin
    sumo_flow: dict[float, int] = {}
    for e in ET.parse(exported.directory / "detectors.out.xml").getroot().iter("interval"):
        x = float(str(e.get("id")).split("_")[1])
        if float(str(e.get("begin"))) >= WARM and x in (650.0, 1000.0):
            sumo_flow[x] = sumo_flow.get(x, 0) + int(float(str(e.get("nVehContrib"))))
    our_flow: dict[float, int] = {}
    for row in summary["detectors"]:
        if row["begin"] >= WARM and row["lane"] >= 1:  # the mainline lanes
            our_flow[row["x"]] = our_flow.get(row["x"], 0) + row["count"]
    assert set(our_flow) == set(sumo_flow) == {650.0, 1000.0}
    for x, count in sumo_flow.items():
        assert our_flow[x] == pytest.approx(count, rel=0.1), x
