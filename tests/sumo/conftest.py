"""SUMO tests need the optional extra ``hcomc[sumo]``; without it they are skipped."""

from __future__ import annotations

from pathlib import Path

import pytest

from hcomc.config import ScenarioConfig, load_config


@pytest.fixture(scope="session")
def c1() -> ScenarioConfig:
    """Condition 1, shortened to keep the SUMO tests fast: long enough for the ramp vehicle
    (released at t = 5 s) to merge and leave the road (near t = 51 s in SUMO, seed 0)."""
    return load_config("C1", duration=60.0)


@pytest.fixture(scope="session")
def c1_scenario(c1: ScenarioConfig, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """C1 exported to SUMO with seed 0."""
    pytest.importorskip("sumo")
    from hcomc.sumo.export import export_scenario

    return export_scenario(c1, 0, tmp_path_factory.mktemp("c1")).sumocfg


@pytest.fixture(scope="session")
def c1_run(c1: ScenarioConfig, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A `hcomc simulate --out` directory of C1 (our engine, no controller, seed 0)."""
    from typer.testing import CliRunner

    from hcomc.cli import app

    out = tmp_path_factory.mktemp("run") / "c1"
    done = CliRunner().invoke(app, ["simulate", "C1", "--duration", str(c1.duration),
                                    "--seed", "0", "--out", str(out), "--json"])  # fmt: skip
    assert done.exit_code == 0, done.output
    return out
