"""Simulation log: preallocated struct-of-arrays trajectories plus a table of events.

The engine writes one row per logging step (compiled: :func:`hcomc.sim.step.loop.record_row`;
from Python: :meth:`SimulationLog.record`) and appends rare discrete
events (insertions, lane changes, merges, collisions, plan fallbacks ...) with
:meth:`SimulationLog.add_event`. Metrics, tables and figures read the log afterwards.

What a log holds and how it is read — ``T`` logging rows x ``N`` vehicles, in plain (T, N)
arrays or in slot columns, and the events — is :class:`hcomc.sim.log.data.LogData`, which
:class:`SimulationLog` extends with the writing, the long format and the files (``.npz``,
``.parquet``, written atomically and read back exactly, by :mod:`hcomc.sim.log.files` behind
:meth:`SimulationLog.save` and :meth:`SimulationLog.load`).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pandas as pd

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.sim.log.data import LogData
from hcomc.sim.log.events import EVENT_DTYPE, EventKind
from hcomc.sim.log.files import events_path, long_columns, read_log, write_log
from hcomc.sim.log.layout import CELL_FIELDS, FILL
from hcomc.sim.log.slots import claim_slots

__all__ = ["EVENT_DTYPE", "EventKind", "SimulationLog"]


class SimulationLog(LogData):
    """Preallocated struct-of-arrays log of one simulation run.

    Build it with :meth:`allocate` (or :meth:`load`); the constructor takes ready arrays
    and is meant for internal use. See :mod:`hcomc.sim.log.layout` for the array layout.

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
        directly, as :func:`hcomc.sim.step.loop.record_row` does)."""
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

    # ------------------------------------------------------------------ long format
    def long_columns(self) -> dict[str, np.ndarray]:
        """Columns of :meth:`to_frame` as arrays (also the Parquet file's table)."""
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
        ``TypeError`` if :attr:`meta` is not JSON-serialisable (:mod:`hcomc.sim.log.files`)."""
        return write_log(self, path)

    @staticmethod
    def events_path(path: str | os.PathLike[str]) -> Path:
        """Sibling file holding the events of a Parquet log: ``<stem>.events.parquet``."""
        return events_path(path)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> SimulationLog:
        """Read a log written by :meth:`save`: arrays, events, ``dt``, ``n_recorded`` and
        ``meta`` as saved. ``ValueError`` on another suffix, an unknown format version, or a
        Parquet events file that does not belong to the log file."""
        return read_log(path, cls)
