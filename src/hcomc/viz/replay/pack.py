"""A run's trajectories as the replay page's compact binary arrays.

The page draws every frame from typed arrays (no per-vehicle objects), so the log is packed
into a few of them, each sent as base64 of its little-endian bytes:

* vehicles are laid out in **columns**: a vehicle keeps one column from the first to the
  last row it is on the road, and a column is handed on once its vehicle has left, so there
  are as many columns as vehicles on the road at once (whatever the log's own layout);
* per (row, column) cell: ``x`` as float32, the log's own precision (0.12 mm on a 2 km
  road), NaN in a free cell; ``y``, ``heading``, ``v`` and ``a`` quantised to int16 with the
  steps of :data:`STEPS` (1 mm, 0.1 mrad, 1 mm/s, 1 mm/s^2; a step doubles until the run's
  largest value fits); ``lane`` as int8;
* per vehicle: ``kind``, ``length``, ``width`` and its ``column``, ``first`` and ``last``
  row, from which the page rebuilds which vehicle each cell holds.

A corridor run's samples are packed the same way (:mod:`hcomc.viz.replay.corridor_run`),
with one more int16 cell array, ``dx``: where the vehicle is drawn minus its ``x`` (1 mm
steps; non-zero on a ramp road, which slopes away from the mainline).

A 90-s Condition 1 run makes a page of 0.43 MB, player included.
"""

from __future__ import annotations

import base64
import heapq
from dataclasses import dataclass
from typing import Any

import numpy as np

from hcomc.sim.log import SimulationLog

__all__ = [
    "STEPS", "Columns", "columns_of", "encode", "pack_cells", "pack_fleet", "pack_samples",
    "pack_vehicles", "partition", "quantise",
]  # fmt: skip

STEPS: dict[str, float] = {"y": 1e-3, "heading": 1e-4, "v": 1e-3, "a": 1e-3}
"""Nominal quantisation steps of the int16 cell arrays: y [m], heading [rad], v [m/s],
a [m/s^2]."""

_INT16_MAX = 32767

_DTYPES = {"<f4": "f4", "<f8": "f8", "<i2": "i2", "<i1": "i1", "|i1": "i1", "<i4": "i4"}


def encode(array: np.ndarray, step: float | None = None) -> dict[str, Any]:
    """The JSON form of one typed array: dtype, shape, quantisation step and base64 bytes."""
    data = np.ascontiguousarray(array)
    if data.dtype.byteorder == ">" or (data.dtype.byteorder == "=" and np.little_endian is False):
        data = data.astype(data.dtype.newbyteorder("<"))
    code = _DTYPES.get(data.dtype.str)
    if code is None:
        raise ValueError(f"array dtype {data.dtype} cannot be packed; allowed: {sorted(_DTYPES)}")
    return {
        "dtype": code,
        "shape": list(data.shape),
        "step": step,
        "b64": base64.b64encode(data.tobytes()).decode("ascii"),
    }


def quantise(values: np.ndarray, nominal: float) -> tuple[np.ndarray, float]:
    """``values`` as int16 multiples of a step, and the step: ``nominal``, doubled until the
    largest finite magnitude fits; NaN becomes 0 (the page reads activity from ``x``)."""
    finite = np.isfinite(values)
    peak = float(np.abs(values[finite]).max(initial=0.0))
    step = float(nominal)
    while peak / step > _INT16_MAX:
        step *= 2.0
    q = np.zeros(values.shape, dtype=np.int16)
    q[finite] = np.rint(values[finite] / step).astype(np.int16)
    return q, step


@dataclass(frozen=True)
class Columns:
    """Which column each vehicle holds, over which rows.

    ``column``, ``first``, ``last`` are (N,) int32: the column and the first and last row of
    each vehicle, -1 for a vehicle never on the road in the recorded rows; ``n_columns`` is
    the number of columns (the most vehicles on the road at once)."""

    column: np.ndarray
    first: np.ndarray
    last: np.ndarray
    n_columns: int


def _active_cells(log: SimulationLog) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows, stored columns and vehicles of the recorded cells whose vehicle is on the road."""
    n = log.n_recorded
    rows, cols = np.nonzero(log.cells["active"][:n])
    return rows, cols, log.owners()[:n][rows, cols]


def columns_of(log: SimulationLog) -> Columns:
    """Columns for the vehicles of ``log`` (:func:`partition`)."""
    rows, _, ids = _active_cells(log)
    n = log.n_vehicles
    first = np.full(n, np.iinfo(np.int32).max, dtype=np.int64)
    last = np.full(n, -1, dtype=np.int64)
    np.minimum.at(first, ids, rows)
    np.maximum.at(last, ids, rows)
    return partition(first, last)


def partition(first: np.ndarray, last: np.ndarray) -> Columns:
    """Columns for vehicles on the road from row ``first`` to row ``last`` (-1: never) by
    interval partitioning: vehicles in order of their first row, each taking the column
    freed earliest (a new one when none is free)."""
    first, last = np.asarray(first, dtype=np.int64).copy(), np.asarray(last, dtype=np.int64)
    n = last.size
    on_road = np.flatnonzero(last >= 0)
    column = np.full(n, -1, dtype=np.int32)
    free: list[tuple[int, int]] = []  # (first row the column is free, column)
    n_columns = 0
    for i in on_road[np.argsort(first[on_road], kind="stable")].tolist():
        if free and free[0][0] <= first[i]:
            _, c = heapq.heappop(free)
        else:
            c, n_columns = n_columns, n_columns + 1
        column[i] = c
        heapq.heappush(free, (int(last[i]) + 1, c))
    first[last < 0] = -1
    return Columns(column, first.astype(np.int32), last.astype(np.int32), n_columns)


def pack_cells(log: SimulationLog, layout: Columns) -> dict[str, dict[str, Any]]:
    """The encoded (rows x columns) cell arrays ``x, y, heading, v, a, lane`` and ``t``."""
    n = log.n_recorded
    rows, cols, ids = _active_cells(log)
    values = {name: log.cells[name][rows, cols] for name in ("x", "lane", *STEPS)}
    return pack_samples(log.t[:n], layout, rows, layout.column[ids], values)


def pack_samples(
    t: np.ndarray, layout: Columns, rows: np.ndarray, columns: np.ndarray,
    values: dict[str, np.ndarray], steps: dict[str, float] = STEPS,
) -> dict[str, dict[str, Any]]:  # fmt: skip
    """The encoded cell arrays of samples at ``(rows, columns)``: ``t`` (one per row),
    ``x`` as float32, ``lane`` as int8 and each name of ``steps`` quantised to int16 with
    its nominal step (:func:`quantise`); ``values`` holds one value per sample each."""
    shape = (len(t), max(layout.n_columns, 1))
    packed: dict[str, dict[str, Any]] = {"t": encode(np.asarray(t, dtype="<f8"))}
    x = np.full(shape, np.nan, dtype="<f4")
    x[rows, columns] = values["x"]
    packed["x"] = encode(x)
    lane = np.full(shape, -1, dtype=np.int8)
    lane[rows, columns] = values["lane"]
    packed["lane"] = encode(lane)
    for name, nominal in steps.items():
        cells = np.full(shape, np.nan, dtype=np.float32)
        cells[rows, columns] = values[name]
        q, step = quantise(cells, nominal)
        packed[name] = encode(q, step)
    return packed


def pack_vehicles(log: SimulationLog, layout: Columns) -> dict[str, dict[str, Any]]:
    """The encoded per-vehicle arrays ``kind, length, width, column, first, last``."""
    return pack_fleet(log.kind, log.length, log.width, layout)


def pack_fleet(kind: np.ndarray, length: np.ndarray, width: np.ndarray,
               layout: Columns) -> dict[str, dict[str, Any]]:  # fmt: skip
    """The encoded per-vehicle arrays of vehicles of ``kind`` (:class:`hcomc.road.Kind`),
    ``length`` and ``width`` [m] laid out in ``layout``."""
    return {
        "kind": encode(np.asarray(kind, dtype=np.int8)),
        "length": encode(np.asarray(length, dtype="<f4")),
        "width": encode(np.asarray(width, dtype="<f4")),
        "column": encode(layout.column.astype("<i4")),
        "first": encode(layout.first.astype("<i4")),
        "last": encode(layout.last.astype("<i4")),
    }
