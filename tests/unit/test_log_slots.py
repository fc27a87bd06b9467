"""Slot-column logs read exactly as the plain (T, N) log of the same rows (the oracle: a log
with one column per vehicle written with the same ``record`` calls)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.sim.log import SimulationLog
from hcomc.sim.log.layout import CELL_FIELDS
from hcomc.sim.log.slots import OPEN, VehicleCells, active_columns


def _pair(seed: int, n_rows: int, n_vehicles: int, slots: int) -> tuple[SimulationLog, ...]:
    """The same rows recorded into a slot-column log and a one-column-per-vehicle log:
    each vehicle on the road for one stretch of rows, as in the engine."""
    rng = np.random.default_rng(seed)
    first = rng.integers(0, n_rows, n_vehicles)
    end = first + rng.integers(1, n_rows + 1, n_vehicles)
    per_vehicle = {"kind": rng.integers(0, 2, n_vehicles), "length": np.full(n_vehicles, 4.5),
                   "width": np.full(n_vehicles, 1.8)}  # fmt: skip
    logs = (
        SimulationLog.allocate(n_rows, n_vehicles, dt=0.1, slots=slots, **per_vehicle),
        SimulationLog.allocate(n_rows, n_vehicles, dt=0.1, **per_vehicle),
    )
    for k in range(n_rows):
        states = rng.normal(size=(5, n_vehicles)) * 100.0
        lane = rng.integers(0, 3, n_vehicles)
        on = (k >= first) & (k < end)
        for log in logs:
            log.record(k, 0.1 * k, *states, lane=lane, active=on)
    return logs


def _same(got: object, want: object) -> None:
    assert np.shape(got) == np.shape(want)
    np.testing.assert_array_equal(np.asarray(got), np.asarray(want))


@settings(max_examples=40, deadline=None)
@given(
    st.integers(0, 2**31), st.integers(1, 25), st.integers(1, 15), st.integers(0, 4),
    st.data(),
)  # fmt: skip
def test_every_index_reads_what_the_plain_log_holds(
    seed: int, n_rows: int, n_vehicles: int, slots: int, data: st.DataObject
) -> None:
    packed, plain = _pair(seed, n_rows, n_vehicles, slots)
    assert not packed.one_column_per_vehicle
    assert plain.one_column_per_vehicle
    assert packed.n_slots <= max(slots, 1) * 2 ** int(np.ceil(np.log2(n_vehicles + 1)))
    row = st.integers(-n_rows, n_rows - 1)
    vehicle = st.integers(-n_vehicles, n_vehicles - 1)
    rows = st.lists(st.integers(0, n_rows - 1), max_size=6).map(np.array)
    vehicles = st.lists(st.integers(0, n_vehicles - 1), min_size=1, max_size=6).map(np.array)
    cut = st.builds(slice, st.none() | row, st.none() | row, st.none() | st.integers(1, 3))
    key = st.one_of(
        row, cut, rows.filter(lambda r: r.size > 0),
        st.tuples(row, vehicle), st.tuples(cut, vehicle), st.tuples(row, cut),
        st.tuples(cut, cut), st.tuples(cut, vehicles),
        st.integers(1, 6).flatmap(lambda n: st.tuples(
            st.lists(st.integers(0, n_rows - 1), min_size=n, max_size=n).map(np.array),
            st.lists(st.integers(0, n_vehicles - 1), min_size=n, max_size=n).map(np.array),
        )),
    )  # fmt: skip
    for name in CELL_FIELDS:
        view, want = getattr(packed, name), getattr(plain, name)
        assert isinstance(view, VehicleCells)
        assert view.shape == want.shape
        assert view.dtype == want.dtype
        _same(view, want)
        for _ in range(5):
            k = data.draw(key)
            _same(view[k], want[k])
        _same(view[plain.active], want[plain.active])  # a (T, N) mask
    _same(packed.active.any(axis=0), plain.active.any(axis=0))  # methods: on the whole array
    _same(np.where(packed.active, packed.x, 0.0), np.where(plain.active, plain.x, 0.0))
    _same(packed.lane == 1, plain.lane == 1)
    _same(packed.logged_vehicles(), plain.logged_vehicles())
    assert packed.vehicle_steps == plain.vehicle_steps
    pd.testing.assert_frame_equal(packed.to_frame(), plain.to_frame())


def test_slots_are_handed_on_in_vehicle_order_and_spans_close_when_vehicles_leave() -> None:
    size = {"kind": np.zeros(4, dtype=int), "length": np.full(4, 5.0), "width": np.full(4, 2.0)}
    log = SimulationLog.allocate(4, 4, dt=1.0, slots=2, **size)
    zeros = np.zeros(4)
    lane = np.ones(4, dtype=int)
    for k, on in enumerate(([1, 1, 0, 0], [0, 1, 0, 0], [0, 1, 1, 1], [0, 0, 1, 1])):
        log.record(k, float(k), zeros, zeros, zeros, zeros, zeros, lane, np.array(on) > 0)
    # vehicle 0 leaves at row 1 and frees slot 0; at row 2 vehicles 2 and 3 enter: 2 takes
    # slot 0, 3 finds none free and the log doubles to 4 columns, giving it slot 2
    assert log.slot.tolist() == [0, 1, 0, 2]
    assert log.span.tolist() == [[0, 1], [0, 3], [2, OPEN], [2, OPEN]]
    assert log.owner.tolist() == [2, -1, 3, -1]  # by slot: vehicle 1 left at row 3
    log.finish()
    assert log.n_slots == 3  # trimmed to the columns used
    assert log.active[:, 0].tolist() == [True, False, False, False]


def test_a_vehicle_back_on_the_road_after_leaving_is_an_error() -> None:
    log = SimulationLog.allocate(3, 1, dt=1.0, kind=[0], length=[5.0], width=[2.0], slots=1)
    one = np.zeros(1)
    for k, on in enumerate((True, False)):
        log.record(k, float(k), one, one, one, one, one, np.ones(1, dtype=int), np.array([on]))
    with pytest.raises(ValueError, match="re-entered"):
        log.record(2, 2.0, one, one, one, one, one, np.ones(1, dtype=int), np.array([True]))


@pytest.mark.parametrize("suffix", [".npz", ".parquet"])
def test_files_keep_the_slot_columns(tmp_path, suffix: str) -> None:
    packed, plain = _pair(7, 20, 9, 2)
    path = packed.save(tmp_path / f"log{suffix}")
    back = SimulationLog.load(path)
    assert back.n_slots == packed.n_slots
    assert not back.one_column_per_vehicle
    for name in ("slot", "span", "owner"):
        np.testing.assert_array_equal(getattr(back, name), getattr(packed, name))
    for name in CELL_FIELDS:
        _same(getattr(back, name), getattr(plain, name))


@settings(max_examples=40, deadline=None)
@given(
    st.integers(0, 2**31), st.integers(1, 25), st.integers(0, 15), st.integers(0, 4),
    st.data(),
)  # fmt: skip
def test_active_columns_list_each_rows_vehicles_on_the_road_in_vehicle_order(
    seed: int, n_rows: int, n_vehicles: int, slots: int, data: st.DataObject
) -> None:
    packed, plain = _pair(seed, n_rows, n_vehicles, slots)
    r0 = data.draw(st.integers(0, n_rows))
    r1 = data.draw(st.integers(r0, n_rows))
    for log in (packed, plain):
        start, vehicle, column = active_columns(log.cells["active"], log.slot, log.span, r0, r1)
        assert start.tolist()[0] == 0
        assert start.size == r1 - r0 + 1
        for k in range(r0, r1):
            on = slice(start[k - r0], start[k - r0 + 1])
            np.testing.assert_array_equal(vehicle[on], np.flatnonzero(plain.active[k]))
            np.testing.assert_array_equal(column[on], log.slot[vehicle[on]])
            for name in CELL_FIELDS:  # the cells the columns point to are the vehicles'
                _same(log.cells[name][k, column[on]], getattr(plain, name)[k, vehicle[on]])


def test_a_scene_that_starts_full_logs_without_widening(monkeypatch) -> None:
    """141 vehicles on the road from the first row: the engine's log starts with a column for
    each vehicle due by its first row and never widens (a copy of every column); a log
    started narrower grows to one column per vehicle in one step (not 64 -> 128 -> 141), and
    trimming keeps those columns."""
    from hcomc.config import load_config
    from hcomc.sim.engine import Simulation
    from hcomc.sim.step import build

    config = load_config(
        "platoon", duration=2.0, warmup=0.0,
        platoon={"followers": 140, "initial_speed": 25.0, "profile": [[0.0, 25.0]]},
        road={"length": 10_000.0, "ramp_start": 1000.0, "accel_lane_start": 2000.0,
              "accel_lane_end": 2250.0},
    )  # fmt: skip
    grown: list[int] = []
    grow = SimulationLog.grow_slots
    monkeypatch.setattr(
        SimulationLog, "grow_slots", lambda log, n: (grown.append(n), grow(log, n))[1]
    )
    log = Simulation(config, 0).run()
    assert grown == []
    assert log.n_slots == 141
    monkeypatch.setattr(build, "initial_slots", lambda demand: build.FIRST_SLOTS)
    narrow = Simulation(config, 0).run()
    assert grown == [141]
    assert narrow.n_slots == 141
    assert narrow.active[0].sum() == 141
    for name in CELL_FIELDS:
        _same(narrow.cells[name], log.cells[name])


def test_a_log_widened_while_written_equals_one_allocated_wide(monkeypatch):
    """The corridor fills from an empty road: its log (64 columns to start) widens while the
    run writes it. The finished log equals, cell for cell, that of the same run with a column
    per vehicle from the start (which never widens)."""
    from hcomc.corridor import load_corridor
    from hcomc.metrics.corridor import simulate_corridor
    from hcomc.sim.step import build

    c = load_corridor("corridor")
    grown: list[int] = []
    grow = SimulationLog.grow_slots
    monkeypatch.setattr(
        SimulationLog, "grow_slots", lambda log, n: (grown.append(n), grow(log, n))[1]
    )
    narrow = simulate_corridor(c, duration=240.0).log
    assert grown == [128, 256]  # 64 -> 128 -> 256 columns while the road fills
    grown.clear()
    monkeypatch.setattr(build, "initial_slots", lambda demand: demand.n)
    wide = simulate_corridor(c, duration=240.0).log
    assert grown == []
    assert narrow.n_slots == wide.n_slots
    for name in CELL_FIELDS:
        _same(narrow.cells[name], wide.cells[name])
    np.testing.assert_array_equal(narrow.t, wide.t)
    np.testing.assert_array_equal(narrow.slot, wide.slot)
    np.testing.assert_array_equal(narrow.span, wide.span)
    assert narrow.events.tobytes() == wide.events.tobytes()  # NaN payloads among them
