"""The on-ramp measured (hcomc.metrics.ramp): closed forms on a hand-made log and a congested
ramp flow against an independent count from the long-format log."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.metrics.ramp import RAMP_COLUMNS, STOPPED, ramp_summary, ramp_vehicles
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.log.events import EVENT_DTYPE


def test_a_hand_made_ramp_gives_the_closed_forms():
    # vehicle 0 stands on the ramp for 5 of 10 rows and merges; vehicle 1 (mainline) stands
    # in lane 1, which is not the ramp; vehicle 2 enters on the ramp and never merges
    rows, dt = 10, 1.0
    v = np.array([[0.0 if r < 5 else 10.0, 0.0, 0.2] for r in range(rows)])
    lane = np.array([[0, 1, 0]] * rows)
    events = np.array(
        [(-2.0, int(EventKind.INSERTION), 0, -1, 250.0, np.nan),
         (-1.0, int(EventKind.INSERTION), 1, -1, 0.0, np.nan),
         (3.0, int(EventKind.INSERTION), 2, -1, 250.0, np.nan),
         (7.0, int(EventKind.MERGE), 0, -1, 800.0, np.nan)],
        dtype=EVENT_DTYPE,
    )  # fmt: skip
    shape = v.shape
    log = SimulationLog(
        dt=dt, t=np.arange(rows) * dt, x=np.full(shape, 500.0), y=np.zeros(shape), v=v,
        a=np.zeros(shape), heading=np.zeros(shape), lane=lane,
        active=np.ones(shape, dtype=bool), kind=np.zeros(3, dtype=np.int8),
        length=np.full(3, 5.0), width=np.full(3, 1.8), n_recorded=rows,
        meta={"config": load_config("C1").model_dump(mode="json")}, events=events,
    )  # fmt: skip
    table = ramp_vehicles(log)
    assert list(table.columns) == list(RAMP_COLUMNS)
    assert table["vehicle"].tolist() == [0, 2]
    assert table["merged"].tolist() == [True, False]
    assert table["t_merge"].iloc[0] == 7.0
    assert np.isnan(table["t_merge"].iloc[1])
    assert table["standing_s"].tolist() == [5.0, 10.0]
    summary = ramp_summary(log)
    assert summary == pytest.approx(
        {"vehicles": 2, "merged": 1, "merges_per_hour": 360.0, "mean_standing_s": 7.5,
         "max_standing_s": 10.0, "max_queue": 2, "mean_queue": 1.5}
    )  # fmt: skip


def test_a_congested_ramp_flow_counts_what_the_log_shows():
    config = load_config("C4", duration=300.0, demand={"ramp": "flow", "ramp_mean_headway": 2.5})
    log = Simulation(config, 0).run()
    table = ramp_vehicles(log)
    merges = log.events_of(EventKind.MERGE)
    assert table["merged"].sum() == np.isin(merges["vehicle"], table["vehicle"]).sum() > 20
    frame = log.to_frame()
    standing = frame[(frame["lane"] == 0) & (frame["v"] < STOPPED)]
    assert len(standing) > 0  # ramp vehicles did stop and wait
    assert table["standing_s"].sum() == pytest.approx(
        len(standing[standing["vehicle"].isin(table["vehicle"])]) * log.dt
    )
    summary = ramp_summary(log)
    assert summary["max_queue"] == standing.groupby("step").size().max()
    assert summary["vehicles"] == len(table)


def test_simulate_reports_the_ramp():
    import json

    from typer.testing import CliRunner

    from hcomc.cli import app

    result = CliRunner().invoke(app, ["simulate", "paper", "--duration", "120", "--json"])
    assert result.exit_code == 0, result.output
    ramp = json.loads(result.stdout)["ramp"]
    assert ramp["vehicles"] >= ramp["merged"] >= 3
    assert ramp["max_queue"] >= 0
