"""Files of a :class:`~hcomc.sim.log.SimulationLog`: ``.npz`` and ``.parquet``, atomic.

``.npz`` holds all arrays (the stored slot columns and their tables, see
:mod:`hcomc.sim.log.slots`), events and metadata in one compressed archive. ``.parquet``
holds the long-format frame of :meth:`SimulationLog.to_frame`, with the run metadata in
the Parquet schema metadata and the events in a sibling ``<stem>.events.parquet``; the two
files share a random token so a log and an events file that do not belong together are
detected. Both formats are read back exactly, with the dtypes of
:mod:`hcomc.sim.log.layout`; files whose arrays have other dtypes (e.g. float64 states) are
read and converted to that layout.

The functions write and read the log's data (:class:`~hcomc.sim.log.data.LogData`, of which
``SimulationLog`` is the subclass that calls them): a log is read into the class
:meth:`SimulationLog.load` is called on, and this module does not import the log class.
:func:`log_file_of` finds the log of a run directory or checks a log file's path, for every
reader of runs (figures, replay, the CommonRoad export).
"""

from __future__ import annotations

import base64
import json
import os
import uuid
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from hcomc.sim.log.data import LogData
from hcomc.sim.log.events import EVENT_DTYPE
from hcomc.sim.log.layout import ARRAY_FIELDS, CELL_FIELDS, DTYPES, STATE_FIELDS, allocate_rows
from hcomc.sim.log.slots import identity_slots
from hcomc.sim.manifest import atomic_paths, json_default

__all__ = ["events_path", "long_columns", "read_log", "write_log"]

_FORMAT_VERSION = 2  # 2: slot columns and their tables; 1 (one column per vehicle) is read
_READABLE = (1, 2)
_TABLES = ("slot", "span", "owner")
_PARQUET_META_KEY = b"hcomc.simulation_log"
_PARQUET_EVENTS_META_KEY = b"hcomc.simulation_log.events"

LogT = TypeVar("LogT", bound=LogData)
"""The class a log is read into (``SimulationLog``, or a subclass of it)."""


def _b64(arr: np.ndarray, dtype: str) -> str:
    return base64.b64encode(np.ascontiguousarray(arr, dtype=dtype).tobytes()).decode("ascii")


def _unb64(text: str, dtype: str) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), dtype=dtype).copy()


def _header(log: LogData) -> dict[str, Any]:
    return {
        "format_version": _FORMAT_VERSION,
        "n_steps": log.n_steps,
        "n_vehicles": log.n_vehicles,
        "n_slots": log.n_slots,
        "dt": log.dt,
        "n_recorded": log.n_recorded,
        "meta": log.meta,
    }


def long_columns(log: LogData) -> dict[str, np.ndarray]:
    """One array per column of :meth:`SimulationLog.to_frame`: a row per active (step,
    vehicle) cell, ordered by step then vehicle."""
    cells = log.cells
    steps, cols = np.nonzero(cells["active"])
    vehicles = cols
    if not log.one_column_per_vehicle:  # stored by slot: the cells' vehicles, then their order
        vehicles = log.owners()[steps, cols]
        order = np.lexsort((vehicles, steps))
        steps, cols, vehicles = steps[order], cols[order], vehicles[order]
    out: dict[str, np.ndarray] = {
        "step": steps.astype(np.int64),
        "t": log.t[steps],
        "vehicle": vehicles.astype(np.int64),
        "kind": log.kind[vehicles],
    }
    for name in (*STATE_FIELDS, "lane"):
        out[name] = cells[name][steps, cols]
    out["length"] = log.length[vehicles]
    out["width"] = log.width[vehicles]
    return out


def events_path(path: str | os.PathLike[str]) -> Path:
    """Sibling file holding the events of a Parquet log: ``<stem>.events.parquet``."""
    path = Path(path)
    return path.with_name(f"{path.stem}.events.parquet")


def write_log(log: LogData, path: str | os.PathLike[str]) -> Path:
    """Write ``log`` to ``.npz`` or ``.parquet``, atomically (see :meth:`SimulationLog.save`)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        _write_npz(log, path)
    elif suffix == ".parquet":
        _write_parquet(log, path)
    else:
        raise ValueError(f"unsupported log file suffix {path.suffix!r}: use .npz or .parquet")
    return path


def _write_npz(log: LogData, path: Path) -> None:
    header = json.dumps(_header(log), default=json_default)
    tables = {"slot": log.slot, "span": log.span, "owner": log.owner}
    per_vehicle = {"kind": log.kind, "length": log.length, "width": log.width}
    arrays: dict[str, Any] = {"t": log.t, **log.cells, **per_vehicle, **tables}
    with atomic_paths(path) as (tmp,), tmp.open("wb") as fh:
        # A file object, not a name: numpy would append ".npz" to the temp name.
        np.savez_compressed(fh, header=np.array(header), events=log.events, **arrays)


def _write_parquet(log: LogData, path: Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    token = uuid.uuid4().hex
    header = _header(log)
    header["token"] = token
    # Per-step and per-vehicle arrays are kept whole (bit-exact, base64): steps
    # without active vehicles and never-active vehicles are absent from the frame.
    header["t"] = _b64(log.t, "<f8")
    header["kind"] = _b64(log.kind, "<i1")
    header["length"] = _b64(log.length, "<f4")
    header["width"] = _b64(log.width, "<f4")
    header["slot"] = _b64(log.slot, "<i8")
    header["span"] = _b64(log.span, "<i8")
    header["owner"] = _b64(log.owner, "<i8")
    header_json = json.dumps(header, default=json_default).encode("utf-8")
    table = pa.table(long_columns(log))
    table = table.replace_schema_metadata({_PARQUET_META_KEY: header_json})

    ev = log.events
    ev_table = pa.table({name: ev[name] for name in EVENT_DTYPE.names or ()})
    ev_meta = json.dumps({"format_version": _FORMAT_VERSION, "token": token}).encode()
    ev_table = ev_table.replace_schema_metadata({_PARQUET_EVENTS_META_KEY: ev_meta})

    # Events first, main file last: the main file's replacement commits the save.
    with atomic_paths(events_path(path), path) as (tmp_ev, tmp_main):
        pq.write_table(ev_table, tmp_ev)
        pq.write_table(table, tmp_main)


LOG_FILES = ("log.npz", "log.parquet")
"""The log's file names in a run directory (``hcomc simulate --out``), in the order looked for."""

LOG_SUFFIXES = (".npz", ".parquet")
"""The suffixes of a log file."""


def log_file_of(source: str | os.PathLike[str]) -> Path:
    """The log file of ``source``: a log file itself, or the first of :data:`LOG_FILES` in a
    run directory; ValueError (one line) when ``source`` does not exist, is a directory
    without a log, or a file of another suffix. The one place a run's log is found."""
    path = Path(source)
    if path.is_dir():
        found = [path / name for name in LOG_FILES if (path / name).is_file()]
        if not found:
            raise ValueError(f"directory '{path}' holds no {' or '.join(LOG_FILES)}")
        return found[0]
    if not path.is_file():
        raise ValueError(f"log file '{path}' does not exist")
    if path.suffix.lower() not in LOG_SUFFIXES:
        raise ValueError(f"log file '{path}' has suffix '{path.suffix}'; "
                         f"allowed: {', '.join(LOG_SUFFIXES)}")  # fmt: skip
    return path


def read_log(path: str | os.PathLike[str], cls: type[LogT]) -> LogT:
    """Read a log written by :func:`write_log` into a ``cls`` (see :meth:`SimulationLog.load`)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        return _read_npz(path, cls)
    if suffix == ".parquet":
        return _read_parquet(path, cls)
    raise ValueError(f"unsupported log file suffix {path.suffix!r}: use .npz or .parquet")


def _check_version(header: dict[str, Any], path: Path) -> None:
    version = header.get("format_version")
    if version not in _READABLE:
        raise ValueError(f"{path}: unsupported simulation log format version {version!r}")


def _read_npz(path: Path, cls: type[LogT]) -> LogT:
    with np.load(path, allow_pickle=False) as data:
        header = json.loads(str(data["header"]))
        _check_version(header, path)
        arrays = {name: data[name] for name in ARRAY_FIELDS}
        tables = {name: data[name] for name in _TABLES} if "slot" in data else None
        events = data["events"]
    common = {"dt": header["dt"], "meta": header["meta"], "n_recorded": header["n_recorded"],
              "events": events}  # fmt: skip
    if tables is None:  # format 1: one column per vehicle
        return cls(**common, **arrays)
    cells = {name: arrays.pop(name) for name in CELL_FIELDS}
    return cls.from_slots(**common, **arrays, cells=cells, **tables)


def _read_parquet(path: Path, cls: type[LogT]) -> LogT:
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    raw = (table.schema.metadata or {}).get(_PARQUET_META_KEY)
    if raw is None:
        raise ValueError(f"{path}: not a hcomc simulation log (no {_PARQUET_META_KEY!r})")
    header = json.loads(raw)
    _check_version(header, path)

    ev_path = events_path(path)
    ev_table = pq.read_table(ev_path)
    ev_raw = (ev_table.schema.metadata or {}).get(_PARQUET_EVENTS_META_KEY)
    ev_token = json.loads(ev_raw).get("token") if ev_raw is not None else None
    if ev_token != header["token"]:
        raise ValueError(f"{ev_path} does not belong to {path} (save was interrupted?)")
    events = np.empty(ev_table.num_rows, dtype=EVENT_DTYPE)
    for name in EVENT_DTYPE.names or ():
        events[name] = ev_table.column(name).to_numpy()

    n_steps, n_vehicles = int(header["n_steps"]), int(header["n_vehicles"])
    n_slots = int(header.get("n_slots", n_vehicles))
    arrays = allocate_rows(n_steps, n_slots)
    arrays["t"][:] = _unb64(header["t"], "<f8")
    steps = table.column("step").to_numpy()
    vehicles = table.column("vehicle").to_numpy()
    if "slot" in header:
        slot = _unb64(header["slot"], "<i8")
        tables = {"slot": slot, "span": _unb64(header["span"], "<i8").reshape(-1, 2),
                  "owner": _unb64(header["owner"], "<i8")}  # fmt: skip
    else:  # format 1: one column per vehicle
        slot, span, owner = identity_slots(n_vehicles)
        tables = {"slot": slot, "span": span, "owner": owner}
    columns = slot[vehicles]
    arrays["active"][steps, columns] = True
    for name in (*STATE_FIELDS, "lane"):
        column = table.column(name).to_numpy()
        if column.dtype.kind != DTYPES[name].kind:
            raise ValueError(f"{path}: column {name!r} has dtype {column.dtype}")
        arrays[name][steps, columns] = column  # float64 columns are rounded to float32
    return cls.from_slots(
        dt=header["dt"],
        meta=header["meta"],
        n_recorded=header["n_recorded"],
        events=events,
        t=arrays.pop("t"),
        cells=arrays,
        kind=_unb64(header["kind"], "<i1"),
        length=_unb64(header["length"], "<f4"),
        width=_unb64(header["width"], "<f4"),
        **tables,
    )
