"""A researcher's own controller, named by its file, in a TOML, ``hcomc run`` and a sweep;
deliberately broken controllers stop with a one-line error or, on request, fall back; a run
whose ramp vehicle never merged is an outcome with empty metrics, never "no disturbance"."""

from __future__ import annotations

import json
import math
import re
import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.experiments.tables import LABELS

CONTROLLERS = '''
import dataclasses

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.interface import MergePlan, Mode
from hcomc.control.fifo import FIFOController


class GapAcceptance:
    """Never cooperates; ``label`` ends up in the plan's reason."""

    name = "gap-acceptance"

    def __init__(self, config: ScenarioConfig, label: str = "own") -> None:
        self.label = label

    def plan(self, view, group, rng):
        return MergePlan(group, Mode.NONE, view.t, reason=self.label)


class Broken(FIFOController):
    """FIFO with one field of every plan spoilt (``field`` = ``value``)."""

    def __init__(self, config: ScenarioConfig, field: str = "merge_x", value: float = 5000.0):
        super().__init__(config)
        self.field, self.value = field, value

    def plan(self, view, group, rng):
        plan = super().plan(view, group, rng)
        value = None if self.field == "vv1" else self.value
        mode = Mode.LONGITUDINAL if self.field == "vv1" else plan.mode
        return dataclasses.replace(plan, **{self.field: value}, mode=mode)


class Raises:
    """A controller with a bug: every plan divides by zero."""

    def __init__(self, config: ScenarioConfig) -> None:
        pass

    def plan(self, view, group, rng):
        return {}[group.vr] / 0
'''

runner = CliRunner()


@pytest.fixture
def own(tmp_path: Path) -> Path:
    path = tmp_path / "own.py"
    path.write_text(textwrap.dedent(CONTROLLERS), encoding="utf-8")
    return path


def _run(*args: str) -> object:
    return runner.invoke(app, ["run", *args, "--seeds", "1", "--workers", "1", "--json"])


def test_a_toml_names_the_controller_and_its_options(own: Path, tmp_path: Path) -> None:
    config = tmp_path / "study.toml"
    config.write_text(
        f'base = "C2"\nduration = 40.0\n\n[control]\ncontroller = "{own}:GapAcceptance"\n\n'
        '[control.options]\nlabel = "mine"\n',
        encoding="utf-8",
    )
    result = _run(str(config))
    assert result.exit_code == 0, result.output
    (row,) = json.loads(result.stdout)
    assert row["configuration"] == f"{own}:GapAcceptance"
    assert row["controller"] == f"{own}:GapAcceptance"
    assert row["mode"] == "none"
    bad = _run(str(config), "--set", "control.options.colour=1")
    assert bad.exit_code == 2
    assert "control.options.colour" in bad.stderr
    assert "allowed: label" in bad.stderr
    assert bad.stderr.strip().count("\n") == 0


@pytest.mark.parametrize(
    ("field", "value", "shown"),
    [("merge_x", 5000.0, "merge_x = 5000"), ("vr_duration", -1.0, "vr_duration = -1"),
     ("vv1", 0.0, "vv1")],
)  # fmt: skip
def test_a_broken_plan_is_a_one_line_error_or_a_recorded_fallback(
    own: Path, field: str, value: float, shown: str
) -> None:
    spec = f"{own}:Broken"
    options = ["--set", f"control.options.field={json.dumps(field)}",
               "--set", f"control.options.value={value}", "--set", "duration=40"]  # fmt: skip
    result = _run("C2", "--controller", spec, *options)
    assert result.exit_code == 2, result.output
    message = result.stderr.strip()
    assert message.count("\n") == 0
    assert "invalid plan" in message
    assert shown in message
    fallback = _run("C2", "--controller", spec, *options, "--set", "on_invalid_plan='fallback'")
    assert fallback.exit_code == 0, fallback.output
    (row,) = json.loads(fallback.stdout)
    assert row["fallback"]
    assert row["mode"] == "none"
    assert row["fallbacks"] >= 1  # recorded, not hidden


@pytest.mark.parametrize("workers", ["1", "2"])
def test_a_raising_controller_is_one_line_with_its_context(own: Path, workers: str) -> None:
    """The message names the controller, what it raised, VR, time, condition and seed, also
    from a worker process; ``hcomc --traceback`` prints the controller's own traceback
    first (its file and line)."""
    args = ["run", "C2", "--controller", f"{own}:Raises", "--seeds", "2", "--workers", workers,
            "--set", "duration=40"]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    message = result.stderr.strip()
    assert message.count("\n") == 0, message
    assert message.startswith("error: controller 'Raises' raised KeyError: ")
    assert re.search(r"while planning for VR \d+ at t = [\d.]+ s \(C2, seed [01]\)", message)
    assert "hcomc --traceback" in message
    traced = runner.invoke(app, ["--traceback", *args])
    assert traced.exit_code == 2
    assert "Traceback (most recent call last)" in traced.stderr
    assert f'File "{own}"' in traced.stderr
    assert "return {}[group.vr] / 0" in traced.stderr
    assert traced.stderr.strip().splitlines()[-1].startswith("error: controller 'Raises' raised")


def test_an_unmerged_run_is_an_outcome_not_a_smooth_run(own: Path) -> None:
    # C1 seed 0 ending at 14 s: VR has entered the control zone and been planned for, but
    # the run ends before it merges (it merges at about 15 s in a longer run)
    result = _run("C1", "--controller", f"{own}:GapAcceptance", "--set", "duration=14")
    assert result.exit_code == 0, result.output
    (row,) = json.loads(result.stdout)
    assert row["vr"] >= 0
    assert row["mode"] == "none"
    assert row["merged"] is False
    assert row["merge_time"] is None
    for metric in LABELS:
        assert row[metric] is None or math.isnan(row[metric]), metric


@pytest.mark.slow
def test_a_sweep_runs_the_controller_beside_the_papers(own: Path, tmp_path: Path) -> None:
    spec = tmp_path / "sweep.toml"
    spec.write_text(
        f'name = "own"\nbase = "C2"\nconfigurations = ["fifo", "{own}:GapAcceptance"]\n'
        "seeds = 1\nduration = 40.0\n",
        encoding="utf-8",
    )
    result = runner.invoke(app, ["sweep", str(spec), "--workers", "1", "--out",
                                 str(tmp_path / "out")])  # fmt: skip
    assert result.exit_code == 0, result.output
    import pandas as pd

    table = pd.read_parquet(tmp_path / "out" / "sweep.parquet")
    assert sorted(table["configuration"]) == sorted(["FIFO", f"{own}:GapAcceptance"])


def test_a_controller_whose_plans_fall_back_is_flagged_in_a_comparison(
    own: Path, tmp_path: Path
) -> None:
    """Every plan of ``Broken`` is invalid; with ``on_invalid_plan = "fallback"`` each becomes
    the safe default. The comparison still scores its runs (VR merges by gap acceptance),
    but counts its fallbacks in the success table and CSV, marks the cell ⚑ and says why, on
    the console and in the report; FIFO's cell shows no fallback. The tables name the
    controller by its class ("Broken"), the runs keep its file (provenance)."""
    import pandas as pd

    spec = f"{own}:Broken"
    args = ["compare", "--controllers", f"fifo,{spec}", "--conditions", "C2", "--seeds", "2",
            "--workers", "1", "--out", str(tmp_path / "cmp"), "--set", "duration=40",
            "--set", "on_invalid_plan='fallback'"]  # fmt: skip
    result = runner.invoke(app, args, terminal_width=400)
    assert result.exit_code == 0, result.output
    assert "runs: 4/4 (100 %)" in result.stderr  # progress, off a terminal as lines
    success = pd.read_csv(tmp_path / "cmp" / "success.csv").set_index("configuration")
    broken, fifo = success.loc["Broken"], success.loc["FIFO"]
    runs = pd.read_parquet(tmp_path / "cmp" / "runs.parquet")
    assert set(runs["configuration"]) == {"FIFO", spec}
    assert broken["fallbacks"] == broken["plans"] >= 2
    assert bool(broken["flagged"])
    assert (fifo["fallbacks"], bool(fifo["flagged"])) == (0, False)
    text = " ".join(result.stdout.split())
    assert f"{broken['plans']}/{broken['plans']} plans fell back ⚑" in text
    assert "note: flagged (more than 50 % of the plans fell back" in text
    assert f"Broken in C2 ({broken['fallbacks']} of {broken['plans']} plans)" in text
    assert f"note: controllers by name: Broken = {spec}" in text
    report = (tmp_path / "cmp" / "report.html").read_text(encoding="utf-8")
    assert "plans fell back ⚑" in report
    assert "flagged (more than 50 % of the plans fell back" in report
