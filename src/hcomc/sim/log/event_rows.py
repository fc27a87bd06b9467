"""The compiled writer of a log's event table (:class:`hcomc.sim.log.events.EventTable`):
events given one array per field, checked and written into the table's structured buffer in
one call, where a check and a copy per field would be a dozen numpy calls per flush of the
engine's event buffer."""

from __future__ import annotations

import numpy as np

from hcomc._jit import kernel

WRITTEN, WRONG_KIND, WRONG_VEHICLE = range(3)
"""What :func:`append_events` returns: written, or what is wrong (nothing written then)."""


@kernel
def append_events(
    buf: np.ndarray, start: int,
    fields: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    n_vehicles: int, first_kind: int, last_kind: int,
) -> int:  # fmt: skip
    """Write the events ``fields`` (t, kind, vehicle, other, x, value) into the rows of
    ``buf`` from ``start`` (room there) after checking every one: a kind in [first_kind,
    last_kind], a vehicle in [0, n_vehicles), another in [-1, n_vehicles)."""
    t, kind, vehicle, other, x, value = fields
    for q in range(t.size):
        if not first_kind <= kind[q] <= last_kind:
            return WRONG_KIND
    for q in range(t.size):
        if not (0 <= vehicle[q] < n_vehicles and -1 <= other[q] < n_vehicles):
            return WRONG_VEHICLE
    for q in range(t.size):
        row = buf[start + q]
        row.t, row.kind, row.vehicle, row.other = t[q], kind[q], vehicle[q], other[q]
        row.x, row.value = x[q], value[q]
    return WRITTEN
