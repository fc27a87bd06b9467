"""The ``[v2x]``, ``[[faults]]`` and ``[shield]`` tables of a config: validated like every key,
the same run as the Python listener, acted out by every command that runs a config, and
recorded in the log for the replay."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ConfigError, config_to_toml, load_config
from hcomc.config.impairment_tables import CHANNELS, FAULTS, FaultParams, ShieldParams
from hcomc.corridor import load_corridor
from hcomc.experiments.runner import RunSpec, make_simulation
from hcomc.robustness.impairments import SHIELD_ACTIONS, Impairments, listeners_of
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.viz.inputs import load_log
from hcomc.viz.replay.decisions import timeline_events

runner = CliRunner()

TABLES = {
    "faults": ["brake-vmf"],
    "v2x": {"latency": 0.1, "loss": 0.1},
    "shield": {"enabled": True},
}
"""A fault, a lossy channel and the shield: the campaign's brake-vmf x lat100-loss10 cell."""

FAULTED_TOML = """base = "C2"
duration = 40.0
faults = ["brake-vmf"]

[control]
controller = "fifo"

[v2x]
latency = 0.1
loss = 0.1

[shield]
enabled = true
"""


def _config(**tables: object):
    return load_config("C2", duration=40.0, control={"controller": "fifo"}, **tables)


def _same_log(a: SimulationLog, b: SimulationLog) -> None:
    for column in ("x", "v", "a", "lane"):
        np.testing.assert_array_equal(getattr(a, column), getattr(b, column))
    for field in a.events.dtype.names:  # field by field: NaN equals NaN
        np.testing.assert_array_equal(a.events[field], b.events[field])


def test_the_tables_validate_and_name_presets() -> None:
    """A preset name is the preset's table; the defaults are the nominal run; the resolved
    config (with [[faults]] tables and an unlimited range) reads back as itself."""
    config = _config(faults=["brake-vmf", {"kind": "aggressive_hdv", "time_headway": 0.4}])
    assert config.faults == (FAULTS["brake-vmf"], FaultParams(kind="aggressive_hdv",
                                                               time_headway=0.4))  # fmt: skip
    assert not config.nominal
    assert _config().nominal
    assert _config(faults=["none"], v2x={"update_rate": 5.0}).nominal
    assert not _config(shield={"enabled": True}).nominal
    for annotate in (False, True):
        text = config_to_toml(config, annotate=annotate)
        assert "[[faults]]" in text
        assert math.isinf(config.v2x.range)
        path = Path("resolved.toml")
        path.write_text(text, encoding="utf-8")
        assert load_config(path) == config


@pytest.mark.parametrize(
    ("override", "named"),
    [
        ({"faults": ["brake-x"]}, "brake-vmf"),
        ({"faults": [{"kind": "meteor"}]}, "faults"),
        ({"faults": [{"kind": "emergency_brake", "delay_min": 5.0, "delay_max": 1.0}]}, "delay"),
        ({"faults": ["none"] * 17}, "faults"),
        ({"v2x": {"loss": 1.0}}, "v2x.loss"),
        ({"v2x": {"loss_model": "bursty"}}, "v2x.loss_model"),
        ({"shield": {"brake_min": 0.0}}, "shield.brake_min"),
        ({"shield": {"enable": True}}, "shield.enable"),
    ],
)
def test_bad_values_are_refused_with_their_key(override: dict, named: str) -> None:
    with pytest.raises(ConfigError, match=named.replace(".", r"\.")):
        load_config("C2", **override)


def test_bad_values_are_one_line_errors_through_the_cli() -> None:
    result = runner.invoke(app, ["simulate", "C2", "--set", "v2x.latency=9"])
    assert result.exit_code == 2
    assert "v2x.latency" in result.output
    assert "Traceback" not in result.output
    result = runner.invoke(app, ["run", "C2", "--seeds", "1", "--set", 'faults=["brake"]'])
    assert result.exit_code == 2
    assert "brake-vmf" in result.output
    assert len(result.output.strip().splitlines()) == 1


def test_a_nominal_config_runs_without_listeners() -> None:
    """Defaults: no listener, the engine's own run."""
    assert listeners_of(_config()) == []
    assert listeners_of(load_corridor("corridor")) == []
    assert make_simulation(_config(), 0).listeners == ()


def test_the_tables_are_the_python_listener_bit_for_bit() -> None:
    """A config's tables give the run that the same settings give as a Python listener."""
    config = _config(**TABLES)
    by_config = make_simulation(config, 4)
    assert [type(x) for x in by_config.listeners] == [Impairments]
    by_hand = Impairments(CHANNELS["lat100-loss10"], [FAULTS["brake-vmf"]],
                          ShieldParams(enabled=True))  # fmt: skip
    plain = Simulation(_config(), 4, listeners=[by_hand])
    _same_log(by_config.run(), plain.run())
    assert by_config.listeners[0].summary() == by_hand.summary()  # type: ignore[attr-defined]


def test_the_log_records_each_fault_and_shield_override() -> None:
    """FAULT events name each fault's vehicles (value: its index), the first fault keeps the
    timing it has alone; a SHIELD event per override, its value the action."""
    both = ["brake-vmf", "brake-vnf"]
    v2x = {"latency": 0.3, "loss": 0.3}
    sim = make_simulation(_config(faults=both, v2x=v2x, shield={"enabled": True}), 0)
    alone = make_simulation(_config(faults=["brake-vmf"]), 0)
    log, _ = sim.run(), alone.run()
    impaired, single = sim.listeners[0], alone.listeners[0]
    assert isinstance(impaired, Impairments)
    assert isinstance(single, Impairments)
    group = log.meta["key_groups"][0]
    faults = log.events_of(EventKind.FAULT)
    by_fault = {int(e["value"]): (int(e["vehicle"]), float(e["t"])) for e in faults}
    first, second = impaired.faults.each
    assert by_fault[0] == (group["VMF"], pytest.approx(first.start, abs=log.dt))
    assert by_fault[1] == (group["VNF"], pytest.approx(second.start, abs=log.dt))
    assert faults.size == 2
    assert first.start == single.fault.start
    assert first.start != second.start
    shield = log.events_of(EventKind.SHIELD)
    counts = impaired.shield.counts()
    for k, action in enumerate(SHIELD_ACTIONS):
        assert int((shield["value"] == k).sum()) == counts[action] > 0
    assert shield.size == sum(counts.values())


def test_the_log_records_each_lost_plan() -> None:
    sim = make_simulation(_config(v2x={"loss": 0.9}), 2)
    log = sim.run()
    impaired = sim.listeners[0]
    assert isinstance(impaired, Impairments)
    lost = log.events_of(EventKind.PLAN_LOST)
    assert lost.size == impaired.plans_lost > 0
    vrs = {int(g["VR"]) for g in log.meta["key_groups"]}
    assert set(lost["vehicle"].tolist()) <= vrs


def test_the_log_records_each_long_silence_of_a_key_vehicle() -> None:
    """A bursty channel losing 30 % of the messages: a V2X_SILENT event whenever a key
    vehicle's next state reached the controller more than ``stale_after`` after the one
    before it (measured between broadcasts: whole update periods), none for any other
    vehicle; the ideal channel logs none."""
    v2x = {"latency": 0.3, "loss": 0.3, "loss_model": "gilbert_elliott"}
    sim = make_simulation(_config(v2x=v2x), 2)
    log = sim.run()
    silent = log.events_of(EventKind.V2X_SILENT)
    assert silent.size > 0
    keys = {int(i) for g in log.meta["key_groups"] for r, i in g.items() if r != "t" and i >= 0}
    assert set(silent["vehicle"].tolist()) <= keys
    assert np.all(silent["value"] > 0.5)
    periods = silent["value"] / 0.1
    np.testing.assert_allclose(periods, np.round(periods), atol=1e-6)
    nominal = make_simulation(_config(), 2)
    assert nominal.run().events_of(EventKind.V2X_SILENT).size == 0


@pytest.fixture(scope="module")
def faulted_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("faulted")
    (folder / "faulted.toml").write_text(FAULTED_TOML, encoding="utf-8")
    return folder


def test_simulate_and_replay_show_what_the_tables_did(faulted_dir: Path) -> None:
    out = faulted_dir / "run"
    result = runner.invoke(app, ["simulate", str(faulted_dir / "faulted.toml"), "--seed", "4",
                                 "--out", str(out), "--json"])  # fmt: skip
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output.strip().splitlines()[-1])
    log = load_log(out)
    group = log.meta["key_groups"][0]
    (fault,) = summary["impairments"]["faults"]
    assert fault["kind"] == "emergency_brake"
    assert fault["vehicles"] == [group["VMF"]]
    assert summary["impairments"]["plans_lost"] == log.events_of(EventKind.PLAN_LOST).size
    events = timeline_events(log)
    names = [events["names"][k] for k in events["kind"]]
    assert names.count("FAULT") == 1
    page = faulted_dir / "replay.html"
    result = runner.invoke(app, ["replay", str(out), "--out", str(page)])
    assert result.exit_code == 0, result.output
    assert '"FAULT"' in page.read_text(encoding="utf-8")


def test_run_rows_carry_the_tables(faulted_dir: Path) -> None:
    """``hcomc run`` of the faulted config: every row says what the faults did."""
    result = runner.invoke(app, ["run", str(faulted_dir / "faulted.toml"), "--seeds", "2",
                                 "--json"])  # fmt: skip
    assert result.exit_code == 0, result.output
    rows = pd.DataFrame(json.loads(result.output.strip().splitlines()[-1]))
    assert (rows.fault_kinds == "emergency_brake").all()
    assert (rows.plans_lost >= 0).all()
    assert (rows.shield_brake >= 0).all()
    for _, row in rows.iterrows():
        assert int(row.fault_vehicles) in map(int, row.key_vehicles.split())


def test_faulted_runs_share_the_undisturbed_run_of_their_seed() -> None:
    """The undisturbed run has no ramp vehicle to plan for or to time a fault from: runs
    that differ only in their tables (or controller) share it."""
    nominal = RunSpec("C2", "FIFO", 3, {"duration": 40.0})
    faulted = RunSpec("C2", "HCOMC", 3, {"duration": 40.0, **TABLES})
    assert faulted.reference_key() == nominal.reference_key()
    assert (
        RunSpec("C2", "FIFO", 4, {}).reference_key() != RunSpec("C2", "FIFO", 3, {}).reference_key()
    )


def test_a_corridor_takes_the_tables(tmp_path: Path) -> None:
    """A corridor file's [v2x] and [[faults]]: the controller at every ramp loses plans, the
    fault brakes a key vehicle, and the run's row says so."""
    road = tmp_path / "short.toml"
    road.write_text('base = "corridor"\nfaults = ["brake-vmf"]\n[corridor]\nduration = 150.0\n'
                    "[v2x]\nloss = 0.5\n", encoding="utf-8")  # fmt: skip
    result = runner.invoke(app, ["run", str(road), "--controller", "fifo", "--seeds", "1",
                                 "--json"])  # fmt: skip
    assert result.exit_code == 0, result.output
    (row,) = json.loads(result.output.strip().splitlines()[-1])
    assert row["plans_lost"] > 0
    assert row["fault_kinds"] == "emergency_brake"
    assert int(row["fault_vehicles"]) >= 0
    assert float(row["fault_starts"]) > 0


def test_compare_takes_the_tables_by_set(tmp_path: Path) -> None:
    """``hcomc compare --set``: every controller's runs carry the same fault, channel and
    shield; the faulted vehicle is the seed's VMF for both (same traffic, same timing)."""
    out = tmp_path / "cmp"
    result = runner.invoke(app, [
        "compare", "--controllers", "fifo,game", "--conditions", "C2", "--seeds", "2",
        "--set", 'faults=["brake-vmf"]', "--set", "v2x.loss=0.3", "--set", "shield.enabled=true",
        "--set", "duration=40", "--workers", "1", "--out", str(out),
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    runs = pd.read_csv(out / "runs.csv")
    assert len(runs) == 4
    assert (runs.fault_kinds == "emergency_brake").all()
    by_seed = runs.groupby("seed")
    assert (by_seed.fault_vehicles.nunique() == 1).all()
    assert (by_seed.fault_starts.nunique() == 1).all()


def test_the_learning_environments_refuse_the_tables() -> None:
    """An episode runs the nominal traffic: a table set is refused by its key, not ignored."""
    from hcomc.envs.corridor.env import load_env_corridor
    from hcomc.envs.options import EnvOptions

    with pytest.raises(ConfigError, match="key 'v2x'"):
        EnvOptions(scenario="C2", overrides={"v2x": {"loss": 0.1}}).config()
    with pytest.raises(ConfigError, match="key 'faults'"):
        EnvOptions(scenario="C2", overrides={"faults": ["brake-vmf"]}).config()
    with pytest.raises(ConfigError, match=r"key 'shield\.enabled'"):
        load_env_corridor("corridor", {"shield.enabled": True})
    assert EnvOptions(scenario="C2", overrides={"faults": ["none"]}).config().nominal
