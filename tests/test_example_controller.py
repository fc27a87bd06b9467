"""The example controller package (examples/my_controller) works as its README says: the
constant-time-gap controller loads by file path, and by its entry point once installed, runs
on the SUMO co-simulation and drives the learning environment."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner, Result

from hcomc.cli import app

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "examples" / "my_controller"
SPEC = f"{PACKAGE / 'src' / 'hcomc_ctg' / 'controller.py'}:ConstantTimeGap"
RUN = ["run", "C2", "--controller", SPEC, "--workers", "1", "--json"]


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty working directory: the commands must leave nothing behind."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


def invoke(*args: str) -> Result:
    return CliRunner().invoke(app, list(args))


def rows(done: Result) -> list[dict[str, Any]]:
    assert done.exit_code == 0, done.output
    out: list[dict[str, Any]] = json.loads(done.stdout)
    return out


def test_run_by_file_path_merges_and_takes_its_options(workdir: Path) -> None:
    plain = rows(invoke(*RUN, "--seeds", "2"))
    assert [r["seed"] for r in plain] == [0, 1]
    assert all(r["merged"] for r in plain)
    assert all(r["collisions"] == 0 for r in plain)
    assert {r["controller"] for r in plain} == {SPEC}

    wider = rows(invoke(*RUN, "--seeds", "2", "--set", "control.options.time_gap=2.0"))
    assert all(r["merged"] for r in wider)
    metric = [r["critical_distance"] for r in plain]
    assert [r["critical_distance"] for r in wider] != metric  # the option reached the class
    assert list(workdir.iterdir()) == []


def test_unknown_option_is_a_one_line_error(workdir: Path) -> None:
    done = invoke(*RUN, "--seeds", "1", "--set", "control.options.gap=2.0")
    assert done.exit_code == 2
    message = done.stderr.strip()
    assert "\n" not in message
    assert message.startswith("error: key 'control.options.gap' = 2.0")
    assert message.endswith("allowed: time_gap, lane_change_duration")


@pytest.mark.parametrize("seed", [1, 9])  # seeds in which VMC cooperates to the end
def test_vmc_opens_the_time_gap_by_the_merge(seed: int) -> None:
    """Where VMC cooperates to the end, VR starts its change about ``time_gap * v`` ahead of
    it when the engine replans every second, correcting the controller's constant-speed
    prediction (the engine checks every plan with hcomc.control.validation on the way)."""
    from hcomc.config import load_config
    from hcomc.control.registry import make_controller
    from hcomc.sim.engine import Simulation
    from hcomc.sim.log import EventKind

    gaps = []
    for time_gap in (1.5, 3.0):
        control = {"controller": SPEC, "options": {"time_gap": time_gap}, "replan_period": 1.0}
        config = load_config("C2", control=control)
        log = Simulation(config, seed, controller=make_controller(config)).run()
        plans = log.meta["plans"]
        assert all(p["mode"] == "longitudinal" for p in plans)
        vr, vmc = plans[-1]["group"]["VR"], plans[-1]["group"]["VMC"]
        starts = log.events_of(EventKind.LANE_CHANGE_START)
        k = int(np.searchsorted(log.t, starts["t"][starts["vehicle"] == vr][0]))
        headway = (log.x[k, vr] - config.road.vehicle_length - log.x[k, vmc]) / log.v[k, vr]
        assert headway == pytest.approx(time_gap, rel=0.15)
        gaps.append(headway)
    assert gaps[1] > gaps[0]


def _subprocess_env(site: Path) -> dict[str, str]:
    paths = [str(site), *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
    return {**os.environ, "PYTHONPATH": os.pathsep.join(paths)}


@pytest.mark.slow
def test_installed_package_registers_ctg(tmp_path: Path) -> None:
    """pip builds and installs the package offline; its entry point names the controller."""
    source, site = tmp_path / "source", tmp_path / "site"
    # a copy: the build writes build/ and *.egg-info next to the sources
    shutil.copytree(PACKAGE, source, ignore=shutil.ignore_patterns("build", "*.egg-info"))
    pip = [sys.executable, "-m", "pip", "install", "--no-deps", "--no-build-isolation",
           "--no-index", "--quiet", "--target", str(site), str(source)]  # fmt: skip
    built = subprocess.run(pip, capture_output=True, text=True, check=False)
    assert built.returncode == 0, built.stdout + built.stderr
    env, work = _subprocess_env(site), tmp_path / "work"
    work.mkdir()

    probe = (
        "import json; from importlib.metadata import entry_points; "
        "from hcomc.control.registry import controller_source, registered; "
        "print(json.dumps([[p.name for p in entry_points(group='hcomc.controllers')], "
        "registered(), controller_source('ctg')]))"
    )
    done = subprocess.run([sys.executable, "-c", probe], cwd=work, env=env,
                          capture_output=True, text=True, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    points, names, source_of = json.loads(done.stdout)
    assert "ctg" in points
    assert names["ctg"] == "hcomc_ctg.controller:ConstantTimeGap"
    assert Path(source_of["file"]).is_relative_to(site)  # the installed copy

    cmd = [sys.executable, "-m", "hcomc", "run", "C2", "--controller", "ctg", "--seeds", "1",
           "--workers", "1", "--json"]  # fmt: skip
    done = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    [row] = json.loads(done.stdout)
    assert row["controller"] == "ctg"
    assert row["merged"]
    assert row["collisions"] == 0
    assert list(work.iterdir()) == []


@pytest.mark.slow
def test_runs_on_the_sumo_cosimulation(workdir: Path) -> None:
    pytest.importorskip("libsumo")
    [row] = rows(invoke(*RUN, "--seeds", "1", "--engine", "sumo"))
    assert row["controller"] == SPEC
    assert row["merged"]
    assert row["collisions"] == 0


@pytest.mark.slow
def test_drives_the_learning_environment(workdir: Path) -> None:
    gym = pytest.importorskip("gymnasium")
    import hcomc.envs  # noqa: F401 (registers hcomc/Merge-v0)
    from hcomc.envs.policies import ControllerPolicy, run_episode

    policy = ControllerPolicy(SPEC)
    env = gym.make("hcomc/Merge-v0", scenario="C2", controller=policy.controller)
    result = run_episode(env.unwrapped, policy, seed=3, name=policy.name)
    assert result.merged
    assert not result.collision
    log, _ = env.unwrapped.episode_logs()
    reasons = [plan["reason"] for plan in log.meta["plans"]]
    assert reasons
    assert all(reason.startswith("CTG: ") for reason in reasons)
    assert any(plan["mode"] == "longitudinal" for plan in log.meta["plans"])
