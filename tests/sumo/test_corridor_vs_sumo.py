"""hcomc's corridor engine against SUMO on the `corridor` preset's first 15 minutes, no ramp
control, the same vehicles departing at the same times: the loops count the same traffic
at every cross-section and the mainline's trips take the same time, within 10 %.

Both roads start empty; the loops are compared once the first vehicles could have crossed the
whole corridor (WARM), since the two engines' first vehicles reach the far loops at slightly
different times. The on-ramps' own travel times are not compared: at `on3` and `on4` SUMO's
ramp vehicles creep along the acceleration lane (SUMO's merging, LC2013), ours merge at speed
(docs/sumo.md)."""

from __future__ import annotations

import json
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.corridor import load_corridor

DURATION, WARM = 900.0, 420.0  # [s]


@pytest.mark.slow
def test_the_corridor_engine_agrees_with_sumo_on_flows_and_mainline_travel_time(tmp_path: Path):
    pytest.importorskip("sumo")
    from hcomc.sumo import sumo_binary
    from hcomc.sumo.corridor import export_corridor

    done = CliRunner().invoke(app, ["simulate", "corridor", "--duration", str(DURATION),
                                    "--json", "--out", str(tmp_path / "ours")])  # fmt: skip
    assert done.exit_code == 0, done.output
    assert json.loads(done.stdout)["collisions"] == 0
    trips = pd.read_csv(tmp_path / "ours" / "trips.csv")
    loops = pd.read_csv(tmp_path / "ours" / "detectors.csv")

    exported = export_corridor(load_corridor("corridor"), tmp_path / "sumo")
    tripinfo = tmp_path / "tripinfo.xml"
    subprocess.run(
        [sumo_binary("sumo"), "-c", str(exported.sumocfg), "--end", f"{DURATION:g}",
         "--no-step-log", "true", "--tripinfo-output", str(tripinfo)],
        check=True, capture_output=True, timeout=900,
    )  # fmt: skip
    infos = ET.parse(tripinfo).getroot().iter("tripinfo")
    sumo_main = [float(str(t.get("duration"))) for t in infos
                 if str(t.get("id")).startswith("main_")]  # fmt: skip
    ours_main = trips[(trips.origin == "main") & trips.arrive.notna()].travel_time
    assert len(ours_main) >= 0.9 * len(sumo_main) > 100
    assert ours_main.mean() == pytest.approx(sum(sumo_main) / len(sumo_main), rel=0.1)

    sumo_counts: dict[float, float] = {}
    for e in ET.parse(exported.directory / "detectors.out.xml").getroot().iter("interval"):
        if float(str(e.get("begin"))) >= WARM:
            x = float(str(e.get("id")).split("_")[1])
            sumo_counts[x] = sumo_counts.get(x, 0.0) + float(str(e.get("nVehContrib")))
    ours = loops[loops.begin >= WARM].groupby("x")["count"].sum()
    assert set(ours.index) == set(sumo_counts)
    for x, count in sumo_counts.items():
        assert ours[x] == pytest.approx(count, rel=0.1), x
