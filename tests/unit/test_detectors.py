"""Virtual induction loops (hcomc.metrics.detectors): closed forms on vehicles at constant
speed, the harmonic/arithmetic mean inequality, and the count of a real run against an
independent count of who passed the detector."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import load_config
from hcomc.metrics.detectors import (
    DETECTOR_COLUMNS,
    VehicleRows,
    _passes,
    crossings,
    detector_table,
    holders,
    vehicle_rows,
)
from hcomc.sim.engine import Simulation
from hcomc.sim.log import SimulationLog


def _constant_speed_log(
    x0: list[float], speeds: list[float], lanes: list[int], length: float = 5.0,
    duration: float = 120.0, dt: float = 0.1,
) -> SimulationLog:  # fmt: skip
    t = np.arange(round(duration / dt) + 1) * dt
    x = np.asarray(x0)[None, :] + t[:, None] * np.asarray(speeds)[None, :]
    n = len(x0)
    shape = x.shape
    return SimulationLog(
        dt=dt, t=t, x=x, y=np.zeros(shape), v=np.broadcast_to(speeds, shape).copy(),
        a=np.zeros(shape), heading=np.zeros(shape), lane=np.broadcast_to(lanes, shape).copy(),
        active=np.ones(shape, dtype=bool), kind=np.zeros(n), length=np.full(n, length),
        width=np.full(n, 1.8), n_recorded=t.size,
    )  # fmt: skip


def test_a_platoon_at_constant_speed_gives_the_closed_forms():
    # 20 vehicles 50 m apart at 25 m/s reach x = 500 m every 2 s from t = (500 - x0) / 25
    x0 = [400.0 - 50.0 * k for k in range(20)]
    log = _constant_speed_log(x0, [25.0] * 20, [1] * 20)
    table = detector_table(log, [500.0], interval=30.0)
    assert list(table.columns) == list(DETECTOR_COLUMNS)
    first = table.iloc[0]
    fronts = (500.0 - np.asarray(x0)) / 25.0  # 4, 6, ..., 42 s
    assert first["count"] == int(((fronts >= 0) & (fronts < 30)).sum()) == 13
    assert first["flow"] == pytest.approx(3600 * 13 / 30)
    assert first["speed"] == pytest.approx(25.0)
    assert first["harmonic_speed"] == pytest.approx(25.0)
    # each vehicle covers the loop for L / v = 0.2 s
    assert first["occupancy"] == pytest.approx(100 * 13 * 0.2 / 30, rel=1e-9)
    assert first["mean_length"] == pytest.approx(5.0)
    assert table.iloc[1]["count"] == 7
    assert table["count"].sum() == 20
    assert (table["begin"].to_numpy() == [0.0, 30.0, 60.0, 90.0]).all()


def test_crossing_times_and_speeds_are_interpolated_between_rows():
    log = _constant_speed_log([0.0], [13.0], [2], dt=0.5, duration=10.0)
    c = crossings(log, 50.0)
    assert c.t_front == pytest.approx([50.0 / 13.0])
    assert c.t_rear == pytest.approx([55.0 / 13.0])
    assert c.speed == pytest.approx([13.0])
    assert c.lane.tolist() == [2]


def test_lanes_are_counted_apart_and_a_vehicle_that_starts_past_the_loop_is_not_counted():
    log = _constant_speed_log([0.0, 10.0, 600.0], [20.0, 30.0, 30.0], [1, 2, 1])
    table = detector_table(log, [300.0], interval=60.0).set_index(["lane", "begin"])
    assert table.loc[(1, 0.0), "count"] == 1
    assert table.loc[(2, 0.0), "count"] == 1
    assert table.loc[(1, 0.0), "speed"] == pytest.approx(20.0)
    assert table.loc[(2, 0.0), "speed"] == pytest.approx(30.0)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(5.0, 40.0), min_size=2, max_size=12))
def test_the_harmonic_mean_speed_never_exceeds_the_arithmetic_one(speeds: list[float]):
    n = len(speeds)
    log = _constant_speed_log([-30.0 * k for k in range(n)], speeds, [1] * n, duration=60.0)
    table = detector_table(log, [200.0], interval=60.0)
    row = table.iloc[0]
    if row["count"]:
        assert row["harmonic_speed"] <= row["speed"] * (1 + 1e-9)
        assert min(speeds) * (1 - 1e-6) <= row["harmonic_speed"]  # the log holds float32


def test_a_run_counts_exactly_the_vehicles_that_drove_past_the_loop():
    log = Simulation(load_config("C1", duration=90.0), 0).run()
    table = detector_table(log, [400.0], interval=30.0)
    frame = log.to_frame()
    path = frame.groupby("vehicle")["x"].agg(["first", "last"])
    # every vehicle logged at one step: it passed x = 400 m iff it was upstream, then past it
    passed = int(((path["first"] < 400.0) & (path["last"] >= 400.0)).sum())
    whole = table[table["end"] <= float(log.t[np.isfinite(log.t)][-1])]
    late = crossings(log, 400.0).t_front >= whole["end"].max()
    assert whole["count"].sum() + int(late.sum()) == passed > 20
    assert set(table["lane"]) == {0, 1, 2}  # the ramp runs beside lane 1 from 250 m
    ramp = frame[frame["lane"] == 0].groupby("vehicle")["x"].agg(["first", "last"])
    on_ramp = int(((ramp["first"] < 400.0) & (ramp["last"] >= 400.0)).sum())
    assert table.loc[table["lane"] == 0, "count"].sum() == on_ramp
    busy = table[table["count"] > 0]
    assert (busy["speed"] > 10.0).all()
    assert ((busy["occupancy"] > 0) & (busy["occupancy"] < 100)).all()


def test_simulate_reports_the_detectors_and_refuses_bad_positions(tmp_path):
    import json

    import pandas as pd
    from typer.testing import CliRunner

    from hcomc.cli import app

    runner = CliRunner()
    out = tmp_path / "run"
    args = ["simulate", "C1", "--duration", "60", "--json", "--detectors", "400, 1200"]
    result = runner.invoke(app, [*args, "--detector-interval", "30", "--out", str(out)])
    assert result.exit_code == 0, result.output
    records = json.loads(result.stdout)["detectors"]
    written = pd.read_csv(out / "detectors.csv")
    assert len(records) == len(written) > 0
    assert {r["x"] for r in records} == {400.0, 1200.0}
    assert {r["end"] - r["begin"] for r in records} == {30.0}
    assert written["count"].sum() == sum(r["count"] for r in records) > 10
    for bad, shown in (("abc", "positions in m"), ("400,5000", "(0, 1500) m")):
        refused = runner.invoke(app, [*args[:-1], bad, "--out", str(tmp_path / "no")])
        assert refused.exit_code == 2
        assert shown in refused.stderr
        assert refused.stderr.strip().count("\n") == 0
        assert not (tmp_path / "no").exists()


@pytest.mark.parametrize(("scenario", "seed"), [("C1", 0), ("C3", 2)])
def test_vehicle_rows_gathers_each_active_cell_with_the_vehicle_holding_its_column(
    scenario: str, seed: int
):
    # the oracle: numpy's scan of the (S, T) transpose, each cell's vehicle the last to take
    # its column at or before its row (holders), against the compiled two-pass gathering
    log = Simulation(load_config(scenario, duration=120.0), seed).run()
    assert log.n_slots < log.n_vehicles  # columns handed on: several vehicles per column
    cells = log.cells
    column, row = np.nonzero(cells["active"].T)
    vehicle = holders(log, row, column)
    rows = vehicle_rows(log)
    expected = {
        "vehicle": vehicle, "row": row, "column": column, "t": log.t[row],
        "x": cells["x"][row, column], "v": cells["v"][row, column],
        "lane": cells["lane"][row, column], "length": np.asarray(log.length)[vehicle],
    }  # fmt: skip
    for name, values in expected.items():
        got = getattr(rows, name)
        assert got.dtype == (
            np.int64 if name in ("vehicle", "row", "column", "lane") else np.float64
        )
        np.testing.assert_array_equal(got, values.astype(got.dtype), err_msg=name)
    # every vehicle's cells together, in time order, and each active row of it once
    assert (np.diff(rows.row)[rows.vehicle[1:] == rows.vehicle[:-1]] > 0).all()
    on_road = {(int(i), int(k)) for i, k in zip(rows.vehicle, rows.row, strict=True)}
    assert len(on_road) == rows.row.size == int(log.active.sum())


def test_vehicle_rows_of_a_log_with_a_column_per_vehicle():
    log = _constant_speed_log([0.0, 30.0, 60.0], [10.0, 12.0, 14.0], [1, 2, 1], duration=2.0)
    rows = vehicle_rows(log)
    assert rows.vehicle.tolist() == rows.column.tolist() == [0] * 21 + [1] * 21 + [2] * 21
    np.testing.assert_array_equal(rows.x, log.x.T.ravel().astype(np.float32))
    assert rows.lane.tolist() == [1] * 21 + [2] * 21 + [1] * 21


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.integers(0, 3), st.integers(0, 2), st.sampled_from([0.0, 5.0, 7.5, 10.0, 12.0, 20.0])
        ),
        max_size=40,
    ),
    st.lists(st.sampled_from([5.0, 7.5, 10.0, 15.0, 20.0]), min_size=1, max_size=5, unique=True),
    st.booleans(),
)
def test_passes_are_those_of_numpys_binary_search(
    entries: list[tuple[int, int, float]], positions: list[float], rear: bool
):
    # the oracle: numpy's searchsorted of every entry, kept for consecutive rows of a vehicle
    # (positions at entries' exact values, vehicles moving back and forth, rows skipped)
    vehicle = np.array([e[0] for e in entries], dtype=np.int64)
    row = np.cumsum([e[1] for e in entries], dtype=np.int64)
    x = np.array([e[2] for e in entries], dtype=np.float64)
    length = np.full(x.size, 2.5)
    zeros = np.zeros(x.size)
    rows = VehicleRows(vehicle, row, row, zeros, x, zeros, row, length)
    where = np.sort(np.array(positions))
    p = x - length if rear else x
    lo = np.searchsorted(where, p[:-1], side="right")
    hi = np.searchsorted(where, p[1:], side="right")
    same = (vehicle[1:] == vehicle[:-1]) & (row[1:] == row[:-1] + 1)
    expected = [(k, j) for k in np.flatnonzero(same) for j in range(lo[k], hi[k])]
    entry, index = _passes(rows, rear, where)
    assert list(zip(entry.tolist(), index.tolist(), strict=True)) == expected
