"""Trips, travel times and delays per origin (hcomc.metrics.travel): which vehicles make a
trip, the closed forms of a hand-made log, and a real run."""

from __future__ import annotations

import numpy as np
import pytest

from hcomc.config import load_config
from hcomc.metrics.travel import TRAVEL_COLUMNS, travel_summary, trips
from hcomc.road import Kind
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.log.events import EVENT_DTYPE


def _log(events: list[tuple[float, EventKind, int, float]], kinds: list[Kind]) -> SimulationLog:
    n, shape = len(kinds), (3, len(kinds))
    table = np.array(
        [(t, int(kind), vehicle, -1, x, np.nan) for t, kind, vehicle, x in events],
        dtype=EVENT_DTYPE,
    )
    config = load_config("C1")
    return SimulationLog(
        dt=0.1, t=np.arange(3) * 0.1, x=np.zeros(shape), y=np.zeros(shape), v=np.zeros(shape),
        a=np.zeros(shape), heading=np.zeros(shape), lane=np.ones(shape, dtype=np.int8),
        active=np.ones(shape, dtype=bool), kind=np.asarray(kinds, dtype=np.int8),
        length=np.full(n, 5.0), width=np.full(n, 1.8), n_recorded=3,
        meta={"config": config.model_dump(mode="json")}, events=table,
    )  # fmt: skip


def test_only_trips_from_an_origin_that_ended_in_the_measured_time_count():
    ins, out = EventKind.INSERTION, EventKind.EXIT
    log = _log(
        [
            (0.0, ins, 0, 0.0), (50.0, out, 0, 1500.0),  # a mainline trip
            (-30.0, ins, 1, 300.0), (10.0, out, 1, 1500.0),  # placed on the road: no trip
            (-5.0, ins, 2, 250.0), (40.0, out, 2, 1500.0),  # a ramp trip begun in warm-up
            (-29.0, ins, 3, 0.0), (-1.0, out, 3, 1500.0),  # ended in the warm-up
            (20.0, ins, 4, 0.0),  # still on the road
        ],
        [Kind.HDV, Kind.HDV, Kind.CAV, Kind.HDV, Kind.CAV],
    )  # fmt: skip
    table = trips(log)
    assert list(table.columns) == list(TRAVEL_COLUMNS)
    assert table["vehicle"].tolist() == [2, 0]  # in the order they entered
    assert table["origin"].tolist() == ["ramp", "main"]
    assert table["travel_time"].tolist() == [45.0, 50.0]
    cfg = load_config("C1")
    assert table["delay"].tolist() == pytest.approx(
        [45.0 - 1250.0 / cfg.cav.desired_speed, 50.0 - 1500.0 / cfg.hdv.desired_speed]
    )
    summary = travel_summary(log)
    assert summary["main"] == pytest.approx(
        {"trips": 1, "mean_s": 50.0, "median_s": 50.0, "p95_s": 50.0,
         "mean_delay_s": 50.0 - 1500.0 / cfg.hdv.desired_speed}
    )  # fmt: skip
    assert summary["ramp"]["trips"] == 1


def test_a_run_without_trips_from_an_origin_says_none():
    log = _log([(0.0, EventKind.INSERTION, 0, 0.0)], [Kind.HDV])
    assert travel_summary(log)["main"] == {
        "trips": 0, "mean_s": None, "median_s": None, "p95_s": None, "mean_delay_s": None
    }  # fmt: skip


def test_the_trips_of_a_run_take_at_least_their_free_flow_time():
    log = Simulation(load_config("C1", control={"controller": "fifo"}), 0).run()
    table = trips(log)
    exits = log.events_of(EventKind.EXIT)
    assert len(table) > 20
    assert set(table["vehicle"]) <= set(exits["vehicle"].tolist())
    assert (table["t_out"] >= 0).all()
    assert (table["delay"] > -0.05).all()  # IDM never exceeds the desired speed
    assert table.loc[table["origin"] == "main", "travel_time"].min() >= 1500.0 / 33.3 - 0.05


def test_simulate_reports_the_trips_per_origin():
    import json

    from typer.testing import CliRunner

    from hcomc.cli import app

    result = CliRunner().invoke(app, ["simulate", "C1", "--duration", "60", "--json"])
    assert result.exit_code == 0, result.output
    travel = json.loads(result.stdout)["travel_times"]
    assert set(travel) == {"main", "ramp"}
    assert travel["main"]["trips"] > 10
    assert travel["main"]["mean_s"] >= 1500.0 / 33.3 - 0.05
