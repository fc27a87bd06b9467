"""The paper's conditions C1-C5 as corridor presets (``paper-C1`` ... ``paper-C5``): each is the
condition written as a road and a demand, and runs bit for bit as the condition does."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ConfigError, load_config
from hcomc.corridor import corridor_to_toml, load_corridor
from hcomc.corridor.engine import scenario_of, scenario_only
from hcomc.metrics.corridor import simulate_corridor
from hcomc.sim.engine import Simulation

CONDITIONS = ("C1", "C2", "C3", "C4", "C5")


@pytest.mark.parametrize("condition", CONDITIONS)
def test_each_preset_is_its_condition(condition: str) -> None:
    corridor = load_corridor(f"paper-{condition}", {})
    mine = scenario_of(corridor).model_dump()
    theirs = load_config(condition).model_dump()
    assert mine.pop("name") == f"paper-{condition}"
    theirs.pop("name"), mine.pop("description"), theirs.pop("description")
    assert mine == theirs
    # Table I's headways come back exactly from the flows per lane
    main = corridor.demand["main"]
    assert main.lane_flows is not None
    assert [3600.0 / q for q in main.lane_flows] == pytest.approx(
        [theirs["demand"]["mean_headway_main_1"], theirs["demand"]["mean_headway_main_2"]],
        abs=1e-12,
    )


def test_a_preset_written_out_and_read_back_is_the_same_corridor(tmp_path: Path) -> None:
    corridor = load_corridor("paper-C2", {})
    path = tmp_path / "c2.toml"
    path.write_text(corridor_to_toml(corridor), encoding="utf-8")
    assert load_corridor(str(path), {}) == corridor


@pytest.mark.parametrize(("condition", "seed"), [("C2", 3), ("C5", 11)])
def test_a_preset_runs_bit_for_bit_as_its_condition(condition: str, seed: int) -> None:
    ours = Simulation(scenario_of(load_corridor(f"paper-{condition}", {})), seed).run()
    reference = Simulation(load_config(condition), seed).run()
    assert ours.n_steps == reference.n_steps
    cells, expected = ours.cells, reference.cells
    assert cells.keys() == expected.keys()
    for name, values in expected.items():
        assert np.array_equal(cells[name], values, equal_nan=True), name
    assert ours.events.dtype == reference.events.dtype
    for name in reference.events.dtype.names or ():
        assert np.array_equal(ours.events[name], reference.events[name], equal_nan=True), name


def test_the_scenario_only_keys_are_named_and_refused_by_the_corridor_engine() -> None:
    assert scenario_only(load_corridor("paper", {})) is None
    assert scenario_only(load_corridor("corridor", {})) is None
    c3 = load_corridor("paper-C3", {})
    assert scenario_only(c3) == ("corridor.warmup", 30.0)
    no_warmup = load_corridor("paper-C3", {"corridor.warmup": 0.0})
    assert scenario_only(no_warmup) == ("demand.main.lane_flows", [720.0, 1200.0])
    with pytest.raises(
        ValueError, match=r"key 'corridor.warmup' = 30.0: a corridor run does not take it"
    ):
        simulate_corridor(c3)


@pytest.mark.parametrize(
    ("override", "message"),
    [({"demand.main.lane_flows": [720.0]}, "key 'demand.main.lane_flows' = [720.0]: allowed: "
      "one flow per lane: 2"),
     ({"demand.main.flow": 1000.0}, "key 'demand.main.flow' = [[0.0, 1000.0]]: allowed: no "
      "'flow' beside lane_flows"),
     ({"demand.ramp.flow": 100.0}, "key 'demand.ramp.flow' = [[0.0, 100.0]]: allowed: no "
      "'flow' beside a release"),
     ({"demand.main.lane_flows": [0.0, 5.0]}, "key 'demand.main.lane_flows[0]' = 0.0"),
     ({"demand.ramp.release": -1.0}, "key 'demand.ramp.release' = -1.0")],
)  # fmt: skip
def test_contradictions_are_named(override: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(message)):
        load_corridor("paper-C3", override)


def test_lane_flows_belong_to_the_mainline_and_a_release_to_a_ramp() -> None:
    lanes = "key 'demand.ramp.lane_flows' = [90.0, 90.0]: allowed: lane flows at the origin main"
    with pytest.raises(ConfigError, match=re.escape(lanes)):
        load_corridor("paper", {"demand.ramp.lane_flows": [90.0, 90.0]})
    release = "key 'demand.main.release' = 3.0: allowed: a release at an on-ramp only"
    with pytest.raises(ConfigError, match=re.escape(release)):
        load_corridor("paper", {"demand.main.release": 3.0, "demand.main.flow": 0.0})


def test_simulate_and_export_take_a_preset(tmp_path: Path) -> None:
    runner = CliRunner()
    done = runner.invoke(app, ["simulate", "paper-C4", "--seed", "2", "--json"])
    assert done.exit_code == 0, done.output
    reference = runner.invoke(app, ["simulate", "C4", "--seed", "2", "--json"])
    assert reference.exit_code == 0, reference.output
    # the same run: the summaries differ only in the condition's name (and the wall time)
    ours, theirs = json.loads(done.stdout), json.loads(reference.stdout)
    for summary in (ours, theirs):
        del summary["wall_s"], summary["vehicle_steps_per_s"]
    assert ours.pop("scenario") == "paper-C4"
    assert theirs.pop("scenario") == "C4"
    assert ours == theirs
    exported = tmp_path / "c4"
    written = runner.invoke(app, ["export", "sumo", "paper-C4", "--out", str(exported)])
    assert written.exit_code == 0, written.output
    condition = tmp_path / "condition"
    assert runner.invoke(app, ["export", "sumo", "C4", "--out", str(condition)]).exit_code == 0
    # the condition's SUMO scenario: the same network sources and the same vehicles
    for name in ("road.nod.xml", "road.edg.xml", "road.con.xml", "vehicles.rou.xml"):
        assert (exported / name).read_bytes() == (condition / name).read_bytes(), name
    config = (exported / "paper-C4.sumocfg").read_text()
    assert config.replace("paper-C4", "C4") == (condition / "C4.sumocfg").read_text()
