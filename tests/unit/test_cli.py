"""The command line: summaries, JSON, outputs and one-line errors with exit status 2."""

from __future__ import annotations

import json
import re

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
        # refused when the run is set up (the log's size), not when the config is loaded
        (
            lambda p: ["simulate", "C1", "--set", "log_memory_limit=0.0001"],
            ["log_memory_limit", "0.0001", "rows x"],
        ),
        (
            lambda p: ["plan", "C1", "--set", "log_memory_limit=0.0001"],
            ["log_memory_limit", "0.0001", "rows x"],
        ),
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


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "C1", "--bogus"], "error: No such option: --bogus (hcomc run -h lists"),
        (["nonsense"], "error: No such command 'nonsense' (hcomc -h lists"),
        (["run"], "error: Missing argument 'CONFIG' (hcomc run -h lists"),
        (["--bogus"], "error: No such option: --bogus (hcomc -h lists"),
        (["simulate", "C1", "--seed", "abc"], "error: Invalid value for '--seed': "),
        (["run", "C1", "--seeds", "0"], "error: option '--seeds' = 0: must be >= 1"),
    ],
)
def test_every_command_line_error_has_one_style(args, message):
    """click's own parse errors read like the commands' checks: one line, ``error:``."""
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    line = result.stderr.strip()
    assert line.count("\n") == 0, line
    assert line.startswith(message), line
    assert "Usage:" not in result.output


# --------------------------------------------------------------------------- a new user's path
def test_simulate_refuses_to_overwrite_a_run_unless_forced(tmp_path):
    out = tmp_path / "run"
    first = runner.invoke(app, ["simulate", "C1", "--duration", "5", "--out", str(out), "--json"])
    assert first.exit_code == 0, first.output
    stamp = (out / "log.npz").read_bytes()
    again = runner.invoke(
        app, ["simulate", "C1", "--duration", "6", "--seed", "2", "--out", str(out)]
    )
    assert again.exit_code == 2
    assert "--force" in again.stderr
    assert "already holds a run" in again.stderr
    assert again.stderr.strip().count("\n") == 0
    assert (out / "log.npz").read_bytes() == stamp  # nothing lost
    forced = runner.invoke(
        app, ["simulate", "C1", "--duration", "6", "--seed", "2", "--out", str(out), "--force"]
    )
    assert forced.exit_code == 0, forced.output
    assert json.loads((out / "summary.json").read_text())["seed"] == 2


@pytest.mark.parametrize("command", ["run", "plan"])
def test_merge_commands_on_the_platoon_preset_say_why_not(command):
    args = [command, "platoon"] + (["--controller", "fifo"] if command == "run" else [])
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert "Traceback" not in result.output
    message = result.stderr.strip()
    assert message.count("\n") == 0
    assert "scenario = 'platoon'" in message
    assert "hcomc simulate" in message


def test_every_command_works_on_the_platoon_preset(tmp_path):
    for args in (
        ["simulate", "platoon", "--duration", "5", "--json"],
        ["config", "show", "platoon"],
    ):
        result = runner.invoke(app, args)
        assert result.exit_code == 0, (args, result.output)


def test_run_without_a_merge_in_time_reports_it_instead_of_crashing():
    result = runner.invoke(app, ["run", "C1", "--controller", "fifo", "--set", "duration=3",
                                 "--workers", "1"])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "no merge planned in seed(s) [0]" in result.stdout


@pytest.mark.parametrize(
    "args",
    [
        ["simulate", "C2", "--duration", "5", "--controller", "HCOMC", "--optimizer", "PSO"],
        ["simulate", "C2", "--duration", "5", "--controller", "Fifo"],
    ],
)
def test_controller_and_optimizer_names_are_case_insensitive(args):
    result = runner.invoke(app, [*args, "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert summary["controller"] == args[args.index("--controller") + 1].lower()
    if "--optimizer" in args:
        assert summary["optimizer"] == "pso"


def test_run_accepts_the_table_spelling_of_a_controller():
    result = runner.invoke(
        app, ["run", "C1", "--controller", "FIFO", "--seeds", "1", "--workers", "1", "--json"]
    )
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)[0]["configuration"] == "FIFO"


@pytest.mark.parametrize(
    ("args", "fragments", "absent"),
    [
        (["run", "C1", "--controller", "lifo"], ["'--controller' = 'lifo'", "fifo, game, hcomc"],
         "--optimizer"),
        (["run", "C1", "--controller", "fifo", "--optimizer", "pso"],
         ["'--optimizer' = 'pso' does not apply", "'fifo'"], None),
        (["simulate", "C1", "--controller", "game", "--optimizer", "sa"],
         ["'--optimizer' = 'sa' does not apply", "'game'"], None),
        (["simulate", "C1", "--optimizer", "ga"],
         ["'--optimizer' = 'ga'", "nsga2, nsga2-pymoo, pso, pso-pymoo, sa, sa-scipy"],
         None),
        (["simulate", "C1", "--set", "cav_penetraton=0.5"],
         ["did you mean 'demand.cav_penetration'?"], None),
        (["simulate", "C1", "--set", "time_headway=1.0"], ["ambiguous", "'hdv.time_headway'"],
         None),
        (["simulate", "C1", "--set", "novalue"], ["'--set' = 'novalue'", "KEY=VALUE"], None),
    ],
)  # fmt: skip
def test_option_errors_name_only_what_the_user_passed(args, fragments, absent):
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    message = result.stderr.strip()
    assert message.count("\n") == 0, message
    for fragment in fragments:
        assert fragment in message
    if absent:
        assert absent not in message


def test_version_and_short_help():
    from hcomc import __version__

    version = runner.invoke(app, ["--version"])
    assert version.exit_code == 0
    assert version.stdout.strip() == f"hcomc {__version__}"
    short = runner.invoke(app, ["simulate", "-h"])
    assert short.exit_code == 0
    assert short.stdout == runner.invoke(app, ["simulate", "--help"]).stdout
    assert "<bool>" not in short.stdout  # flags are shown as flags
    assert "--json " in short.stdout
    assert "Measured duration [s]" in short.stdout  # units are not eaten as markup


@pytest.mark.parametrize("command", ["simulate", "run", "plan", "compare", "reproduce"])
def test_help_names_every_form_of_a_controller(command):
    """A researcher's own controller works wherever a controller is named (a registered
    name, a module or a file), and every such command's help says so."""
    text = " ".join(runner.invoke(app, [command, "--help"], terminal_width=200).stdout.split())
    for form in ("registered name", "package.module:Class", "path/to/file.py:Class"):
        assert form in text, (command, form)


def test_simulate_summary_names_the_controller_and_units():
    result = runner.invoke(app, ["simulate", "C2", "--duration", "5", "--controller", "fifo"])
    assert result.exit_code == 0, result.output
    assert "controller fifo" in result.stdout
    for label in ("mean speed lane 1 [m/s]", "fuel, all vehicles [L]", "wall time [s]",
                  "measured duration [s]"):  # fmt: skip
        assert label in result.stdout


def test_config_show_applies_settings_and_documents_keys(tmp_path):
    result = runner.invoke(app, ["config", "show", "C2", "--set", "cav_penetration=0.5",
                                 "--set", "demand.mean_headway_main_1=4"])  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "cav_penetration = 0.5  # share of CAVs [-]" in result.stdout
    assert "demand.cav_penetration 0.9 -> 0.5" in result.stdout  # description follows
    path = tmp_path / "shown.toml"
    path.write_text(result.stdout)
    loaded = load_config(path)
    assert (loaded.demand.cav_penetration, loaded.demand.mean_headway_main_1) == (0.5, 4.0)


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["plot", "C2", "--kind", "timespace", "--metric", "fuel"], "'--metric' = 'fuel' applies"),
        (["plot", "C2", "--kind", "timespace", "--raw"], "'--raw' applies to --kind contour"),
        (["plot", "results/runs.parquet", "--kind", "metrics", "--seed", "3"],
         "'--seed' = 3 applies only when"),
    ],
)  # fmt: skip
def test_plot_options_that_do_not_apply_are_errors(args, fragment, tmp_path):
    result = runner.invoke(app, [*args, "--out", str(tmp_path / "f.png")])
    assert result.exit_code == 2
    assert fragment in result.stderr
    assert not (tmp_path / "f.png").exists()


def test_set_values_reach_the_run_and_conflicts_with_options_are_errors():
    result = runner.invoke(app, ["simulate", "C1", "--set", "duration=5", "--set",
                                 "seed=2", "--json"])  # fmt: skip
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout)
    assert (summary["seed"], summary["duration_s"]) == (2, 5.0)
    clash = runner.invoke(app, ["simulate", "C1", "--set", "duration=5", "--duration", "6"])
    assert clash.exit_code == 2
    assert "conflicts with '--set duration=5'" in clash.stderr


def test_readme_synopsis_names_every_command_and_option():
    """Every command has a line in the README's synopsis naming each of its options, so the
    synopsis cannot fall behind the commands."""
    import re
    from pathlib import Path

    import typer

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    block = readme.split("## Command line\n\n```text\n", 1)[1].split("```", 1)[0]
    group = typer.main.get_command(app)

    def commands(cmd, path):
        subs = getattr(cmd, "commands", None)
        if subs is None:
            yield path, cmd
            return
        for name, sub in subs.items():
            yield from commands(sub, (*path, name))

    missing = []
    for path, cmd in commands(group, ("hcomc",)):
        lines = [line for line in block.splitlines() if line.startswith(" ".join(path) + " ")]
        options = {o for p in cmd.params for o in p.opts if o.startswith("--")} - {"--help"}
        if not lines:
            missing.append(" ".join(path))
        for option in sorted(options):
            if not any(re.search(rf"{re.escape(option)}\b", line) for line in lines):
                missing.append(f"{' '.join(path)} {option}")
    assert missing == [], missing
    for flag in ("--version", "--traceback"):
        assert f"hcomc {flag}" in block


def test_progress_is_a_bar_on_a_terminal_and_lines_in_a_log(monkeypatch):
    """A terminal gets rich's bar with the counts and the time left; other output (a log, CI)
    lines on stderr at each tenth and at the end, with the time left until then."""
    import io

    from rich.console import Console

    from hcomc.cli import _app

    screen = io.StringIO()
    monkeypatch.setattr(_app, "out", Console(file=screen, force_terminal=True, width=100))
    with _app._progress("runs", 20) as update:
        assert update is not None
        update(5, 20)
    shown = screen.getvalue()  # the bar's last frame, drawn as it closes
    assert "runs" in shown
    assert "5/20" in shown
    assert re.search(r"(-:--:--|\d:\d\d:\d\d)", shown)  # the time left
    log = io.StringIO()
    monkeypatch.setattr(_app, "out", Console(file=io.StringIO(), force_terminal=False))
    monkeypatch.setattr(_app, "err", Console(file=log, force_terminal=False, width=200))
    with _app._progress("cells", 20) as update:
        assert update is not None
        for done in range(1, 21):
            update(done, 20)
    lines = log.getvalue().splitlines()
    assert len(lines) == 10  # 2/20, 4/20, ..., 20/20
    assert lines[0].startswith("cells: 2/20 (10 %), ")
    assert "left" in lines[0]
    assert lines[-1].startswith("cells: 20/20 (100 %), ")
    assert "left" not in lines[-1]
