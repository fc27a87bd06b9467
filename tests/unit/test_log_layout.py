"""Tests of the log layout (dtypes, sizes), the event table and reading older log files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.config import ConfigError, load_config
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EVENT_DTYPE, EventKind, SimulationLog
from hcomc.sim.log import files as log_io
from hcomc.sim.log.events import EventTable
from hcomc.sim.log.layout import (
    ARRAY_FIELDS,
    BYTES_PER_CELL,
    CELL_FIELDS,
    DTYPES,
    STATE_FIELDS,
    as_layout,
    bytes_needed,
)
from hcomc.sim.step import build as core_build
from hcomc.sim.step.build import FIRST_SLOTS


def _allocate(n_steps: int, n_vehicles: int, slots: int | None = None) -> SimulationLog:
    return SimulationLog.allocate(
        n_steps,
        n_vehicles,
        dt=0.1,
        kind=np.arange(n_vehicles) % 2,
        length=np.full(n_vehicles, 4.5),
        width=np.full(n_vehicles, 1.8),
        slots=slots,
    )


# ---------------------------------------------------------------------- sizes


def test_cell_costs_22_bytes_and_the_one_hour_figure() -> None:
    assert BYTES_PER_CELL == 5 * 4 + 1 + 1
    # 1 hour at 0.1 s (36 001 rows incl. t = 0) x 2000 columns: cells + t + per vehicle
    # (kind, length, width; slot and span) + per column (owner)
    one_hour = 36_001 * 2000 * 22 + 36_001 * 8 + 2000 * (9 + 24) + 2000 * 8
    assert bytes_needed(36_001, 2000) == one_hour == 1_584_414_008
    assert SimulationLog.bytes_needed(12_001, 2000) / 2**30 == pytest.approx(0.49195, abs=1e-5)
    # the same 2000 vehicles, at most 40 on the road at once: 40 slot columns
    assert bytes_needed(36_001, 2000, 40) == 36_001 * 40 * 22 + 36_001 * 8 + 2000 * 33 + 40 * 8


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 40), st.integers(0, 40), st.none() | st.integers(0, 40))
def test_bytes_needed_is_the_allocated_size(
    n_steps: int, n_vehicles: int, slots: int | None
) -> None:
    log = _allocate(n_steps, n_vehicles, slots)
    assert log.nbytes == bytes_needed(n_steps, n_vehicles, slots)
    for name in ARRAY_FIELDS:
        arr = getattr(log, name)
        assert arr.dtype == DTYPES[name], name
        assert arr.flags.c_contiguous, name
    for name in CELL_FIELDS:
        assert getattr(log, name).shape == (n_steps, n_vehicles)


def test_bytes_needed_rejects_negative_sizes() -> None:
    with pytest.raises(ValueError, match="must be >= 0"):
        bytes_needed(-1, 3)


def test_record_writes_into_the_same_arrays() -> None:
    """A compiled kernel holding the arrays sees every row the log records."""
    log = _allocate(3, 4)
    held = {name: getattr(log, name) for name in ("t", *CELL_FIELDS)}
    ones = np.ones(4)
    log.record(1, 0.1, ones, ones, ones, ones, ones, np.ones(4, dtype=np.int64), ones > 0)
    for name, arr in held.items():
        assert getattr(log, name) is arr, name
    assert held["x"][1].tolist() == [1.0] * 4
    assert held["lane"][1].tolist() == [1] * 4


def test_float32_positions_resolve_the_shipped_roads_to_half_a_millimetre() -> None:
    for name in ("C1", "C2", "C3", "C4", "C5", "platoon"):
        road = load_config(name).road
        spacing = float(np.spacing(np.float32(road.length)))
        assert spacing <= 0.5e-3, name
    assert float(np.spacing(np.float32(2000.0))) == 2.0**-13  # 0.12 mm below 2048 m
    assert float(np.spacing(np.float32(2048.0))) == 2.0**-12  # 0.24 mm from 2048 m


def test_engine_refuses_exactly_above_the_allocated_size() -> None:
    config = load_config("C1", duration=20.0, warmup=0.0, log_interval=0.2)
    log = Simulation(config, 0).log
    n, slots = log.n_vehicles, log.n_slots
    rows = round(20.0 / 0.2) + 1
    need = bytes_needed(rows, n, slots) / 2**30
    sim = Simulation(config.model_copy(update={"log_memory_limit": need * (1 + 1e-9)}), 0)
    assert sim.log.nbytes == bytes_needed(rows, n, slots)
    assert sim.log.n_steps == rows
    with pytest.raises(ConfigError, match=rf"\({rows} rows x {slots} vehicles on the road"):
        Simulation(config.model_copy(update={"log_memory_limit": need * (1 - 1e-6)}), 0)


def test_a_log_that_grows_its_columns_logs_the_same_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """A log starting with 4 slot columns grows as vehicles enter (at once to the vehicles on
    the road at its first row, then doubling): the same cells as a log that never grows, and
    the limit checked again at each growth."""
    config = load_config("C1", duration=60.0, log_interval=0.1)
    plain = Simulation(config, 0)
    plain.run()
    assert FIRST_SLOTS > plain.log.n_slots > 8  # about 20 vehicles on the road at once
    monkeypatch.setattr(core_build, "initial_slots", lambda demand: 4)
    grown = Simulation(config, 0)
    assert grown.log.n_slots == 4
    grown.run()
    for name in CELL_FIELDS:
        np.testing.assert_array_equal(getattr(grown.log, name), getattr(plain.log, name))
    np.testing.assert_array_equal(grown.log.slot, plain.log.slot)
    np.testing.assert_array_equal(grown.log.span, plain.log.span)
    rows, n = grown.log.n_steps, grown.log.n_vehicles
    first = int(plain.log.active[0].sum())  # on the road at the first row: more than 2 x 4
    assert first > 8
    limit = bytes_needed(rows, n, first - 1) / 2**30  # room for 4 columns, not for `first`
    sim = Simulation(config.model_copy(update={"log_memory_limit": limit}), 0)
    with pytest.raises(ConfigError, match=rf"\({rows} rows x {first} vehicles on the road"):
        sim.run()


# ---------------------------------------------------------------------- conversion


def test_as_layout_keeps_conforming_arrays_and_converts_others() -> None:
    x = np.zeros((2, 3), dtype=np.float32)
    assert as_layout("x", x) is x
    x64 = np.array([[1.0 / 3.0, 2000.0001]])
    got = as_layout("x", x64)
    assert got.dtype == np.float32
    np.testing.assert_array_equal(got, x64.astype(np.float32))
    fortran = np.asfortranarray(np.zeros((2, 3), dtype=np.float32))
    assert as_layout("v", fortran).flags.c_contiguous
    assert as_layout("lane", np.array([[-1, 0, 2]])).dtype == np.int8
    with pytest.raises(ValueError, match="lane"):
        as_layout("lane", np.array([[0, 300]]))
    with pytest.raises(ValueError, match="active"):
        as_layout("active", np.array([[0, 2]]))
    with pytest.raises(ValueError, match="kind"):
        as_layout("kind", np.array([0.5]))


def _float64_arrays(n_steps: int, n_vehicles: int) -> dict[str, np.ndarray]:
    """Arrays as an older writer could have saved them: float64 states, int64 lanes."""
    rng = np.random.default_rng(3)
    active = rng.random((n_steps, n_vehicles)) < 0.6
    arrays: dict[str, np.ndarray] = {"t": 0.1 * np.arange(n_steps), "active": active}
    for name in STATE_FIELDS:
        arrays[name] = np.where(active, rng.uniform(-5, 1900, (n_steps, n_vehicles)), np.nan)
    arrays["lane"] = np.where(active, rng.integers(0, 3, (n_steps, n_vehicles)), -1)
    arrays["kind"] = np.arange(n_vehicles) % 2
    arrays["length"] = np.full(n_vehicles, 4.6)
    arrays["width"] = np.full(n_vehicles, 1.9)
    return arrays


def _header(n_steps: int, n_vehicles: int) -> dict[str, object]:
    return {
        "format_version": 1,
        "n_steps": n_steps,
        "n_vehicles": n_vehicles,
        "dt": 0.1,
        "n_recorded": n_steps,
        "meta": {"seed": 1},
    }


def _check_converted(log: SimulationLog, arrays: dict[str, np.ndarray]) -> None:
    for name in ARRAY_FIELDS:
        got = getattr(log, name)
        assert got.dtype == DTYPES[name], name
        np.testing.assert_array_equal(got, arrays[name].astype(DTYPES[name]), err_msg=name)


def test_float64_npz_of_an_older_writer_loads_as_float32(tmp_path: Path) -> None:
    arrays = _float64_arrays(5, 4)
    events = np.array([(0.2, 3, 1, -1, 812.5, np.nan)], dtype=EVENT_DTYPE)
    path = tmp_path / "old.npz"
    np.savez_compressed(path, header=np.array(json.dumps(_header(5, 4))), events=events, **arrays)
    log = SimulationLog.load(path)
    _check_converted(log, arrays)
    assert log.events_of(EventKind.MERGE)["x"].tolist() == [812.5]
    # and the converted log round-trips with its own dtypes
    back = SimulationLog.load(log.save(tmp_path / "new.npz"))
    _check_converted(back, arrays)


def test_float64_parquet_of_an_older_writer_loads_as_float32(tmp_path: Path) -> None:
    arrays = _float64_arrays(5, 4)
    steps, vehicles = np.nonzero(arrays["active"])
    columns = {"step": steps, "t": arrays["t"][steps], "vehicle": vehicles}
    for name in (*STATE_FIELDS, "lane"):
        columns[name] = arrays[name][steps, vehicles]  # float64 / int64 columns
    header = _header(5, 4) | {"token": "abc"}
    header["t"] = log_io._b64(arrays["t"], "<f8")
    header["kind"] = log_io._b64(arrays["kind"], "<i1")
    header["length"] = log_io._b64(arrays["length"], "<f4")
    header["width"] = log_io._b64(arrays["width"], "<f4")
    table = pa.table(columns).replace_schema_metadata(
        {log_io._PARQUET_META_KEY: json.dumps(header).encode()}
    )
    path = tmp_path / "old.parquet"
    pq.write_table(table, path)
    ev = pa.table({name: np.zeros(0, EVENT_DTYPE)[name] for name in EVENT_DTYPE.names or ()})
    ev = ev.replace_schema_metadata(
        {log_io._PARQUET_EVENTS_META_KEY: json.dumps({"token": "abc"}).encode()}
    )
    pq.write_table(ev, log_io.events_path(path))
    _check_converted(SimulationLog.load(path), arrays)


# ---------------------------------------------------------------------- events


def test_event_table_grows_and_keeps_every_event() -> None:
    table = EventTable(10)
    n = 1000  # well past the initial capacity, several doublings
    for i in range(n):
        table.add(float(n - i) / 10.0, i % 9, i % 10, other=(i + 1) % 10 - 1, x=float(i))
    assert len(table) == n
    ev = table.sorted()
    assert ev.dtype == EVENT_DTYPE
    assert ev.size == n
    np.testing.assert_array_equal(ev["x"], np.arange(n - 1, -1, -1, dtype=float))
    assert np.all(np.diff(ev["t"]) > 0)
    assert table.nbytes < 2 * n * EVENT_DTYPE.itemsize
    assert EVENT_DTYPE.itemsize == 41


def test_event_table_sorts_stably_and_copies() -> None:
    table = EventTable(3, np.array([(1.0, 0, 0, -1, np.nan, np.nan)], dtype=EVENT_DTYPE))
    table.add(0.5, EventKind.EXIT, 2)
    table.add(1.0, EventKind.MERGE, 1)
    ev = table.sorted()
    assert ev["kind"].tolist() == [EventKind.EXIT, EventKind.INSERTION, EventKind.MERGE]
    ev["t"] = -1.0  # a returned array is the caller's
    assert table.sorted()["t"].tolist() == [0.5, 1.0, 1.0]
    assert table.of_kind(EventKind.MERGE)["vehicle"].tolist() == [1]


def test_event_table_validates() -> None:
    table = EventTable(2)
    with pytest.raises(ValueError, match="EventKind"):
        table.add(0.0, 42, 0)
    with pytest.raises(ValueError, match="vehicle 2"):
        table.add(0.0, EventKind.EXIT, 2)
    with pytest.raises(ValueError, match="one-dimensional"):
        EventTable(2, np.zeros((1, 1), dtype=EVENT_DTYPE))
