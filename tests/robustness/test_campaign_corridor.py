"""``hcomc faults`` on a corridor: the V2X channel, the faults and the shield act on a road
with five on-ramps and the controller at every one, through the CLI."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config.impairment_tables import FAULTS
from hcomc.corridor import load_corridor
from hcomc.experiments.corridor.runs import with_configuration
from hcomc.metrics.corridor import CorridorRun, simulate_corridor
from hcomc.robustness.faults import Fault
from hcomc.sim.corridor_scene import corridor_config

runner = CliRunner()
EXAMPLE = (Path(__file__).resolve().parents[2] / "examples" / "my_controller" / "src"
           / "hcomc_ctg" / "controller.py")  # fmt: skip

SHORT = 'base = "corridor"\n[corridor]\nduration = 150.0\n'
"""The corridor preset's first 150 s: merges at its first ramps, some still on the way."""


@pytest.fixture(scope="module")
def campaign(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, pd.DataFrame]:
    folder = tmp_path_factory.mktemp("corridor_faults")
    road = folder / "short.toml"
    road.write_text(SHORT, encoding="utf-8")
    result = runner.invoke(app, [
        "faults", "--seeds", "1", "--conditions", str(road), "--configurations", "HCOMC",
        "--faults", "none,brake-vmf", "--channels", "ideal,lat300-loss30-bursty",
        "--workers", "1", "--out", str(folder / "out"),
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    return str(road), pd.read_csv(folder / "out" / "runs.csv")


@pytest.fixture(scope="module")
def plain(campaign: tuple[str, pd.DataFrame]) -> CorridorRun:
    """The campaign's corridor with HCOMC, seed 0, run without listeners."""
    return simulate_corridor(with_configuration(load_corridor(campaign[0]), "HCOMC"), seed=0)


def _cell(runs: pd.DataFrame, fault: str, channel: str, shield: bool) -> pd.Series:
    rows = runs[(runs.fault == fault) & (runs.channel == channel) & (runs.shield == shield)]
    assert len(rows) == 1
    return rows.iloc[0]


def test_the_nominal_corridor_run_is_the_run_without_listeners(
    campaign: tuple[str, pd.DataFrame], plain: CorridorRun
) -> None:
    """Ideal channel, no fault, no shield: the corridor's own run, figure for figure."""
    road, runs = campaign
    assert len(runs) == 2 * 2 * 2
    assert set(runs.condition) == {road}
    nominal = _cell(runs, "none", "ideal", False)
    assert nominal.collisions == plain.collision_count == 0
    assert nominal.plans == plain.decisions > 10  # plans at several ramps
    assert nominal.min_ttc == pytest.approx(float(plain.merges.min_ttc.min()), rel=1e-12)
    assert nominal.max_drac == pytest.approx(float(plain.merges.max_drac.max()), rel=1e-12)
    merged = plain.merges[plain.merges.merged]
    assert nominal.merge_time == pytest.approx(float(merged.time_to_merge.mean()), rel=1e-12)
    assert set(plain.merges.ramp) >= {"on1", "on2"}


def test_the_fault_is_timed_from_the_first_control_zone_entry(
    campaign: tuple[str, pd.DataFrame], plain: CorridorRun
) -> None:
    """brake-vmf brakes the VMF of the first ramp vehicle to enter a control zone that has
    one, after a delay drawn from the run's seed as on the paper's road; its start is
    reported from the first entry."""
    road, runs = campaign
    groups = plain.log.meta["key_groups"]
    target = next(g for g in groups if g["VMF"] >= 0)
    config = corridor_config(load_corridor(road), duration=150.0, seed=0, log_interval=0.1)
    delay = Fault(FAULTS["brake-vmf"], config, 0).delay
    for _, row in runs[runs.fault == "brake-vmf"].iterrows():
        assert row.fault_vehicle == target["VMF"]
        expected = target["t"] - groups[0]["t"] + delay
        assert row.fault_start == pytest.approx(expected, abs=1e-9)
    for _, row in runs[runs.fault == "none"].iterrows():
        assert row.fault_vehicle == -1
        assert math.isnan(row.fault_start)


def test_the_channel_and_the_shield_act_at_the_ramps(campaign: tuple[str, pd.DataFrame]) -> None:
    """The lossy channel loses plans and leaves CAVs with stale leaders; the shield
    overrides commands; on the ideal channel nothing is lost."""
    _, runs = campaign
    for fault in ("none", "brake-vmf"):
        lossy = _cell(runs, fault, "lat300-loss30-bursty", False)
        assert lossy.plans_lost > 0
        assert lossy.degraded_steps > 0
        ideal = _cell(runs, fault, "ideal", False)
        assert ideal.plans_lost == ideal.degraded_steps == 0
        shielded = _cell(runs, fault, "ideal", True)
        overrides = shielded.shield_brakes + shielded.shield_holds + shielded.shield_releases
        assert overrides > 0
        assert ideal.shield_brakes == ideal.shield_holds == ideal.shield_releases == 0


def test_corridor_conditions_are_checked(tmp_path: Path) -> None:
    """A corridor in SUMO, or one with keys only the paper's conditions take, is a
    one-line error."""
    road = tmp_path / "short.toml"
    road.write_text(SHORT, encoding="utf-8")
    warm = tmp_path / "warm.toml"
    warm.write_text(SHORT + "warmup = 30.0\n", encoding="utf-8")
    for args, fragment in (
        (["--conditions", str(road), "--engine", "sumo"], "engine 'sumo'"),
        (["--conditions", f"C1,{tmp_path / 'none.toml'}"], "--conditions"),
        (["--conditions", str(warm)], "corridor.warmup"),
    ):
        result = runner.invoke(app, ["faults", *args, "--out", str(tmp_path / "x")])
        assert result.exit_code == 2, (args, result.output)
        assert fragment in result.stderr
        assert result.stderr.strip().count("\n") == 0


def test_a_corridor_edited_between_two_runs_of_a_campaign_is_refused(tmp_path: Path) -> None:
    """The campaign's identity holds each corridor's resolved content: a rerun after the
    corridor file changed would mix two roads' runs, and is refused."""
    road = tmp_path / "short.toml"
    road.write_text(SHORT, encoding="utf-8")
    args = ["faults", "--seeds", "1", "--conditions", str(road), "--configurations", "FIFO",
            "--faults", "none", "--channels", "ideal", "--workers", "1",
            "--out", str(tmp_path / "out")]  # fmt: skip
    assert runner.invoke(app, args).exit_code == 0
    assert runner.invoke(app, args).exit_code == 0  # the same road: resumed, nothing to do
    road.write_text(SHORT.replace("150.0", "120.0"), encoding="utf-8")
    edited = runner.invoke(app, args)
    assert edited.exit_code == 2
    assert "another spec" in edited.stderr


def test_any_controller_enters_the_campaign_on_either_road(tmp_path: Path) -> None:
    """``--controllers`` takes what ``hcomc compare`` takes: the example package's
    controller, by file path, runs beside FIFO on a paper condition and on a corridor (at
    every ramp), and its source is part of the campaign's identity."""
    from hcomc.experiments.runner import configuration_label

    spec = f"{EXAMPLE}:ConstantTimeGap"
    road = tmp_path / "short.toml"
    road.write_text(SHORT, encoding="utf-8")
    out = tmp_path / "out"
    result = runner.invoke(app, [
        "faults", "--seeds", "1", "--conditions", f"C2,{road}", "--controllers", f"fifo,{spec}",
        "--faults", "brake-vmf", "--channels", "ideal", "--workers", "1", "--out", str(out),
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    runs = pd.read_csv(out / "runs.csv")
    label = configuration_label(spec)
    assert set(runs.configuration) == {"FIFO", label}
    mine = runs[runs.configuration == label]
    assert len(mine) == 2 * 3  # two roads: shield off and on, and the nominal run
    assert (mine.plans > 0).all()
    faulted = mine[mine.fault == "brake-vmf"]
    assert (faulted.fault_vehicle >= 0).all()
    assert (mine[mine.fault == "none"].fault_vehicle < 0).all()
    identity = json.loads((out / "campaign.json").read_text())
    assert identity["controllers"][label]["class"].endswith(":ConstantTimeGap")
    bad = runner.invoke(app, ["faults", "--controllers", "fifo,nobody.py:X",
                              "--out", str(tmp_path / "x")])  # fmt: skip
    assert bad.exit_code == 2
    assert "--configurations" in bad.stderr
