"""Tests of hcomc.sim.log (SimulationLog, EventKind) and its files (hcomc.sim.log.files)."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from hcomc.sim.log import EVENT_DTYPE, EventKind, SimulationLog
from hcomc.sim.log import files as log_io

T, N = 6, 4
ARRAY_NAMES = ("t", "x", "y", "v", "a", "heading", "lane", "active", "kind", "length", "width")


def _empty(n_steps: int = T, n_vehicles: int = N, **kw: object) -> SimulationLog:
    return SimulationLog.allocate(
        n_steps,
        n_vehicles,
        dt=0.1,
        kind=np.arange(n_vehicles) % 2,
        length=np.full(n_vehicles, 4.5),
        width=np.full(n_vehicles, 1.8),
        **kw,
    )


def _filled(n_rows: int = T - 1) -> SimulationLog:
    """A log with a deterministic pattern of activity, values and events.

    Vehicle j is active in rows j .. j + 2; the last slot is never active; the last
    allocated row is never recorded.
    """
    log = _empty(meta={"seed": 7, "config": {"condition": "C1", "dt": 0.1}})
    rng = np.random.default_rng(0)
    for k in range(n_rows):
        active = (np.arange(N) <= k) & (k <= np.arange(N) + 2)
        active[-1] = False
        log.record(
            k,
            0.1 * k,
            x=rng.uniform(0, 1500, N),
            y=rng.choice([-3.75, 0.0, 3.75], N),
            v=rng.uniform(0, 33, N),
            a=rng.normal(0, 1, N),
            heading=rng.normal(0, 0.05, N),
            lane=rng.integers(0, 3, N),
            active=active,
        )
    log.add_event(0.3, EventKind.MERGE, 1, other=0, x=812.5)
    log.add_event(0.1, EventKind.INSERTION, 1)
    log.add_event(0.3, EventKind.COLLISION, 0, other=2, value=1.5)
    log.add_event(0.0, EventKind.INSERTION, 0)
    return log


def _assert_logs_equal(a: SimulationLog, b: SimulationLog) -> None:
    for name in ARRAY_NAMES:
        got, want = getattr(b, name), getattr(a, name)
        assert got.dtype == want.dtype, name
        np.testing.assert_array_equal(got, want, err_msg=name, strict=True)
    # Structured arrays: compare field by field (NaN-aware).
    assert a.events.dtype == b.events.dtype
    for field in EVENT_DTYPE.names or ():
        np.testing.assert_array_equal(b.events[field], a.events[field], err_msg=field)
    assert b.dt == a.dt
    assert b.n_recorded == a.n_recorded
    assert b.meta == a.meta


# ---------------------------------------------------------------------- allocation


def test_allocate_shapes_dtypes_and_fill() -> None:
    log = _empty()
    for name in ("x", "y", "v", "a", "heading"):
        arr = getattr(log, name)
        assert arr.shape == (T, N)
        assert arr.dtype == np.float32
        assert np.isnan(arr).all()
    assert log.lane.dtype == np.int8
    assert (log.lane == -1).all()
    assert log.active.dtype == np.bool_
    assert not log.active.any()
    assert log.t.shape == (T,)
    assert log.t.dtype == np.float64
    assert np.isnan(log.t).all()
    assert log.kind.dtype == np.int8
    np.testing.assert_array_equal(log.kind, [0, 1, 0, 1])
    assert log.length.dtype == np.float32
    assert log.width.dtype == np.float32
    assert log.length.shape == log.width.shape == (N,)
    assert (log.n_steps, log.n_vehicles, log.n_recorded, log.vehicle_steps) == (T, N, 0, 0)
    assert log.meta == {}
    assert log.dt == 0.1
    # cells, row times, kind/length/width, the slot tables (slot, span: 24 B per vehicle;
    # owner: 8 B per column)
    assert log.nbytes == 5 * T * N * 4 + 2 * T * N + T * 8 + N * (1 + 4 + 4) + N * 24 + N * 8
    assert log.events.shape == (0,)
    assert log.events.dtype == EVENT_DTYPE


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"n_steps": -1}, "n_steps"),
        ({"dt": 0.0}, "dt"),
        ({"dt": math.nan}, "dt"),
        ({"kind": np.array([0, 1, 2, 0])}, "kind"),
        ({"kind": np.zeros(3)}, "kind"),
        ({"length": np.zeros(N)}, "length"),
        ({"width": np.full(N, np.inf)}, "width"),
    ],
)
def test_allocate_rejects_bad_input(kwargs: dict[str, object], match: str) -> None:
    args: dict[str, object] = {
        "n_steps": T,
        "n_vehicles": N,
        "dt": 0.1,
        "kind": np.zeros(N, dtype=int),
        "length": np.full(N, 4.5),
        "width": np.full(N, 1.8),
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        SimulationLog.allocate(**args)  # type: ignore[arg-type]


# ---------------------------------------------------------------------- record


def test_record_writes_nan_for_inactive() -> None:
    log = _empty()
    active = np.array([True, False, True, False])
    vals = np.arange(N, dtype=float) + 10.0
    log.record(2, 0.2, vals, vals + 1, vals + 2, vals + 3, vals + 4, np.array([1, 2, 0, 1]), active)
    np.testing.assert_array_equal(log.x[2], np.array([10, np.nan, 12, np.nan], np.float32))
    np.testing.assert_array_equal(log.heading[2], np.array([14, np.nan, 16, np.nan], np.float32))
    np.testing.assert_array_equal(log.lane[2], np.array([1, -1, 0, -1], np.int8))
    np.testing.assert_array_equal(log.active[2], active)
    assert log.t[2] == 0.2
    assert log.n_recorded == 3
    assert log.vehicle_steps == 2
    # Rows not written stay untouched.
    assert np.isnan(log.x[[0, 1, 3]]).all()

    # Rewriting a row overwrites it completely: a vehicle gone inactive is cleared.
    log.record(2, 0.2, vals, vals, vals, vals, vals, np.ones(N, int), np.array([0, 1, 0, 0], bool))
    np.testing.assert_array_equal(log.x[2], np.array([np.nan, 11, np.nan, np.nan], np.float32))
    np.testing.assert_array_equal(log.lane[2], np.array([-1, 1, -1, -1], np.int8))
    assert log.n_recorded == 3


def test_record_rejects_out_of_range_row() -> None:
    log = _empty()
    z = np.zeros(N)
    with pytest.raises(IndexError):
        log.record(T, 0.0, z, z, z, z, z, np.zeros(N, int), np.ones(N, bool))


def test_finish_trims_to_recorded_rows() -> None:
    log = _filled(n_rows=3)
    before = log.x[:3].copy()
    assert log.finish() is log
    assert log.n_steps == 3
    assert log.x.shape == log.lane.shape == log.active.shape == (3, N)
    assert log.t.shape == (3,)
    assert log.x.base is None  # memory of the dropped rows is released
    np.testing.assert_array_equal(log.x, before)
    log.truncate(1)
    assert (log.n_steps, log.n_recorded) == (1, 1)
    with pytest.raises(ValueError, match="trim"):
        log.finish(5)


# ---------------------------------------------------------------------- events


def test_event_kind_values() -> None:
    assert [(k.name, int(k)) for k in EventKind] == [
        ("INSERTION", 0),
        ("LANE_CHANGE_START", 1),
        ("LANE_CHANGE_END", 2),
        ("MERGE", 3),
        ("COLLISION", 4),
        ("RAMP_WAIT", 5),
        ("EXIT", 6),
        ("PLAN", 7),
        ("FALLBACK", 8),
        ("MISSED_EXIT", 9),
        ("LANE_CHANGE_ABORT", 10),
        ("PLAN_LOST", 11),
        ("SHIELD", 12),
        ("FAULT", 13),
        ("V2X_SILENT", 14),
    ]


def test_events_sorted_stably_by_time() -> None:
    ev = _filled().events
    assert ev.dtype == EVENT_DTYPE
    np.testing.assert_array_equal(ev["t"], [0.0, 0.1, 0.3, 0.3])
    # Equal times keep insertion order: MERGE was added before COLLISION.
    np.testing.assert_array_equal(
        ev["kind"], [EventKind.INSERTION, EventKind.INSERTION, EventKind.MERGE, EventKind.COLLISION]
    )
    merge = ev[2]
    assert (merge["vehicle"], merge["other"], merge["x"]) == (1, 0, 812.5)
    assert np.isnan(merge["value"])
    assert ev[0]["other"] == -1
    assert np.isnan(ev[0]["x"])


def test_events_of_filters() -> None:
    log = _filled()
    ins = log.events_of(EventKind.INSERTION)
    np.testing.assert_array_equal(ins["vehicle"], [0, 1])
    assert log.events_of(4)["value"][0] == 1.5
    assert log.events_of(EventKind.FALLBACK).shape == (0,)


def test_add_event_validates() -> None:
    log = _empty()
    with pytest.raises(ValueError, match="EventKind"):
        log.add_event(0.0, 99, 0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="vehicle"):
        log.add_event(0.0, EventKind.EXIT, N)
    with pytest.raises(ValueError, match="other"):
        log.add_event(0.0, EventKind.COLLISION, 0, other=-2)


def test_bulk_events_equal_one_by_one_and_cursor() -> None:
    one, bulk = _empty(), _empty()
    rows = [(0.5 * k, k % 9, k % N, (k % N) - 1, 10.0 * k, math.nan) for k in range(150)]
    for row in rows:  # beyond the initial capacity: the table grows
        one.add_event(*row)
    events = np.array(rows, dtype=EVENT_DTYPE)
    bulk.add_events(events[:70])
    assert bulk.n_events == 70
    bulk.add_events(events[70:])
    for field in EVENT_DTYPE.names or ():
        np.testing.assert_array_equal(bulk.events[field], one.events[field], err_msg=field)
    np.testing.assert_array_equal(bulk.events_since(148)["t"], [74.0, 74.5])
    for count in (1, 40):  # a few events go one by one, many at once: both are checked
        bad_kind = np.array([(0.0, 1, 0, -1, 0.0, 0.0)] * count, dtype=EVENT_DTYPE)
        bad_kind["kind"][-1] = 42
        with pytest.raises(ValueError, match=r"EventKind|unknown event kinds"):
            bulk.add_events(bad_kind[-1:] if count == 1 else bad_kind)
        bad_vehicle = np.array([(0.0, 1, 0, -1, 0.0, 0.0)] * count, dtype=EVENT_DTYPE)
        bad_vehicle["vehicle"][-1] = N
        with pytest.raises(ValueError, match="outside"):
            bulk.add_events(bad_vehicle)
    assert bulk.n_events == 150


def test_events_frame_has_kind_names() -> None:
    frame = _filled().events_frame()
    assert list(frame.columns) == ["t", "kind", "vehicle", "other", "x", "value"]
    assert list(frame["kind"].astype(str)) == ["INSERTION", "INSERTION", "MERGE", "COLLISION"]
    assert isinstance(frame["kind"].dtype, pd.CategoricalDtype)
    assert list(frame["kind"].cat.categories) == [k.name for k in EventKind]
    assert len(_empty().events_frame()) == 0


# ---------------------------------------------------------------------- long frame


def test_to_frame_rows_and_values() -> None:
    log = _filled()
    frame = log.to_frame()
    assert len(frame) == log.vehicle_steps == 9
    assert list(frame.columns) == [
        "step", "t", "vehicle", "kind", "x", "y", "v", "a", "heading", "lane", "length", "width"
    ]  # fmt: skip
    assert frame[["x", "y", "v", "a", "heading"]].notna().all().all()
    assert (frame["lane"] >= 0).all()
    steps, vehicles = frame["step"].to_numpy(), frame["vehicle"].to_numpy()
    assert log.active[steps, vehicles].all()
    for name in ("x", "y", "v", "a", "heading", "lane"):
        np.testing.assert_array_equal(frame[name].to_numpy(), getattr(log, name)[steps, vehicles])
    np.testing.assert_array_equal(frame["t"].to_numpy(), log.t[steps])
    np.testing.assert_array_equal(frame["kind"].to_numpy(), log.kind[vehicles])
    np.testing.assert_array_equal(frame["length"].to_numpy(), log.length[vehicles])
    row = frame[(frame["step"] == 2) & (frame["vehicle"] == 1)].iloc[0]
    assert row["x"] == log.x[2, 1]
    assert row["t"] == pytest.approx(0.2)
    assert N - 1 not in set(frame["vehicle"])  # never-active slot has no rows


# ---------------------------------------------------------------------- persistence


@pytest.mark.parametrize("suffix", [".npz", ".parquet"])
def test_round_trip(tmp_path: Path, suffix: str) -> None:
    log = _filled()
    path = log.save(tmp_path / f"run{suffix}")
    assert path.exists()
    back = SimulationLog.load(path)
    _assert_logs_equal(log, back)
    assert back.vehicle_steps == log.vehicle_steps
    pd.testing.assert_frame_equal(back.to_frame(), log.to_frame())
    assert sorted(p.name for p in tmp_path.iterdir()) == (
        ["run.events.parquet", "run.parquet"] if suffix == ".parquet" else ["run.npz"]
    )


@pytest.mark.parametrize("suffix", [".npz", ".parquet"])
def test_round_trip_empty_and_trimmed(tmp_path: Path, suffix: str) -> None:
    empty = _empty(n_steps=0, n_vehicles=0)
    _assert_logs_equal(empty, SimulationLog.load(empty.save(tmp_path / f"e{suffix}")))
    trimmed = _filled().finish()
    _assert_logs_equal(trimmed, SimulationLog.load(trimmed.save(tmp_path / f"t{suffix}")))


def test_parquet_is_the_long_frame_with_metadata(tmp_path: Path) -> None:
    log = _filled()
    log.save(tmp_path / "run.parquet")
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "run.parquet"), log.to_frame())
    header = json.loads(pq.read_schema(tmp_path / "run.parquet").metadata[log_io._PARQUET_META_KEY])
    assert (header["n_steps"], header["n_vehicles"]) == (T, N)
    assert header["meta"] == log.meta
    assert len(pq.read_table(tmp_path / "run.events.parquet")) == 4


def test_parquet_detects_mismatched_events_file(tmp_path: Path) -> None:
    _filled().save(tmp_path / "a.parquet")
    _filled().save(tmp_path / "b.parquet")
    os.replace(tmp_path / "b.events.parquet", tmp_path / "a.events.parquet")
    with pytest.raises(ValueError, match="does not belong"):
        SimulationLog.load(tmp_path / "a.parquet")


def test_meta_with_numpy_values_is_saved_as_plain_json(tmp_path: Path) -> None:
    log = _empty(meta={"seed": np.int64(3), "weights": np.array([0.5, 0.25])})
    back = SimulationLog.load(log.save(tmp_path / "m.npz"))
    assert back.meta == {"seed": 3, "weights": [0.5, 0.25]}


def test_unsupported_suffix(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="suffix"):
        _empty().save(tmp_path / "run.csv")
    with pytest.raises(ValueError, match="suffix"):
        SimulationLog.load(tmp_path / "run.h5")


def _failing_savez(fh: object, **arrays: object) -> None:
    fh.write(b"PK\x03\x04 half an archive")  # type: ignore[attr-defined]
    raise OSError("disk full")


def _failing_write_table(table: object, where: object, **kwargs: object) -> None:
    Path(str(where)).write_bytes(b"PAR1 garbage")
    raise OSError("disk full")


@pytest.mark.parametrize("suffix", [".npz", ".parquet"])
def test_interrupted_save_keeps_existing_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, suffix: str
) -> None:
    good = _filled()
    path = good.save(tmp_path / f"run{suffix}")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    if suffix == ".npz":
        monkeypatch.setattr(np, "savez_compressed", _failing_savez)
    else:
        monkeypatch.setattr(pq, "write_table", _failing_write_table)
    other = _empty()
    with pytest.raises(OSError, match="disk full"):
        other.save(path)

    after = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert after == before  # unchanged, and no temporary file left behind
    monkeypatch.undo()
    _assert_logs_equal(good, SimulationLog.load(path))


def test_interrupted_first_save_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(np, "savez_compressed", _failing_savez)
    with pytest.raises(OSError, match="disk full"):
        _filled().save(tmp_path / "new.npz")
    assert list(tmp_path.iterdir()) == []
