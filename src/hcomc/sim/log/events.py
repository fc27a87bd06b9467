"""The event table of a :class:`~hcomc.sim.log.SimulationLog`: rare discrete events.

Insertions, lane changes, merges, collisions, plans, fallbacks ... are appended one at a
time to a growable structured numpy array (:data:`EVENT_DTYPE`, 41 bytes per event; the
buffer doubles when full) and read back sorted by time.
"""

from __future__ import annotations

import enum
import math

import numpy as np
import pandas as pd

from hcomc.sim.log.event_rows import WRONG_KIND, WRONG_VEHICLE, append_events

__all__ = ["EVENT_DTYPE", "EventKind", "EventTable"]


class EventKind(enum.IntEnum):
    """Kinds of discrete events recorded in a :class:`~hcomc.sim.log.SimulationLog`."""

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
    MISSED_EXIT = 9
    """A vehicle bound for an off-ramp passed its deceleration lane on the mainline and
    drives on to the mainline's end; ``value`` = the off-ramp lane's code."""
    LANE_CHANGE_ABORT = 10
    """A vehicle gave up a lane change it stood still in before the lane line when its
    duration was over; ``value`` = the lane it had aimed for."""
    PLAN_LOST = 11
    """The V2X channel lost a plan on its way to the vehicles (``[v2x]``); ``vehicle`` = VR."""
    SHIELD = 12
    """The safety shield overrode a command (``[shield]``); ``other`` = the vehicle it was
    unsafe to, ``value`` = 0 braked, 1 held a lane change, 2 released VR from its plan."""
    FAULT = 13
    """An injected fault began to act on ``vehicle`` (``[[faults]]``); ``value`` = the
    fault's index in the list."""
    V2X_SILENT = 14
    """The controller heard nothing new of key vehicle ``vehicle`` on the V2X channel for
    longer than ``[v2x].stale_after`` (messages lost or late); logged when its next message
    arrives, ``value`` = the time between the two messages' broadcasts [s]."""


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
"""Structured dtype of :attr:`SimulationLog.events` (packed, 41 bytes per event)."""

_INITIAL_CAPACITY = 64
_FIRST_KIND, _LAST_KIND = int(min(EventKind)), int(max(EventKind))
assert list(EventKind) == list(range(_FIRST_KIND, _LAST_KIND + 1))  # kinds are contiguous


class EventTable:
    """Append-only table of events about ``n_vehicles`` vehicle slots.

    Parameters
    ----------
    n_vehicles : int
        Number of vehicle slots; event vehicles must lie in [0, n_vehicles).
    events : numpy.ndarray or None
        Initial events (:data:`EVENT_DTYPE` or a structured array with the same fields),
        e.g. read from a file; kept in the given order.
    """

    def __init__(self, n_vehicles: int, events: np.ndarray | None = None) -> None:
        self.n_vehicles = int(n_vehicles)
        initial = np.zeros(0, EVENT_DTYPE) if events is None else np.asarray(events)
        if initial.ndim != 1:
            raise ValueError(f"events must be one-dimensional, got shape {initial.shape}")
        self._buf = np.empty(max(_INITIAL_CAPACITY, initial.size), dtype=EVENT_DTYPE)
        for name in EVENT_DTYPE.names or ():
            self._buf[name][: initial.size] = initial[name]
        self._n = int(initial.size)

    def __len__(self) -> int:
        return self._n

    @property
    def nbytes(self) -> int:
        """Memory held by the table's buffer [bytes] (capacity, not only the used part)."""
        return int(self._buf.nbytes)

    def add(
        self,
        t: float,
        kind: EventKind | int,
        vehicle: int,
        other: int = -1,
        x: float = math.nan,
        value: float = math.nan,
    ) -> None:
        """Append one event (see :meth:`SimulationLog.add_event`).

        Raises
        ------
        ValueError
            On an unknown *kind* or a vehicle index out of range.
        """
        kind = EventKind(kind)
        n = self.n_vehicles
        if not 0 <= vehicle < n:
            raise ValueError(f"event vehicle {vehicle} outside [0, {n})")
        if not -1 <= other < n:
            raise ValueError(f"event other vehicle {other} outside [-1, {n})")
        if self._n == self._buf.size:
            grown = np.empty(2 * self._buf.size, dtype=EVENT_DTYPE)
            grown[: self._n] = self._buf
            self._buf = grown
        self._buf[self._n] = (float(t), int(kind), int(vehicle), int(other), float(x), float(value))
        self._n += 1

    def extend(self, events: np.ndarray) -> None:
        """Append many events at once (:data:`EVENT_DTYPE` fields), checked as :meth:`add`
        checks one."""
        self.extend_columns(*(events[name] for name in EVENT_DTYPE.names or ()))

    def extend_columns(
        self, t: np.ndarray, kind: np.ndarray, vehicle: np.ndarray, other: np.ndarray,
        x: np.ndarray, value: np.ndarray,
    ) -> None:  # fmt: skip
        """:meth:`extend` from one array per field (the engine's event buffers), checked and
        written by one compiled call (:func:`hcomc.sim.log.event_rows.append_events`)."""
        m = len(t)
        if m == 0:
            return
        if self._n + m > self._buf.size:
            grown = np.empty(max(2 * self._buf.size, self._n + m), dtype=EVENT_DTYPE)
            grown[: self._n] = self._buf[: self._n]
            self._buf = grown
        n = self.n_vehicles
        wrong = append_events(self._buf, self._n, (t, kind, vehicle, other, x, value), n,
                              _FIRST_KIND, _LAST_KIND)  # fmt: skip
        if wrong == WRONG_KIND:
            raise ValueError(f"unknown event kinds in {sorted(set(kind.tolist()))}")
        if wrong == WRONG_VEHICLE:
            raise ValueError(f"event vehicles outside [0, {n}) (other: [-1, {n}))")
        self._n += m

    def since(self, start: int) -> np.ndarray:
        """The events appended after the first ``start`` ones, in the order they came."""
        return self._buf[start : self._n].copy()

    def sorted(self) -> np.ndarray:
        """All events as a new :data:`EVENT_DTYPE` array, stably sorted by t."""
        used = self._buf[: self._n]
        return used[np.argsort(used["t"], kind="stable")]

    def of_kind(self, kind: EventKind | int) -> np.ndarray:
        """Events of one kind, stably sorted by t."""
        ev = self.sorted()
        return ev[ev["kind"] == int(EventKind(kind))]

    def frame(self) -> pd.DataFrame:
        """Events as a DataFrame; ``kind`` is a categorical of :class:`EventKind` names."""
        ev = self.sorted()
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
