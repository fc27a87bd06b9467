"""Simulation log: preallocated struct-of-arrays trajectories plus a list of events.

The engine writes one row per logging step with :meth:`SimulationLog.record` (a handful
of vectorised numpy operations, no Python loop over vehicles) and appends rare discrete
events (insertions, lane changes, merges, collisions, plan fallbacks ...) with
:meth:`SimulationLog.add_event`. Metrics, tables and figures read the log afterwards.

Layout (``T`` logging steps x ``N`` vehicle slots):

=========== ========= ======== ======================================= ==============
array       shape     dtype    meaning                                 unused cell
=========== ========= ======== ======================================= ==============
``t``       (T,)      float64  time of the row [s]                     NaN
``x``       (T, N)    float32  longitudinal position [m]               NaN
``y``       (T, N)    float32  lateral position [m]                    NaN
``v``       (T, N)    float32  speed [m/s]                             NaN
``a``       (T, N)    float32  acceleration [m/s^2]                    NaN
``heading`` (T, N)    float32  heading angle [rad]                     NaN
``lane``    (T, N)    int8     lane index (0 = ramp, 1, 2)             -1
``active``  (T, N)    bool     vehicle is on the road                  False
``kind``    (N,)      int8     0 = HDV, 1 = CAV                        -
``length``  (N,)      float32  vehicle length [m]                      -
``width``   (N,)      float32  vehicle width [m]                       -
=========== ========= ======== ======================================= ==============

A (step, vehicle) cell costs 22 bytes (float32 states; float32 resolution at
x = 1500 [m] is about 1e-4 [m]). A 1 GiB budget for a 1-hour run with
2000 vehicle slots therefore needs a logging interval of at least 0.15 [s]
(3600 / 0.15 * 2000 * 22 B = 0.98 GiB); at 0.1 [s] the arrays take 1.48 GiB.

Files (``.npz``, ``.parquet``, written atomically and read back exactly) are handled by
:mod:`hcomc.sim.log_io` behind :meth:`SimulationLog.save` and :meth:`SimulationLog.load`.
"""

from __future__ import annotations

import enum
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hcomc._typing import BoolArray, FloatArray, IntArray

__all__ = ["EVENT_DTYPE", "EventKind", "SimulationLog"]


_STATE_FIELDS = ("x", "y", "v", "a", "heading")
_VEHICLE_FIELDS = ("kind", "length", "width")
_ARRAY_FIELDS = ("t", *_STATE_FIELDS, "lane", "active", *_VEHICLE_FIELDS)


class EventKind(enum.IntEnum):
    """Kinds of discrete events recorded in a :class:`SimulationLog`."""

    INSERTION = 0
    """A vehicle entered the simulation."""
    LANE_CHANGE_START = 1
    """A vehicle started a (quintic) lane change; ``value`` = target lane."""
    LANE_CHANGE_END = 2
    """A vehicle completed a lane change; ``value`` = new lane."""
    MERGE = 3
    """A ramp vehicle completed its merge into lane 1."""
    COLLISION = 4
    """Two vehicles' rectangles overlap; ``vehicle`` and ``other`` are the pair."""
    RAMP_WAIT = 5
    """A ramp vehicle stopped at the end of the acceleration lane."""
    EXIT = 6
    """A vehicle left the simulated road."""
    PLAN = 7
    """A merge controller issued a plan for a ramp vehicle."""
    FALLBACK = 8
    """A controller fell back to a safe plan (e.g. all candidates infeasible)."""


EVENT_DTYPE = np.dtype(
    [
        ("t", "f8"),  # [s]
        ("kind", "i1"),  # EventKind
        ("vehicle", "i8"),  # vehicle slot
        ("other", "i8"),  # second vehicle slot, -1 if none
        ("x", "f8"),  # position [m], NaN if not given
        ("value", "f8"),  # kind-specific payload, NaN if not given
    ]
)
"""Structured dtype of :attr:`SimulationLog.events`."""


class SimulationLog:
    """Preallocated struct-of-arrays log of one simulation run.

    Build it with :meth:`allocate` (or :meth:`load`); the constructor takes ready arrays
    and is meant for internal use. See the module docstring for the array layout.

    Parameters
    ----------
    dt : float
        Logging interval [s].
    t : numpy.ndarray
        (T,) float64 row times [s].
    x, y, v, a, heading : numpy.ndarray
        (T, N) float32 position [m], lateral position [m], speed [m/s],
        acceleration [m/s^2], heading [rad].
    lane : numpy.ndarray
        (T, N) int8 lane index, -1 when inactive.
    active : numpy.ndarray
        (T, N) bool activity mask.
    kind : numpy.ndarray
        (N,) int8 vehicle type, 0 = HDV, 1 = CAV.
    length, width : numpy.ndarray
        (N,) float32 vehicle dimensions [m].
    meta : dict or None
        JSON-serialisable run metadata (seed, config, version ...).
    n_recorded : int
        Number of rows already written.
    events : numpy.ndarray or None
        Initial events, :data:`EVENT_DTYPE`.
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
        dt = float(dt)
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt (logging interval) must be finite and > 0 [s], got {dt}")
        self.dt: float = dt
        self.t: FloatArray = t
        self.x = x
        self.y = y
        self.v = v
        self.a = a
        self.heading = heading
        self.lane = lane
        self.active = active
        self.kind = kind
        self.length = length
        self.width = width
        self.meta: dict[str, Any] = {} if meta is None else meta
        n_steps, n_vehicles = self.x.shape
        for name in (*_STATE_FIELDS, "lane", "active"):
            if getattr(self, name).shape != (n_steps, n_vehicles):
                raise ValueError(
                    f"{name} has shape {getattr(self, name).shape}, "
                    f"expected {(n_steps, n_vehicles)}"
                )
        if self.t.shape != (n_steps,):
            raise ValueError(f"t has shape {self.t.shape}, expected {(n_steps,)}")
        for name in _VEHICLE_FIELDS:
            if getattr(self, name).shape != (n_vehicles,):
                raise ValueError(
                    f"{name} has shape {getattr(self, name).shape}, expected {(n_vehicles,)}"
                )
        if not 0 <= n_recorded <= n_steps:
            raise ValueError(f"n_recorded must be in [0, {n_steps}], got {n_recorded}")
        self._n_recorded = int(n_recorded)
        self._events: list[tuple[float, int, int, int, float, float]] = []
        if events is not None:
            self._events.extend(tuple(e.item()) for e in np.asarray(events, EVENT_DTYPE))

    # ------------------------------------------------------------------ construction
    @staticmethod
    def bytes_needed(n_steps: int, n_vehicles: int) -> int:
        """Memory of the (T x N) arrays of a log [bytes]: five float32 states, int8 lane and
        bool active per cell (events and per-vehicle arrays are negligible)."""
        return n_steps * n_vehicles * (len(_STATE_FIELDS) * 4 + 1 + 1)

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
    ) -> SimulationLog:
        """Preallocate an empty log.

        Parameters
        ----------
        n_steps : int
            Number of logging rows T (>= 0).
        n_vehicles : int
            Number of vehicle slots N (>= 0).
        dt : float
            Logging interval [s] (> 0).
        kind : array_like of int, shape (N,)
            Vehicle type per slot, 0 = HDV, 1 = CAV.
        length, width : array_like of float, shape (N,)
            Vehicle dimensions [m] (finite, > 0).
        meta : dict or None
            JSON-serialisable run metadata. Stored by reference.

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
        per_vehicle: dict[str, np.ndarray] = {}
        for name, value in (("kind", kind), ("length", length), ("width", width)):
            arr = np.asarray(value)
            if arr.shape != (n_vehicles,):
                raise ValueError(f"{name} must have shape ({n_vehicles},), got {arr.shape}")
            per_vehicle[name] = arr
        kind_arr = per_vehicle["kind"]
        if kind_arr.size and not np.isin(kind_arr, (0, 1)).all():
            raise ValueError(f"kind must be 0 (HDV) or 1 (CAV), got values {np.unique(kind_arr)}")
        for name in ("length", "width"):
            arr = per_vehicle[name].astype(np.float64)
            if arr.size and not (np.isfinite(arr).all() and (arr > 0).all()):
                raise ValueError(f"{name} must be finite and > 0 [m]")
        shape = (n_steps, n_vehicles)
        states = {name: np.full(shape, np.nan, dtype=np.float32) for name in _STATE_FIELDS}
        return cls(
            dt=dt,
            t=np.full(n_steps, np.nan, dtype=np.float64),
            lane=np.full(shape, -1, dtype=np.int8),
            active=np.zeros(shape, dtype=np.bool_),
            kind=kind_arr.astype(np.int8),
            length=per_vehicle["length"].astype(np.float32),
            width=per_vehicle["width"].astype(np.float32),
            meta=meta,
            x=states["x"],
            y=states["y"],
            v=states["v"],
            a=states["a"],
            heading=states["heading"],
        )

    # ------------------------------------------------------------------ sizes
    @property
    def n_steps(self) -> int:
        """Number of allocated rows T."""
        return int(self.x.shape[0])

    @property
    def n_vehicles(self) -> int:
        """Number of vehicle slots N."""
        return int(self.x.shape[1])

    @property
    def n_recorded(self) -> int:
        """Number of rows written so far (highest recorded row index + 1)."""
        return self._n_recorded

    @property
    def vehicle_steps(self) -> int:
        """Number of active (step, vehicle) cells."""
        return int(np.count_nonzero(self.active))

    @property
    def nbytes(self) -> int:
        """Memory held by the log's arrays [bytes] (events excluded)."""
        return int(sum(getattr(self, name).nbytes for name in _ARRAY_FIELDS))

    def __repr__(self) -> str:
        return (
            f"SimulationLog(n_steps={self.n_steps}, n_vehicles={self.n_vehicles}, "
            f"dt={self.dt}, n_recorded={self.n_recorded}, "
            f"vehicle_steps={self.vehicle_steps}, n_events={len(self._events)})"
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
        never carries stale state. Rewriting a row overwrites it completely.

        Parameters
        ----------
        k : int
            Row index, 0 <= k < T.
        t : float
            Simulation time of the row [s].
        x, y, v, a, heading : numpy.ndarray, shape (N,)
            Position [m], lateral position [m], speed [m/s], acceleration [m/s^2],
            heading [rad] of every slot (any value for inactive slots).
        lane : numpy.ndarray of int, shape (N,)
            Lane index of every slot.
        active : numpy.ndarray of bool, shape (N,)
            Which slots are on the road.

        Raises
        ------
        IndexError
            If *k* is outside [0, T).
        """
        if not 0 <= k < self.x.shape[0]:
            raise IndexError(f"row {k} outside the log's {self.x.shape[0]} rows")
        self.t[k] = t
        self.active[k] = active
        mask = self.active[k]  # bool view: accepts any truthy input dtype
        self.x[k] = np.where(mask, x, np.nan)
        self.y[k] = np.where(mask, y, np.nan)
        self.v[k] = np.where(mask, v, np.nan)
        self.a[k] = np.where(mask, a, np.nan)
        self.heading[k] = np.where(mask, heading, np.nan)
        self.lane[k] = np.where(mask, lane, -1)
        if k >= self._n_recorded:
            self._n_recorded = k + 1

    def mark_recorded(self, n: int) -> None:
        """Declare rows ``0 .. n-1`` written (by a compiled writer that fills the arrays
        directly, as :func:`hcomc.sim.core.record_row` does)."""
        if not 0 <= n <= self.x.shape[0]:
            raise IndexError(f"{n} rows outside the log's {self.x.shape[0]} rows")
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
        kind = EventKind(kind)
        n = self.x.shape[1]
        if not 0 <= vehicle < n:
            raise ValueError(f"event vehicle {vehicle} outside [0, {n})")
        if not -1 <= other < n:
            raise ValueError(f"event other vehicle {other} outside [-1, {n})")
        self._events.append((float(t), int(kind), int(vehicle), int(other), float(x), float(value)))

    def finish(self, n: int | None = None) -> SimulationLog:
        """Trim the log to its first *n* rows, releasing the memory of the rest.

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
        if n != self.n_steps:
            for name in ("t", *_STATE_FIELDS, "lane", "active"):
                setattr(self, name, getattr(self, name)[:n].copy())
        self._n_recorded = min(self._n_recorded, n)
        return self

    truncate = finish

    # ------------------------------------------------------------------ events
    @property
    def events(self) -> np.ndarray:
        """All events as a structured array (:data:`EVENT_DTYPE`), stably sorted by t."""
        arr = np.array(self._events, dtype=EVENT_DTYPE)
        return arr[np.argsort(arr["t"], kind="stable")]

    def events_of(self, kind: EventKind | int) -> np.ndarray:
        """Events of one kind, stably sorted by t."""
        ev = self.events
        return ev[ev["kind"] == int(EventKind(kind))]

    def events_frame(self) -> pd.DataFrame:
        """Events as a DataFrame; ``kind`` is a categorical of :class:`EventKind` names."""
        ev = self.events
        names = [k.name for k in EventKind]
        codes = ev["kind"].astype(np.int64)  # EventKind values are 0..8 == category codes
        return pd.DataFrame(
            {
                "t": ev["t"],
                "kind": pd.Categorical.from_codes(codes, categories=names),
                "vehicle": ev["vehicle"],
                "other": ev["other"],
                "x": ev["x"],
                "value": ev["value"],
            }
        )

    # ------------------------------------------------------------------ long format
    def long_columns(self) -> dict[str, np.ndarray]:
        """Columns of :meth:`to_frame` as arrays (also the Parquet file's table)."""
        steps, vehicles = np.nonzero(self.active)
        cols: dict[str, np.ndarray] = {
            "step": steps.astype(np.int64),
            "t": self.t[steps],
            "vehicle": vehicles.astype(np.int64),
            "kind": self.kind[vehicles],
        }
        for name in _STATE_FIELDS:
            cols[name] = getattr(self, name)[steps, vehicles]
        cols["lane"] = self.lane[steps, vehicles]
        cols["length"] = self.length[vehicles]
        cols["width"] = self.width[vehicles]
        return cols

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
        """Write the log to ``.npz`` or ``.parquet``, atomically.

        Parameters
        ----------
        path : str or os.PathLike
            Target file; the suffix selects the format. For Parquet the events go to the
            sibling ``<stem>.events.parquet``. The directory must exist.

        Returns
        -------
        pathlib.Path
            The target path.

        Raises
        ------
        ValueError
            On an unsupported suffix.
        TypeError
            If :attr:`meta` is not JSON-serialisable.

        Notes
        -----
        Data are written to temporary files in the target directory and moved into
        place with :func:`os.replace`; an interrupted save leaves existing files intact
        and no temporary file behind. For Parquet the two files share a random token,
        so :meth:`load` detects a log and events file that do not belong together.
        """
        from hcomc.sim.log_io import write_log  # the file formats live in log_io

        return write_log(self, path)

    @staticmethod
    def events_path(path: str | os.PathLike[str]) -> Path:
        """Sibling file holding the events of a Parquet log: ``<stem>.events.parquet``."""
        from hcomc.sim.log_io import events_path

        return events_path(path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> SimulationLog:
        """Read a log written by :meth:`save` (``.npz`` or ``.parquet``).

        Parameters
        ----------
        path : str or os.PathLike
            File to read.

        Returns
        -------
        SimulationLog
            Arrays, events, ``dt``, ``n_recorded`` and ``meta`` as saved.

        Raises
        ------
        ValueError
            On an unsupported suffix, an unknown format version, or (Parquet) an events
            file that does not belong to the log file.
        """
        from hcomc.sim.log_io import read_log

        return read_log(path)
