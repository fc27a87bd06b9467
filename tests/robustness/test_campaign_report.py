"""The campaign's HTML report: its worst runs, re-simulated from the configs it writes, are
the campaign's runs figure for figure."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import load_config
from hcomc.metrics import key_window
from hcomc.metrics.surrogate import closing_metrics, max_drac, min_ttc
from hcomc.robustness.impairments import listeners_of
from hcomc.sim.engine import Simulation
from hcomc.viz.campaign_report import worst_runs

runner = CliRunner()


def test_the_report_links_configs_that_are_the_campaigns_runs(tmp_path: Path) -> None:
    out = tmp_path / "camp"
    result = runner.invoke(app, [
        "faults", "--seeds", "2", "--conditions", "C2", "--controllers", "fifo,hcomc",
        "--faults", "brake-vmf", "--channels", "lat100-loss10", "--workers", "1",
        "--out", str(out),
    ])  # fmt: skip
    assert result.exit_code == 0, result.output
    runs = pd.read_csv(out / "runs.csv")
    shown = worst_runs(runs)
    assert len(shown) == 2  # no collision: each configuration's run of least TTC
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "<table" in page
    for row in shown.to_dict("records"):
        shield = "on" if row["shield"] else "off"
        name = f"C2-{row['configuration']}-{row['fault']}-{row['channel']}-shield-{shield}"
        path = out / "worst" / f"{name}-seed-{row['seed']}.toml"
        assert f"worst/{path.stem}.html" in page
        config = load_config(path)
        assert config.seed == row["seed"]
        log = Simulation(config, listeners=listeners_of(config)).run()
        closing = closing_metrics(log, key_window(log))
        assert closing[min_ttc] == pytest.approx(row["min_ttc"], rel=1e-12)
        assert closing[max_drac] == pytest.approx(row["max_drac"], rel=1e-12)
