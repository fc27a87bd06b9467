"""The command line: summaries, JSON, outputs and one-line errors with exit status 2."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import load_config
from hcomc.sim.log import SimulationLog

runner = CliRunner()


def test_simulate_json_keys_and_values(tmp_path):
    result = runner.invoke(
        app,
        [
            "simulate",
            "C1",
            "--seed",
            "3",
            "--duration",
            "30",
            "--json",
            "--out",
            str(tmp_path / "run"),
        ],
    )
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    for key in (
        "vehicle_steps",
        "collisions",
        "merges",
        "fuel_l",
        "wall_s",
        "mean_speed",
        "vehicles",
    ):
        assert key in summary
    assert summary["seed"] == 3
    assert summary["vehicle_steps"] > 1000
    assert summary["fuel_l"] > 0
    log = SimulationLog.load(tmp_path / "run" / "log.npz")
    assert log.meta["seed"] == 3
    assert log.meta["config"]["duration"] == 30.0
    manifest = json.loads((tmp_path / "run" / "manifest.json").read_text())
    assert {"seed", "config", "hcomc_version", "git_revision"} <= manifest.keys()
    assert np.isfinite(log.x[log.active]).all()


def test_simulate_table_output():
    result = runner.invoke(app, ["simulate", "C2", "--duration", "10"])
    assert result.exit_code == 0, result.output
    for label in ("merges", "collisions", "fuel", "vehicle-steps", "mean speed lane 1"):
        assert label in result.stdout


def test_config_show_round_trips(tmp_path):
    result = runner.invoke(app, ["config", "show", "C3"])
    assert result.exit_code == 0
    path = tmp_path / "c3.toml"
    path.write_text(result.stdout)
    assert load_config(path) == load_config("C3")


def _write(tmp_path, text):
    path = tmp_path / "cfg.toml"
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (lambda p: ["simulate", _write(p, "[demand]\nfoo = 1\n")], ["unknown key 'demand.foo'"]),
        (
            lambda p: ["simulate", _write(p, "[demand]\nmean_headway_main_1 = -2.0\n")],
            ["demand.mean_headway_main_1", "-2.0", "greater than 0"],
        ),
        (
            lambda p: ["simulate", _write(p, "[demand]\ncav_penetration = 1.5\n")],
            ["demand.cav_penetration", "1.5", "less than or equal to 1"],
        ),
        (
            lambda p: ["simulate", _write(p, 'duration = "long"\n')],
            ["'duration'", "'long'", "valid number"],
        ),
        (lambda p: ["simulate", str(p / "missing.toml")], ["missing.toml", "does not exist"]),
        (lambda p: ["simulate", "C7"], ["unknown preset 'C7'", "C1, C2, C3, C4, C5"]),
        (lambda p: ["config", "show", "nope"], ["unknown preset 'nope'"]),
        (lambda p: ["simulate", "C1", "--duration", "-5"], ["'duration'", "-5", "greater than 0"]),
        (lambda p: ["simulate", "C1", "--seed", "-1"], ["--seed", "-1", ">= 0"]),
    ],
)
def test_bad_input_one_line_exit_2(tmp_path, args, fragments):
    result = runner.invoke(app, args(tmp_path))
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    message = result.stderr.strip()
    assert message.count("\n") == 0, message
    for fragment in fragments:
        assert fragment in message


def test_wrong_option_type_is_a_usage_error():
    result = runner.invoke(app, ["simulate", "C1", "--seed", "abc"])
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    assert "Invalid value for '--seed'" in result.output
    assert "valid integer" in result.output
