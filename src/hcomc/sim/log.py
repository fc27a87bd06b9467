"""Simulation log: preallocated struct-of-arrays trajectories plus a table of events.

The engine writes one row per logging step (compiled: :func:`hcomc.sim.core.record_row`;
from Python: :meth:`SimulationLog.record`) and appends rare discrete
events (insertions, lane changes, merges, collisions, plan fallbacks ...) with
:meth:`SimulationLog.add_event`. Metrics, tables and figures read the log afterwards.

The trajectories read as ``T`` logging rows x ``N`` vehicles: ``t`` (T,) float64 and
``x, y, v, a, heading`` (float32), ``lane`` (int8), ``active`` (bool), each indexed like a
(T, N) numpy array, plus per-vehicle ``kind``, ``length``, ``width``. A log built from plain
(T, N) arrays stores them as they are. The engine's log stores its cells in slot columns that
vehicles leaving the road hand on to vehicles entering it, so its memory follows the number
of vehicles on the road at once, not the number over the run (:mod:`hcomc.sim.log_slots`);
its ``x`` ... ``active`` are read views of the same (T, N) shape. The layout, the reasons
for each dtype and the memory figures are in :mod:`hcomc.sim.log_layout`; the events in
:mod:`hcomc.sim.log_events`. Files (``.npz``, ``.parquet``, written atomically and read
back exactly) are handled by :mod:`hcomc.sim.log_io` behind :meth:`SimulationLog.save`
and :meth:`SimulationLog.load`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.sim.log_events import EVENT_DTYPE, EventKind, EventTable
from hcomc.sim.log_layout import (
    ARRAY_FIELDS,
    CELL_FIELDS,
    FILL,
    VEHICLE_FIELDS,
    allocate_rows,
    as_layout,
    bytes_needed,
    vehicle_arrays,
)
from hcomc.sim.log_slots import (
    OPEN,
    VehicleCells,
    claim_slots,
    empty_slots,
    identity_slots,
    owner_grid,
    widen,
)

__all__ = ["EVENT_DTYPE", "EventKind", "SimulationLog"]


def _conformed(
    given: dict[str, Any], n_steps: int, n_vehicles: int, n_slots: int
) -> dict[str, np.ndarray]:
    """Every array of a log (:data:`ARRAY_FIELDS`) from ``given``, checked against its shape
    (``t`` (T,), the stored cells (T, S), per-vehicle arrays (N,)) and in the layout's dtype;
    ``ValueError`` naming the first array of another shape."""
    expected: dict[str, tuple[int, ...]] = {"t": (n_steps,)}
    expected.update(dict.fromkeys(CELL_FIELDS, (n_steps, n_slots)))
    expected.update(dict.fromkeys(VEHICLE_FIELDS, (n_vehicles,)))
    for name, shape in expected.items():
        if np.shape(given[name]) != shape:
            raise ValueError(f"{name} has shape {np.shape(given[name])}, expected {shape}")
    return {name: as_layout(name, given[name]) for name in ARRAY_FIELDS}


def _cell_view(name: str, doc: str) -> Any:
    """The property ``log.<name>``: the stored array of a log with one column per vehicle,
    else a (T, N) :class:`~hcomc.sim.log_slots.VehicleCells` read view."""
    return property(lambda log: log._view(name), doc=doc)


class SimulationLog:
    """Preallocated struct-of-arrays log of one simulation run.

    Build it with :meth:`allocate` (or :meth:`load`); the constructor takes ready arrays
    and is meant for internal use. See :mod:`hcomc.sim.log_layout` for the array layout.

    Parameters
    ----------
    dt : float
        Logging interval [s].
    t : numpy.ndarray
        (T,) row times [s].
    x, y, v, a, heading : numpy.ndarray
        (T, N) position [m], lateral position [m], speed [m/s], acceleration [m/s^2],
        heading [rad].
    lane : numpy.ndarray
        (T, N) lane index, -1 when inactive.
    active : numpy.ndarray
        (T, N) activity mask.
    kind : numpy.ndarray
        (N,) vehicle type, 0 = HDV, 1 = CAV.
    length, width : numpy.ndarray
        (N,) vehicle dimensions [m].
    meta : dict or None
        JSON-serialisable run metadata (seed, config, version ...).
    n_recorded : int
        Number of rows already written.
    events : numpy.ndarray or None
        Initial events, :data:`EVENT_DTYPE`.

    Arrays already of the layout's dtype and C-contiguous are kept as they are (no
    copy); others are converted (e.g. float64 states are rounded to float32).
    """

    def __init__(
        self,
        *,
        dt: float,
        t: FloatArray,
        x: np.ndarray,
        y: np.ndarray,
        v: np.ndarray,
        a: np.ndarray,
        heading: np.ndarray,
        lane: np.ndarray,
        active: BoolArray,
        kind: np.ndarray,
        length: np.ndarray,
        width: np.ndarray,
        meta: dict[str, Any] | None = None,
        n_recorded: int = 0,
        events: np.ndarray | None = None,
    ) -> None:
        given = {
            "t": t, "x": x, "y": y, "v": v, "a": a, "heading": heading, "lane": lane,
            "active": active, "kind": kind, "length": length, "width": width,
        }  # fmt: skip
        x_shape = np.shape(x)
        if len(x_shape) != 2:
            raise ValueError(f"x must be two-dimensional (rows x vehicles), got shape {x_shape}")
        n_steps, n_vehicles = x_shape
        arrays = _conformed(given, n_steps, n_vehicles, n_vehicles)
        self._setup(dt, arrays, identity_slots(n_vehicles), meta, n_recorded, events)

    def _setup(
        self,
        dt: float,
        arrays: dict[str, np.ndarray],
        slots: tuple[np.ndarray, np.ndarray, np.ndarray],
        meta: dict[str, Any] | None,
        n_recorded: int,
        events: np.ndarray | None,
    ) -> None:
        dt = float(dt)
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt (logging interval) must be finite and > 0 [s], got {dt}")
        self.dt: float = dt
        self.t: FloatArray = arrays["t"]
        self._cells: dict[str, np.ndarray] = {name: arrays[name] for name in CELL_FIELDS}
        self.slot, self.span, self.owner = slots
        self._one_per_vehicle = self.owner.size == self.slot.size and bool(
            (self.slot == np.arange(self.slot.size)).all() and (self.span[:, 0] == 0).all()
            and (self.span[:, 1] == OPEN).all()
        )  # fmt: skip
        self.kind: np.ndarray = arrays["kind"]
        self.length: np.ndarray = arrays["length"]
        self.width: np.ndarray = arrays["width"]
        self.meta: dict[str, Any] = {} if meta is None else meta
        n_steps = self.t.size
        if not 0 <= n_recorded <= n_steps:
            raise ValueError(f"n_recorded must be in [0, {n_steps}], got {n_recorded}")
        self._n_recorded = int(n_recorded)
        self._event_table = EventTable(self.slot.size, events)

    @classmethod
    def from_slots(
        cls,
        *,
        dt: float,
        t: FloatArray,
        cells: dict[str, np.ndarray],
        slot: np.ndarray,
        span: np.ndarray,
        owner: np.ndarray,
        kind: np.ndarray,
        length: np.ndarray,
        width: np.ndarray,
        meta: dict[str, Any] | None = None,
        n_recorded: int = 0,
        events: np.ndarray | None = None,
    ) -> SimulationLog:
        """A log stored in slot columns (:mod:`hcomc.sim.log_slots`): ``cells`` maps each of
        ``x, y, v, a, heading, lane, active`` to a (T, S) array; ``slot`` (N,), ``span``
        (N, 2) and ``owner`` (S,) say which vehicle a column holds when."""
        n_vehicles, n_slots = np.shape(slot)[0], np.shape(owner)[0]
        given = {"t": t, **cells, "kind": kind, "length": length, "width": width}
        arrays = _conformed(given, int(np.size(t)), n_vehicles, n_slots)
        if np.shape(span) != (n_vehicles, 2):
            raise ValueError(f"span has shape {np.shape(span)}, expected ({n_vehicles}, 2)")
        tables = tuple(np.ascontiguousarray(a, dtype=np.int64) for a in (slot, span, owner))
        log = cls.__new__(cls)
        log._setup(dt, arrays, tables, meta, n_recorded, events)  # type: ignore[arg-type]
        return log

    # ------------------------------------------------------------------ construction
    @staticmethod
    def bytes_needed(n_steps: int, n_vehicles: int, n_slots: int | None = None) -> int:
        """Exact memory of the arrays of a log of T rows, N vehicles and S slot columns
        (default S = N) [bytes], events excluded.

        Equals :attr:`nbytes` of the log :meth:`allocate` would build; see
        :func:`hcomc.sim.log_layout.bytes_needed`.
        """
        return bytes_needed(n_steps, n_vehicles, n_slots)

    @classmethod
    def allocate(
        cls,
        n_steps: int,
        n_vehicles: int,
        *,
        dt: float,
        kind: IntArray,
        length: FloatArray,
        width: FloatArray,
        meta: dict[str, Any] | None = None,
        slots: int | None = None,
    ) -> SimulationLog:
        """Preallocate an empty log.

        Parameters
        ----------
        n_steps : int
            Number of logging rows T (>= 0).
        n_vehicles : int
            Number of vehicles N (>= 0).
        dt : float
            Logging interval [s] (> 0).
        kind : array_like of int, shape (N,)
            Vehicle type per vehicle, 0 = HDV, 1 = CAV.
        length, width : array_like of float, shape (N,)
            Vehicle dimensions [m] (finite, > 0).
        meta : dict or None
            JSON-serialisable run metadata. Stored by reference.
        slots : int or None
            None: one column per vehicle. A number S: that many slot columns, which
            vehicles leaving the road hand on to vehicles entering it
            (:mod:`hcomc.sim.log_slots`); :meth:`record` adds columns when more vehicles
            are on the road at once.

        Returns
        -------
        SimulationLog
            State arrays filled with NaN, ``lane`` with -1, ``active`` with False,
            ``t`` with NaN; no rows recorded, no events.

        Raises
        ------
        ValueError
            On negative sizes, a bad ``dt``, wrongly shaped per-vehicle arrays, a kind
            other than 0/1 or a non-positive dimension.
        """
        n_steps, n_vehicles = int(n_steps), int(n_vehicles)
        if n_steps < 0 or n_vehicles < 0:
            raise ValueError(f"n_steps and n_vehicles must be >= 0, got {n_steps}, {n_vehicles}")
        per_vehicle = vehicle_arrays(n_vehicles, kind=kind, length=length, width=width)
        if slots is None:
            rows = allocate_rows(n_steps, n_vehicles)
            return cls(
                dt=dt, meta=meta, t=rows["t"], x=rows["x"], y=rows["y"], v=rows["v"],
                a=rows["a"], heading=rows["heading"], lane=rows["lane"], active=rows["active"],
                kind=per_vehicle["kind"], length=per_vehicle["length"],
                width=per_vehicle["width"],
            )  # fmt: skip
        if slots < 0:
            raise ValueError(f"slots must be >= 0, got {slots}")
        rows = allocate_rows(n_steps, int(slots))
        slot, span, owner = empty_slots(n_vehicles, int(slots))
        return cls.from_slots(
            dt=dt, t=rows.pop("t"), cells=rows, slot=slot, span=span, owner=owner, meta=meta,
            kind=per_vehicle["kind"], length=per_vehicle["length"], width=per_vehicle["width"],
        )  # fmt: skip

    # ------------------------------------------------------------------ cells
    def _view(self, name: str) -> Any:
        store = self._cells[name]
        if self._one_per_vehicle:
            return store
        return VehicleCells(store, self.slot, self.span, FILL[name])

    x = _cell_view(
        "x", "(T, N) longitudinal position [m]; NaN where the vehicle is not on the road."
    )
    y = _cell_view("y", "(T, N) lateral position [m].")
    v = _cell_view("v", "(T, N) speed [m/s].")
    a = _cell_view("a", "(T, N) acceleration [m/s^2].")
    heading = _cell_view("heading", "(T, N) heading [rad].")
    lane = _cell_view("lane", "(T, N) lane index, -1 where the vehicle is not on the road.")
    active = _cell_view("active", "(T, N) whether the vehicle is on the road.")

    @property
    def cells(self) -> dict[str, np.ndarray]:
        """The stored (T, S) arrays by name (S = N for a log with one column per vehicle);
        which vehicle a column holds when is :attr:`slot`, :attr:`span`, :attr:`owner`."""
        return self._cells

    @property
    def one_column_per_vehicle(self) -> bool:
        """Whether vehicle i is column i at every row (``x`` ... are then plain arrays)."""
        return self._one_per_vehicle

    def logged_vehicles(self) -> np.ndarray:
        """(N,) bool: the vehicles on the road at one logged row at least."""
        if self._one_per_vehicle:
            return np.asarray(self._cells["active"].any(axis=0))
        return (self.slot >= 0) & (self.span[:, 0] < self.n_steps)

    def owners(self) -> np.ndarray:
        """(T, S) int64: the vehicle each stored cell belongs to, -1 for none."""
        return owner_grid(self.slot, self.span, self.n_steps, self.n_slots)

    def grow_slots(self, n_slots: int) -> None:
        """Widen a slot-column log to ``n_slots`` columns (new columns free and unwritten)."""
        if self._one_per_vehicle:
            raise ValueError("a log with one column per vehicle has no slots to grow")
        self._cells, self.owner = widen(self._cells, self.owner, n_slots)

    # ------------------------------------------------------------------ sizes
    @property
    def n_steps(self) -> int:
        """Number of allocated rows T."""
        return int(self.t.size)

    @property
    def n_vehicles(self) -> int:
        """Number of vehicles N."""
        return int(self.slot.size)

    @property
    def n_slots(self) -> int:
        """Number of stored columns S (N for a log with one column per vehicle)."""
        return int(self.owner.size)

    @property
    def n_recorded(self) -> int:
        """Number of rows already written (highest recorded row index + 1)."""
        return self._n_recorded

    @property
    def vehicle_steps(self) -> int:
        """Number of active (step, vehicle) cells."""
        return int(np.count_nonzero(self._cells["active"]))

    @property
    def nbytes(self) -> int:
        """Memory held by the log's arrays [bytes] (events excluded)."""
        arrays = [self.t, *self._cells.values(), self.kind, self.length, self.width,
                  self.slot, self.span, self.owner]  # fmt: skip
        return int(sum(arr.nbytes for arr in arrays))

    def __repr__(self) -> str:
        return (
            f"SimulationLog(n_steps={self.n_steps}, n_vehicles={self.n_vehicles}, "
            f"n_slots={self.n_slots}, dt={self.dt}, n_recorded={self.n_recorded}, "
            f"vehicle_steps={self.vehicle_steps}, n_events={len(self._event_table)})"
        )

    # ------------------------------------------------------------------ writing
    def record(
        self,
        k: int,
        t: float,
        x: FloatArray,
        y: FloatArray,
        v: FloatArray,
        a: FloatArray,
        heading: FloatArray,
        lane: IntArray,
        active: BoolArray,
    ) -> None:
        """Write logging row *k*.

        Values of inactive vehicles are replaced by NaN (floats) and -1 (lane), so a row
        never carries stale state. In a log with one column per vehicle rewriting a row
        overwrites it completely; a slot-column log is written row after row (a vehicle
        that left the road does not come back), adding columns when it needs them.

        Parameters
        ----------
        k : int
            Row index, 0 <= k < T.
        t : float
            Simulation time of the row [s].
        x, y, v, a, heading : numpy.ndarray, shape (N,)
            Position [m], lateral position [m], speed [m/s], acceleration [m/s^2],
            heading [rad] of every vehicle (any value for inactive ones).
        lane : numpy.ndarray of int, shape (N,)
            Lane index of every vehicle.
        active : numpy.ndarray of bool, shape (N,)
            Which vehicles are on the road.

        Raises
        ------
        IndexError
            If *k* is outside [0, T).
        """
        if not 0 <= k < self.n_steps:
            raise IndexError(f"row {k} outside the log's {self.n_steps} rows")
        mask = np.asarray(active).astype(bool)
        self.t[k] = t
        values = {"x": x, "y": y, "v": v, "a": a, "heading": heading, "lane": lane}
        if self._one_per_vehicle:
            self._cells["active"][k] = mask
            for name, value in values.items():
                self._cells[name][k] = np.where(mask, value, FILL[name])
        else:
            if k < self._n_recorded:
                raise ValueError(f"row {k}: a slot-column log is written row after row "
                                 f"({self._n_recorded} rows written)")  # fmt: skip
            while not claim_slots(mask, self.slot, self.span, self.owner, k):
                self.grow_slots(max(2 * self.n_slots, 1))
            on = np.flatnonzero(mask)
            cols = self.slot[on]
            self._cells["active"][k, cols] = True
            for name, value in values.items():
                self._cells[name][k, cols] = np.asarray(value)[on]
        if k >= self._n_recorded:
            self._n_recorded = k + 1

    def mark_recorded(self, n: int) -> None:
        """Declare rows ``0 .. n-1`` written (by a compiled writer that fills the arrays
        directly, as :func:`hcomc.sim.core.record_row` does)."""
        if not 0 <= n <= self.n_steps:
            raise IndexError(f"{n} rows outside the log's {self.n_steps} rows")
        self._n_recorded = max(self._n_recorded, n)

    def add_event(
        self,
        t: float,
        kind: EventKind | int,
        vehicle: int,
        other: int = -1,
        x: float = math.nan,
        value: float = math.nan,
    ) -> None:
        """Append a discrete event.

        Parameters
        ----------
        t : float
            Event time [s].
        kind : EventKind or int
            What happened.
        vehicle : int
            Vehicle slot concerned, 0 <= vehicle < N.
        other : int
            Second vehicle slot (collision partner, cooperating vehicle ...), -1 if none.
        x : float
            Longitudinal position of the event [m], NaN if not given.
        value : float
            Kind-specific payload (see :class:`EventKind`), NaN if not given.

        Raises
        ------
        ValueError
            On an unknown *kind* or a vehicle index out of range.
        """
        self._event_table.add(t, kind, vehicle, other, x, value)

    def finish(self, n: int | None = None) -> SimulationLog:
        """Trim the log to its first *n* rows (and a slot-column log to the columns it
        used), releasing the memory of the rest.

        Parameters
        ----------
        n : int or None
            Rows to keep; default :attr:`n_recorded`. Must be in [0, T].

        Returns
        -------
        SimulationLog
            ``self``, for chaining.
        """
        n = self._n_recorded if n is None else int(n)
        if not 0 <= n <= self.n_steps:
            raise ValueError(f"cannot trim to {n} rows, log has {self.n_steps}")
        used = self.n_slots if self._one_per_vehicle else int(self.slot.max(initial=-1)) + 1
        if n != self.n_steps or used != self.n_slots:
            self.t = self.t[:n].copy()
            self.owner = self.owner[:used].copy()
            for name in CELL_FIELDS:
                self._cells[name] = self._cells[name][:n, :used].copy()
        self._n_recorded = min(self._n_recorded, n)
        return self

    truncate = finish

    # ------------------------------------------------------------------ events
    @property
    def events(self) -> np.ndarray:
        """All events as a structured array (:data:`EVENT_DTYPE`), stably sorted by t."""
        return self._event_table.sorted()

    def add_events(self, events: np.ndarray) -> None:
        """Append many events at once (a structured array with the fields of
        :data:`EVENT_DTYPE`), in order."""
        self._event_table.extend(events)

    def add_event_columns(
        self, t: np.ndarray, kind: np.ndarray, vehicle: np.ndarray, other: np.ndarray,
        x: np.ndarray, value: np.ndarray,
    ) -> None:  # fmt: skip
        """:meth:`add_events` from one array per field."""
        self._event_table.extend_columns(t, kind, vehicle, other, x, value)

    @property
    def n_events(self) -> int:
        """Number of events recorded so far."""
        return len(self._event_table)

    def events_since(self, start: int) -> np.ndarray:
        """The events recorded after the first ``start`` ones, in recording order (a
        stream's cursor: ``events_since(n)`` with ``n`` an earlier :attr:`n_events`)."""
        return self._event_table.since(start)

    def events_of(self, kind: EventKind | int) -> np.ndarray:
        """Events of one kind, stably sorted by t."""
        return self._event_table.of_kind(kind)

    def events_frame(self) -> pd.DataFrame:
        """Events as a DataFrame; ``kind`` is a categorical of :class:`EventKind` names."""
        return self._event_table.frame()

    # ------------------------------------------------------------------ long format
    def long_columns(self) -> dict[str, np.ndarray]:
        """Columns of :meth:`to_frame` as arrays (also the Parquet file's table)."""
        from hcomc.sim.log_io import long_columns  # the long format lives in log_io

        return long_columns(self)

    def to_frame(self) -> pd.DataFrame:
        """Long-format trajectories: one row per active (step, vehicle) cell.

        Returns
        -------
        pandas.DataFrame
            Columns ``step`` (int64), ``t`` [s] (float64), ``vehicle`` (int64), ``kind``
            (int8, 0 = HDV, 1 = CAV), ``x`` [m], ``y`` [m], ``v`` [m/s], ``a`` [m/s^2],
            ``heading`` [rad] (float32), ``lane`` (int8), ``length`` [m], ``width`` [m]
            (float32), ordered by step then vehicle.
        """
        return pd.DataFrame(self.long_columns())

    # ------------------------------------------------------------------ persistence
    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the log to ``path`` (``.npz``, or ``.parquet`` with the events in the sibling
        ``<stem>.events.parquet``; the directory must exist), atomically: an interrupted save
        leaves existing files intact. Returns the path; ``ValueError`` on another suffix,
        ``TypeError`` if :attr:`meta` is not JSON-serialisable (:mod:`hcomc.sim.log_io`)."""
        from hcomc.sim.log_io import write_log  # the file formats live in log_io

        return write_log(self, path)

    @staticmethod
    def events_path(path: str | os.PathLike[str]) -> Path:
        """Sibling file holding the events of a Parquet log: ``<stem>.events.parquet``."""
        from hcomc.sim.log_io import events_path

        return events_path(path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> SimulationLog:
        """Read a log written by :meth:`save`: arrays, events, ``dt``, ``n_recorded`` and
        ``meta`` as saved. ``ValueError`` on another suffix, an unknown format version, or a
        Parquet events file that does not belong to the log file."""
        from hcomc.sim.log_io import read_log

        return read_log(path)
