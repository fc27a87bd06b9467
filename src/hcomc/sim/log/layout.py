"""Array layout of a :class:`~hcomc.sim.log.SimulationLog`: names, dtypes, fill values, sizes.

This module is the one home of the log's column dtypes. A log of ``T`` logging rows and
``N`` vehicles reads as (the engine's log stores the (T, N) arrays in slot columns,
:mod:`hcomc.sim.log.slots`):

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

The stored arrays are plain C-contiguous numpy arrays, one row per logging step, so a row
is one contiguous block that a compiled kernel can write directly.

**Why these dtypes.** The simulation integrates in float64; the log only stores results.

* ``x`` float32: float32 numbers in [2**k, 2**(k+1)) are 2**(k-23) apart: 0.12 mm for
  positions of 1024-2048 m (the shipped merge scenarios, 1.5 km), 0.24 mm up to 4096 m,
  0.49 mm up to 8192 m (the 5 km platoon road). A gap ``x_l - L_l - x_f`` read from the
  log is therefore off by at most one spacing, and a crossing time interpolated from x
  (the post-encroachment time) by that over the speed (1e-5 s at 25 m/s). Speeds are
  logged themselves, so nothing differentiates x over a 0.1 s row, where this would
  matter. The spacing keeps doubling with the road length: 3.9 mm up to 65 km (the
  stretched roads of the throughput benchmark), 6 cm at the 1000 km limit of
  ``road.length``. float64 x would add 4 bytes to each 22-byte cell for no metric that
  can see the difference.
* ``v``, ``a``, ``y``, ``heading`` float32: relative resolution 6e-8 (1.9e-6 m/s at
  30 m/s, 2.4e-7 m/s^2 at 3 m/s^2), far below every metric tolerance (0.05 m/s^2, 0.5 m/s)
  and below the reported digits of every metric. float16 would save 2 bytes per value but
  resolve speeds only to 0.016 m/s between 16 and 32 m/s and accelerations to 0.002 m/s^2
  between 2 and 4 m/s^2, coarser than the reported digits of the average-acceleration
  metric (1e-4 m/s^2), so it is not used.
* ``t`` float64: one value per row (8 bytes per row, nothing per vehicle); it keeps row
  times exact to well under the 1e-6 s tolerance the metrics compare times with, which
  float32 (spacing 0.24 ms at 3600 s) would not.
* ``lane`` int8 and ``active`` bool: one byte each, the smallest plain numpy types.

**Memory.** A stored cell costs :data:`BYTES_PER_CELL` = 22 bytes; a row adds 8 bytes
(``t``), a vehicle 33 (``kind``, ``length``, ``width``; its column and rows, ``slot`` and
``span``), a stored column 8 (``owner``). The engine's log stores S slot columns, S = the
most vehicles on the road at once (:mod:`hcomc.sim.log.slots`); a log with one column per
vehicle stores S = N. Events are stored apart (:mod:`hcomc.sim.log.events`, 41 bytes each).
:func:`bytes_needed` gives the exact size of the arrays before allocating them; for 1 hour
with 2000 columns (2000 vehicles on the road at once, or one column each):

============== ======== =========
log interval   rows     arrays
============== ======== =========
0.1 s          36 001   1.48 GiB
0.2 s          18 001   0.74 GiB
0.3 s          12 001   0.49 GiB
0.5 s           7 201   0.30 GiB
1.0 s           3 601   0.15 GiB
============== ======== =========

A 1-hour Condition 1 run of 2020 vehicles holds at most 38 at once: 0.028 GiB at 0.1 s.

The logging interval is the scenario key ``log_interval``: it must be a multiple of the
simulation step ``dt``, and the engine logs every ``log_interval / dt``-th step.
"""

from __future__ import annotations

from typing import Final

import numpy as np

__all__ = [
    "ARRAY_FIELDS",
    "BYTES_PER_CELL",
    "BYTES_PER_ROW",
    "BYTES_PER_SLOT",
    "BYTES_PER_VEHICLE",
    "CELL_FIELDS",
    "DTYPES",
    "FILL",
    "STATE_FIELDS",
    "VEHICLE_FIELDS",
    "allocate_rows",
    "as_layout",
    "bytes_needed",
    "vehicle_arrays",
]

STATE_FIELDS: Final = ("x", "y", "v", "a", "heading")
"""Float state arrays, shape (T, N)."""
CELL_FIELDS: Final = (*STATE_FIELDS, "lane", "active")
"""All (T, N) arrays, one row per logging step."""
VEHICLE_FIELDS: Final = ("kind", "length", "width")
"""Per-vehicle-slot arrays, shape (N,)."""
ARRAY_FIELDS: Final = ("t", *CELL_FIELDS, *VEHICLE_FIELDS)
"""Every array of a log, in file order."""

DTYPES: Final[dict[str, np.dtype]] = {
    "t": np.dtype(np.float64),
    **{name: np.dtype(np.float32) for name in STATE_FIELDS},
    "lane": np.dtype(np.int8),
    "active": np.dtype(np.bool_),
    "kind": np.dtype(np.int8),
    "length": np.dtype(np.float32),
    "width": np.dtype(np.float32),
}
"""dtype of each array (native byte order)."""

FILL: Final[dict[str, float | int | bool]] = {
    "t": np.nan,
    **dict.fromkeys(STATE_FIELDS, np.nan),
    "lane": -1,
    "active": False,
}
"""Value of an unwritten row / inactive cell of each per-row array."""

BYTES_PER_CELL: Final = sum(DTYPES[name].itemsize for name in CELL_FIELDS)
"""Bytes of one (row, vehicle) cell over all (T, N) arrays (22)."""
BYTES_PER_ROW: Final = DTYPES["t"].itemsize
"""Bytes per row outside the cells (the row time, 8)."""
BYTES_PER_VEHICLE: Final = sum(DTYPES[name].itemsize for name in VEHICLE_FIELDS) + 3 * 8
"""Bytes per vehicle outside the cells (kind, length, width: 9; its column and the rows it
holds it, ``slot`` and ``span`` of :mod:`hcomc.sim.log.slots`: 24)."""
BYTES_PER_SLOT: Final = 8
"""Bytes per stored column outside the cells (its current vehicle, ``owner``)."""


def bytes_needed(n_steps: int, n_vehicles: int, n_slots: int | None = None) -> int:
    """Exact memory of the arrays of a log of T rows, N vehicles and S stored columns
    (default S = N: one column per vehicle) [bytes], events excluded.

    Equal to :attr:`SimulationLog.nbytes` of ``SimulationLog.allocate(n_steps, n_vehicles,
    ..., slots=n_slots)``; computed without allocating anything.

    >>> round(bytes_needed(36_001, 2000) / 2**30, 4)  # 1 hour at 0.1 s, 2000 columns [GiB]
    1.4756
    """
    n_steps, n_vehicles = int(n_steps), int(n_vehicles)
    n_slots = n_vehicles if n_slots is None else int(n_slots)
    if n_steps < 0 or n_vehicles < 0 or n_slots < 0:
        raise ValueError(f"n_steps, n_vehicles and n_slots must be >= 0, got {n_steps}, "
                         f"{n_vehicles}, {n_slots}")  # fmt: skip
    return (
        n_steps * n_slots * BYTES_PER_CELL
        + n_steps * BYTES_PER_ROW
        + n_vehicles * BYTES_PER_VEHICLE
        + n_slots * BYTES_PER_SLOT
    )


def allocate_rows(n_steps: int, n_vehicles: int) -> dict[str, np.ndarray]:
    """The per-row arrays ``t`` (T,) and :data:`CELL_FIELDS` (T, N), filled with :data:`FILL`."""
    arrays = {"t": np.full(n_steps, FILL["t"], dtype=DTYPES["t"])}
    for name in CELL_FIELDS:
        arrays[name] = np.full((n_steps, n_vehicles), FILL[name], dtype=DTYPES[name])
    return arrays


def vehicle_arrays(
    n_vehicles: int, *, kind: np.ndarray, length: np.ndarray, width: np.ndarray
) -> dict[str, np.ndarray]:
    """The per-vehicle arrays ``kind, length, width``, checked: shape (N,), kind 0 (HDV) or
    1 (CAV), finite positive dimensions [m]; ``ValueError`` otherwise."""
    out: dict[str, np.ndarray] = {}
    for name, value in (("kind", kind), ("length", length), ("width", width)):
        arr = np.asarray(value)
        if arr.shape != (n_vehicles,):
            raise ValueError(f"{name} must have shape ({n_vehicles},), got {arr.shape}")
        out[name] = arr
    if out["kind"].size and not ((out["kind"] == 0) | (out["kind"] == 1)).all():
        raise ValueError(f"kind must be 0 (HDV) or 1 (CAV), got values {np.unique(out['kind'])}")
    for name in ("length", "width"):
        arr = out[name].astype(np.float64)
        if arr.size and not (np.isfinite(arr).all() and (arr > 0).all()):
            raise ValueError(f"{name} must be finite and > 0 [m]")
    return out


def as_layout(name: str, arr: np.ndarray) -> np.ndarray:
    """``arr`` as a C-contiguous array of the dtype :data:`DTYPES` gives ``name``.

    Returned unchanged (no copy) if it already is one. Otherwise converted: floats are
    rounded to the nearest float32 (how logs saved with float64 states are read), integer
    columns must fit their narrower type.

    Raises
    ------
    ValueError
        If an integer column holds values its dtype cannot represent, or a bool column
        values other than 0/1.
    """
    want = DTYPES[name]
    arr = np.asarray(arr)
    if arr.dtype == want and arr.flags.c_contiguous:
        return arr
    if want.kind in "iub" and arr.size:
        if want.kind == "b":
            lo, hi = 0, 1
        else:
            info = np.iinfo(want)
            lo, hi = int(info.min), int(info.max)
        if arr.dtype.kind == "f" and not np.isfinite(arr).all():
            raise ValueError(f"{name}: non-finite values cannot be stored as {want}")
        if arr.min() < lo or arr.max() > hi or (arr.dtype.kind == "f" and (arr % 1).any()):
            raise ValueError(f"{name}: values outside what {want} can represent")
    return np.ascontiguousarray(arr, dtype=want)
