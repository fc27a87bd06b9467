"""Co-simulation (`--engine sumo`) and cross-validation against our engine.

Tolerance of the uncontrolled cross-validation: 5 % per seed on the mean speed of each main
lane and on the flow past the merge (docs/sumo.md explains the remaining differences).
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import load_config
from hcomc.metrics import METRICS
from hcomc.road import Kind, Lane
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind

pytest.importorskip("libsumo")

from hcomc.sumo.cosim import SumoSimulation
from hcomc.sumo.crossval import traffic_stats

TOLERANCE = 0.05
SEEDS = (0, 1, 3)
"""Seeds whose ramp vehicle SUMO merges uncontrolled (in seed 2 SUMO's gap acceptance keeps it
waiting at the end of the acceleration lane for the whole run, where our engine's MOBIL-based
acceptance merges it)."""


@pytest.mark.parametrize("seed", SEEDS)
def test_uncontrolled_c1_agrees_with_our_engine(seed: int) -> None:
    config = load_config("C1")
    ours = traffic_stats(Simulation(config, seed).run())
    sumo_log = SumoSimulation(config, seed).run()
    theirs = traffic_stats(sumo_log)
    for name in ("speed_lane_1", "speed_lane_2", "flow"):
        a, b = getattr(ours, name), getattr(theirs, name)
        assert b == pytest.approx(a, rel=TOLERANCE), name
    assert sumo_log.meta["engine"] == "sumo"
    assert sumo_log.events_of(EventKind.COLLISION).size == 0
    assert sumo_log.events_of(EventKind.MERGE).size == 1


def test_same_demand_and_same_clock_as_our_engine() -> None:
    config = load_config("C1", duration=20.0)
    ours, sim = Simulation(config, 3), SumoSimulation(config, 3)
    np.testing.assert_array_equal(sim.demand.kind, ours.demand.kind)
    np.testing.assert_array_equal(sim.demand.t, ours.demand.t)
    log, ref = sim.run(), ours.run()
    np.testing.assert_allclose(log.t, ref.t, atol=1e-9)
    np.testing.assert_array_equal(log.kind, ref.kind)
    inserted = log.events_of(EventKind.INSERTION)
    # SUMO inserts the initial fill in its first step, like our engine at t = -warmup
    fill = sim.demand.t == -config.warmup
    first = inserted[np.isin(inserted["vehicle"], np.flatnonzero(fill))]
    assert first.size == fill.sum()
    assert first["t"].max() <= -config.warmup + 2 * config.dt


@pytest.mark.parametrize("controller", ["fifo", "game", "hcomc"])
@pytest.mark.parametrize("seed", [0, 1])
def test_controllers_run_collision_free_and_execute_their_plans(controller: str, seed: int) -> None:
    config = load_config("C1", duration=60.0, control={"controller": controller, "budget": 120})
    sim = SumoSimulation(config, seed)
    log = sim.run()
    assert log.events_of(EventKind.COLLISION).size == 0
    assert log.meta["sumo_collisions"] == 0
    assert log.meta["sumo_teleports"] == 0
    vr = sim.key_group.vr
    merges = log.events_of(EventKind.MERGE)
    assert merges["vehicle"].tolist() == [vr]
    starts = log.events_of(EventKind.LANE_CHANGE_START)
    start = starts[starts["vehicle"] == vr][0]
    # receding horizon as in the engine: plans every replan period until the change starts
    times = np.array([p.t0 for p in sim.decisions])
    gaps = np.diff(times)  # one period apart, or more after a commitment window
    assert (gaps >= config.control.replan_period - 1e-6).all()
    assert times.max() <= start["t"]
    plan = sim.decisions[-1]  # the plan in force when VR's change started
    executed = sim.fleet.kind[vr] == Kind.CAV and np.isfinite(plan.merge_x)
    fell_back = any(e["vehicle"] == vr for e in log.events_of(EventKind.FALLBACK))
    if executed and not fell_back:
        # the commanded lane change never starts before the plan's merge point (VR makes no
        # change of its own while commanded; SUMO's own safety check may delay it) and lasts
        # the plan's duration (lateral speed W / duration)
        assert start["x"] >= plan.merge_x
        took = merges["t"][0] - start["t"]
        assert took == pytest.approx(plan.vr_duration, abs=3 * config.dt)
    assert (log.lane[-1][log.active[-1]] != Lane.RAMP).all()


def test_cli_run_engine_sumo_prints_the_metric_rows_of_our_engine() -> None:
    runner = CliRunner()
    args = ["run", "C1", "--controller", "fifo", "--json", "--workers", "1"]
    ours = json.loads(runner.invoke(app, args).stdout)
    done = runner.invoke(app, [*args, "--engine", "sumo"])
    assert done.exit_code == 0, done.output
    theirs = json.loads(done.stdout)  # stdout is pure JSON (libsumo's notices are kept out)
    assert theirs[0].keys() == ours[0].keys()
    for metric in METRICS:
        if metric == "min_ttc" and theirs[0][metric] is None:
            continue  # inf (no key pair ever closes) is JSON null
        assert np.isfinite(theirs[0][metric]), metric
    assert theirs[0]["vr_kind"] == ours[0]["vr_kind"]  # the same ramp vehicle of the demand


def test_simulate_engine_sumo_log_is_accepted_by_plot_and_export(tmp_path) -> None:
    runner = CliRunner()
    out = tmp_path / "run"
    done = runner.invoke(app, ["simulate", "C1", "--engine", "sumo", "--controller", "hcomc",
                               "--duration", "45", "--out", str(out), "--json"])  # fmt: skip
    assert done.exit_code == 0, done.output
    assert json.loads(done.stdout)["merges"] == 1
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["engine"] == "sumo"
    assert manifest["plans"]
    for kind in ("trajectories", "timespace"):
        png = tmp_path / f"{kind}.png"
        done = runner.invoke(app, ["plot", str(out), "--kind", kind, "--out", str(png)])
        assert done.exit_code == 0, done.output
        assert png.stat().st_size > 10_000
    fcd = tmp_path / "run.xml"
    done = runner.invoke(app, ["export", "trajectories", str(out), "--format", "fcd",
                               "--out", str(fcd)])  # fmt: skip
    assert done.exit_code == 0, done.output


def test_missing_sumo_is_one_line_with_the_install_hint(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "libsumo", None)  # import libsumo -> ImportError
    done = CliRunner().invoke(app, ["run", "C1", "--controller", "fifo", "--engine", "sumo"])
    assert done.exit_code == 2
    assert 'pip install "hcomc[sumo]"' in done.output
    assert "Traceback" not in done.output


def test_side_by_side_reports_sumo_relative_to_ours() -> None:
    import pandas as pd

    from hcomc.sumo.crossval import side_by_side

    runs = pd.DataFrame(
        {
            "configuration": ["FIFO"] * 4,
            "engine": ["hcomc", "sumo", "hcomc", "sumo"],
            "fuel": [2.0, 3.0, 4.0, 3.0],
        }
    )
    (row,) = side_by_side(runs, ["fuel"]).to_dict("records")
    assert (row["hcomc"], row["sumo"]) == (3.0, 3.0)
    assert row["difference"] == 0.0
