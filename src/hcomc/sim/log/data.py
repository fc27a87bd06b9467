"""The data of a simulation log and how to read it: trajectories in preallocated arrays, and
the table of events.

The trajectories read as ``T`` logging rows x ``N`` vehicles: ``t`` (T,) float64 and
``x, y, v, a, heading`` (float32), ``lane`` (int8), ``active`` (bool), each indexed like a
(T, N) numpy array, plus per-vehicle ``kind``, ``length``, ``width``. A log built from plain
(T, N) arrays stores them as they are. The engine's log stores its cells in slot columns that
vehicles leaving the road hand on to vehicles entering it, so its memory follows the number
of vehicles on the road at once, not the number over the run (:mod:`hcomc.sim.log.slots`);
its ``x`` ... ``active`` are read views of the same (T, N) shape. The layout, the reasons
for each dtype and the memory figures are in :mod:`hcomc.sim.log.layout`; the events in
:mod:`hcomc.sim.log.events`.

:class:`LogData` builds, holds and reads these; :class:`hcomc.sim.log.SimulationLog` adds the
writing, the long format and the files. The files module (:mod:`hcomc.sim.log.files`) writes and
reads a :class:`LogData`, so it does not depend on the log class it serves.
"""

from __future__ import annotations

import math
from typing import Any, Self

import numpy as np
import pandas as pd

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.sim.log.events import EventKind, EventTable
from hcomc.sim.log.layout import (
    ARRAY_FIELDS,
    CELL_FIELDS,
    FILL,
    VEHICLE_FIELDS,
    allocate_rows,
    as_layout,
    bytes_needed,
    vehicle_arrays,
)
from hcomc.sim.log.slots import (
    OPEN,
    VehicleCells,
    empty_slots,
    identity_slots,
    owner_grid,
    widen,
)

__all__ = ["LogData"]


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
    else a (T, N) :class:`~hcomc.sim.log.slots.VehicleCells` read view."""
    return property(lambda log: log._view(name), doc=doc)


class LogData:
    """The arrays and events of one simulation run, built, held and read (the constructor's
    parameters are those of :class:`hcomc.sim.log.SimulationLog`, the class to use)."""

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
    ) -> Self:
        """A log stored in slot columns (:mod:`hcomc.sim.log.slots`): ``cells`` maps each of
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
        :func:`hcomc.sim.log.layout.bytes_needed`.
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
    ) -> Self:
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
            (:mod:`hcomc.sim.log.slots`); :meth:`~hcomc.sim.log.SimulationLog.record` adds
            columns when more vehicles are on the road at once.

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

    # ------------------------------------------------------------------ events
    @property
    def events(self) -> np.ndarray:
        """All events as a structured array (:data:`~hcomc.sim.log.events.EVENT_DTYPE`), stably
        sorted by t."""
        return self._event_table.sorted()

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
