r"""Space-time speed fields of the mainline, for the figures.

Two fields are defined on the same kind of bins (``dx`` = 10 m by ``dt_bin`` = 0.5 s):

* :func:`speed_field`: the mean speed of the logged cells (row, vehicle) that fall in each
  bin; NaN for empty bins. At highway headways most bins are empty.
* :func:`lane_speed_field`: in every logged row the lane's speed profile
  ``v(x)`` is the linear interpolation, in ``x``, between the speeds of the active vehicles
  of that lane (NaN upstream of its first and downstream of its last vehicle); it is sampled
  at each bin's centre and averaged over the rows of the time bin (NaN if no row of the bin
  has a sample). The space between two vehicles so moves at a speed between theirs, which
  is what a contour map of the traffic state shows. The profile is that of
  :mod:`hcomc.metrics.lane_profile`
  (:func:`~hcomc.metrics.logged_profile.lane_profile_at`; the binning is its
  :func:`~hcomc.metrics.lane_profile.field_sums`).

LSRV is not computed on these fields but vehicle by vehicle (:mod:`hcomc.metrics.lsrv`).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._typing import FloatArray
from hcomc.metrics.lane_profile import field_sums, interp_into, lane_profile_of
from hcomc.metrics.window import MetricWindow, road_of, times, window_rows
from hcomc.road import Lane
from hcomc.sim.log import SimulationLog
from hcomc.sim.log.slots import active_columns

__all__ = [
    "DT_BIN",
    "DX_BIN",
    "interp_into",
    "lane_profile_of",
    "lane_speed_field",
    "reference_speed",
    "speed_field",
]

DX_BIN = 10.0
"""Space bin of the speed fields [m]."""
DT_BIN = 0.5
"""Time bin of the speed fields [s]."""

_EPS_BIN = 1e-9  # relative tolerance of bin assignment (float rounding of t/dt_bin)


def _x_edges(x0: float, x1: float, dx: float) -> FloatArray:
    n_x = max(1, math.ceil((x1 - x0) / dx - _EPS_BIN))
    return np.minimum(x0 + np.arange(n_x + 1, dtype=np.float64) * dx, x1)


def _t_edges(log: SimulationLog, window: MetricWindow, dt_bin: float) -> FloatArray:
    """Time bins over ``[t_start, t_end + log.dt)``: each row stands for one interval."""
    if not (math.isfinite(window.t_start) and math.isfinite(window.t_end)):
        return np.array([0.0, 0.0])
    span = window.t_end + log.dt - window.t_start
    n_t = max(1, math.ceil(span / dt_bin - _EPS_BIN))
    edges = window.t_start + np.arange(n_t + 1, dtype=np.float64) * dt_bin
    edges[-1] = min(edges[-1], window.t_end + log.dt)
    return edges


def _time_bin(
    log: SimulationLog, window: MetricWindow, rows: slice, n_t: int, dt_bin: float
) -> np.ndarray:
    it = np.floor((times(log)[rows] - window.t_start) / dt_bin + _EPS_BIN)
    return np.clip(it, 0, n_t - 1).astype(np.int64)


def _check_bins(dx: float, dt_bin: float) -> None:
    if not (dx > 0 and dt_bin > 0):
        raise ValueError(f"bin sizes must be > 0, got dx={dx}, dt_bin={dt_bin}")


# --------------------------------------------------------------------------- plot field
def speed_field(
    log: SimulationLog,
    window: MetricWindow,
    *,
    lane: int,
    dx: float = DX_BIN,
    dt_bin: float = DT_BIN,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Binned space-time speed field v(x, t) of one lane: mean speed of the cells per bin.

    Definition: the active cells (row, vehicle) of the window rows with logged lane
    ``lane`` and front bumper ``0 <= x <= road.length`` are binned by x into bins
    ``[k dx, (k+1) dx)`` over ``[0, road.length]`` (the last bin is closed and may be
    narrower) and by row time into bins ``[t_start + m dt_bin, t_start + (m+1) dt_bin)``
    over ``[t_start, t_end + log.dt)`` (the last bin may be narrower). A bin's speed is the
    mean speed of its cells.

    Returns
    -------
    x_edges : numpy.ndarray, shape (n_x + 1,)
        Space bin edges [m].
    t_edges : numpy.ndarray, shape (n_t + 1,)
        Time bin edges [s].
    V : numpy.ndarray, shape (n_t, n_x)
        Mean speed per bin [m/s], NaN for empty bins; rows are time bins, so
        ``pcolormesh(x_edges, t_edges, V)`` draws it.
    """
    _check_bins(dx, dt_bin)
    x_edges = _x_edges(0.0, road_of(log).length, dx)
    t_edges = _t_edges(log, window, dt_bin)
    n_x, n_t = x_edges.size - 1, t_edges.size - 1
    rows = window_rows(log, window)
    x = log.x[rows].astype(np.float64)
    with np.errstate(invalid="ignore"):
        cell = log.active[rows] & (log.lane[rows] == lane) & (x >= 0.0) & (x <= x_edges[-1])
    r, c = np.nonzero(cell)
    ix = np.clip(np.floor(x[r, c] / dx + _EPS_BIN), 0, n_x - 1).astype(np.int64)
    it = _time_bin(log, window, rows, n_t, dt_bin)[r]
    flat = it * n_x + ix
    v = log.v[rows][r, c].astype(np.float64)
    sums = np.bincount(flat, weights=v, minlength=n_t * n_x).reshape(n_t, n_x)
    counts = np.bincount(flat, minlength=n_t * n_x).reshape(n_t, n_x)
    with np.errstate(invalid="ignore", divide="ignore"):
        V = np.where(counts > 0, sums / counts, np.nan)
    return x_edges, t_edges, V


def reference_speed(log: SimulationLog, window: MetricWindow) -> float:
    """Mean mainline speed upstream of the control zone [m/s] (a colour-scale anchor for plots).

    Definition: the mean of ``v`` over all active cells of the window rows with logged lane
    1 or 2 and ``x < road.control_zone_start``; if there is none, over all active lane-1/2
    cells of the window rows; NaN if there is none either.
    """
    rows = window_rows(log, window)
    lane = log.lane[rows]
    main = log.active[rows] & ((lane == Lane.MAIN_1) | (lane == Lane.MAIN_2))
    v = log.v[rows].astype(np.float64)
    upstream = main & (log.x[rows].astype(np.float64) < road_of(log).control_zone_start)
    for mask in (upstream, main):
        if mask.any():
            return float(v[mask].mean())
    return math.nan


def _lane_fields(
    log: SimulationLog, window: MetricWindow, lanes: tuple[int, ...], x_min: float, dx: float,
    dt_bin: float,
) -> tuple[FloatArray, FloatArray, list[FloatArray]]:  # fmt: skip
    """:func:`lane_speed_field` of each of ``lanes``, from one pass over the window rows:
    ``(x_edges, t_edges, [V per lane])``."""
    _check_bins(dx, dt_bin)
    x_edges = _x_edges(x_min, road_of(log).length, dx)
    t_edges = _t_edges(log, window, dt_bin)
    n_x, n_t = x_edges.size - 1, t_edges.size - 1
    centres = 0.5 * (x_edges[:-1] + x_edges[1:])
    rows = window_rows(log, window)
    it = _time_bin(log, window, rows, n_t, dt_bin)
    sums = np.zeros((len(lanes), n_t, n_x))
    counts = np.zeros((len(lanes), n_t, n_x))
    cells = log.cells
    start, _, column = active_columns(cells["active"], log.slot, log.span, rows.start, rows.stop)
    field_sums(cells["x"], cells["lane"], cells["v"], start, column, rows.start,
                np.array(lanes, dtype=np.int64), centres, np.asarray(it, dtype=np.int64), sums,
                counts)  # fmt: skip
    with np.errstate(invalid="ignore", divide="ignore"):
        fields = [np.where(n > 0, total / n, np.nan) for total, n in zip(sums, counts, strict=True)]
    return x_edges, t_edges, fields


def lane_speed_field(
    log: SimulationLog,
    window: MetricWindow,
    *,
    lane: int,
    x_min: float = 0.0,
    dx: float = DX_BIN,
    dt_bin: float = DT_BIN,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Vehicle-interpolated speed field of one lane over ``[x_min, road.length]`` [m/s].

    Definition: space bins ``[x_min + k dx, x_min + (k+1) dx)`` up to ``road.length`` (the
    last may be narrower), time bins as in :func:`speed_field`. In each window row the
    lane's profile of :func:`~hcomc.metrics.logged_profile.lane_profile_at` (no clamping)
    is sampled at the bin centres; a bin's speed is the mean of the finite samples of the
    rows of its time bin, NaN if there is none.

    Returns ``(x_edges, t_edges, V)`` shaped as in :func:`speed_field`.
    """
    x_edges, t_edges, (V,) = _lane_fields(log, window, (int(lane),), x_min, dx, dt_bin)
    return x_edges, t_edges, V
