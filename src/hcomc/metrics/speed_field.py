r"""Space-time speed fields of the mainline and the low-speed region volume (LSRV).

Two fields are defined on the same kind of bins (``dx`` = 10 m by ``dt_bin`` = 0.5 s):

* :func:`speed_field` (for plots): the mean speed of the logged cells (row, vehicle) that
  fall in each bin; NaN for empty bins. At highway headways most bins are empty.
* :func:`lane_speed_field` (for LSRV): in every logged row the lane's speed profile
  ``v(x)`` is the linear interpolation, in ``x``, between the speeds of the active vehicles
  of that lane (NaN upstream of its first and downstream of its last vehicle); it is sampled
  at each bin's centre and averaged over the rows of the time bin (NaN if no row of the bin
  has a sample). The space between two vehicles so moves at a speed between theirs, which
  is what a contour map of the traffic state shows.

LSRV compares the factual field with the **undisturbed** field of the same run without the
merge (see :mod:`hcomc.metrics.window`), so speed changes that happen without the merge
(vehicles adjusting to their desired speed, lane changes elsewhere) cancel out.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hcomc._typing import FloatArray
from hcomc.metrics.window import (
    MetricWindow,
    check_reference,
    road_of,
    times,
    window_rows,
)
from hcomc.road import Lane
from hcomc.sim.log import SimulationLog

__all__ = [
    "DT_BIN",
    "DX_BIN",
    "lane_profile_at",
    "lane_profile_of",
    "lane_speed_field",
    "low_speed_region_volume",
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


# --------------------------------------------------------------------------- lane profile
def lane_profile_at(
    log: SimulationLog, row: int, lane: int, x: FloatArray, *, clamp: bool = False
) -> tuple[FloatArray, FloatArray]:
    """Speed and acceleration of lane ``lane`` at positions ``x`` in one logged row.

    Linear interpolation in x between the active vehicles of the lane (sorted by x). Outside
    their range: NaN, or with ``clamp=True`` the nearest vehicle's value. NaN everywhere if
    the lane is empty in that row.
    """
    profile = lane_profile_of(log.x[row], log.active[row], log.lane[row], lane, x, clamp,
                       log.v[row], log.a[row])  # fmt: skip
    return profile[0], profile[1]


@njit(cache=True)
def _last_at_or_below(key: float, xp: np.ndarray) -> int:
    """The largest j with ``xp[j] <= key`` (``xp`` ascending, ``xp[0] <= key``): the
    interval :func:`numpy.interp` interpolates in."""
    lo, hi = 0, xp.size
    while lo < hi:
        mid = (lo + hi) >> 1
        if key >= xp[mid]:
            lo = mid + 1
        else:
            hi = mid
    return lo - 1


@njit(cache=True)
def interp_into(
    x: np.ndarray, xp: np.ndarray, fp: np.ndarray, left: float, right: float, out: np.ndarray
) -> None:
    """``out[:] = numpy.interp(x, xp, fp, left, right)``, value for value: numpy's
    arithmetic and special cases (an exact knot or the last one gives its ``fp``; a NaN from
    an infinite slope is retried from the right knot; one knot has its own rule) for
    ascending ``xp`` (ties allowed)."""
    n = xp.size
    for i in range(x.size):
        xv = x[i]
        if n == 1:  # numpy's own branch for one knot (a NaN query gets fp[0] there)
            out[i] = left if xv < xp[0] else (right if xv > xp[0] else fp[0])
        elif math.isnan(xv):
            out[i] = xv
        elif xv < xp[0]:
            out[i] = left
        elif xv > xp[n - 1]:
            out[i] = right
        else:
            j = _last_at_or_below(xv, xp)
            if j == n - 1 or xp[j] == xv:
                out[i] = fp[j]
                continue
            slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
            value = slope * (xv - xp[j]) + fp[j]
            if math.isnan(value):
                value = slope * (xv - xp[j + 1]) + fp[j + 1]
                if math.isnan(value) and fp[j] == fp[j + 1]:
                    value = fp[j]
            out[i] = value


@njit(cache=True)
def lane_vehicles(
    x_row: np.ndarray, active_row: np.ndarray, lane_row: np.ndarray, lane: int
) -> tuple[np.ndarray, np.ndarray]:
    """The active vehicles of ``lane`` in one logged row, sorted by position (ties in
    vehicle order), and their positions as float64."""
    count = 0
    for i in range(x_row.size):
        count += active_row[i] and lane_row[i] == lane
    on = np.empty(count, dtype=np.int64)
    m = 0
    for i in range(x_row.size):
        if active_row[i] and lane_row[i] == lane:
            on[m] = i
            m += 1
    xs = np.empty(count)
    for m in range(count):
        xs[m] = x_row[on[m]]
    order = np.argsort(xs, kind="mergesort")  # stable
    return on[order], xs[order]


@njit(cache=True)
def _profile_into(
    x_row: np.ndarray, active_row: np.ndarray, lane_row: np.ndarray, lane: int,
    x: np.ndarray, clamp: bool, values: np.ndarray, out: np.ndarray,
) -> None:  # fmt: skip
    """One row's lane profile of ``values`` at ``x`` into ``out`` (see :func:`lane_profile_of`)."""
    on, xs = lane_vehicles(x_row, active_row, lane_row, lane)
    if on.size == 0:
        out[:] = math.nan
        return
    ys = np.empty(on.size)
    for m in range(on.size):
        ys[m] = values[on[m]]
    left, right = (ys[0], ys[-1]) if clamp else (math.nan, math.nan)
    interp_into(x, xs, ys, left, right, out)


def lane_profile_of(
    x_row: np.ndarray, active_row: np.ndarray, lane_row: np.ndarray, lane: int, x: FloatArray,
    clamp: bool, *value_rows: np.ndarray,
) -> list[FloatArray]:  # fmt: skip
    """:func:`lane_profile_at` on one logged row's arrays (N,) (``log.x[row]``,
    ``log.active[row]``, ``log.lane[row]``): each of ``value_rows`` (e.g. ``log.v[row]``)
    interpolated at ``x`` between the active vehicles of ``lane`` (sorted by position, ties
    in vehicle order), as :func:`numpy.interp` does. Callers that visit many rows read the
    arrays once and pass their rows."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    row = (np.asarray(x_row), np.asarray(active_row), np.asarray(lane_row), int(lane))
    out = []
    for values in value_rows:
        profile = np.empty(x.shape)
        _profile_into(*row, x.reshape(-1), bool(clamp), np.asarray(values), profile.reshape(-1))
        out.append(profile)
    return out


@njit(cache=True)
def _field_sums(
    xs: np.ndarray, active: np.ndarray, lanes: np.ndarray, speeds: np.ndarray, lane: int,
    centres: np.ndarray, it: np.ndarray, sums: np.ndarray, counts: np.ndarray,
) -> None:  # fmt: skip
    """Add each row's lane profile at ``centres`` (its finite samples) to the row's time bin
    ``it[k]`` of ``sums`` and ``counts``."""
    v = np.empty(centres.size)
    for k in range(xs.shape[0]):
        _profile_into(xs[k], active[k], lanes[k], lane, centres, False, speeds[k], v)
        for b in range(centres.size):
            if np.isfinite(v[b]):
                sums[it[k], b] += v[b]
                counts[it[k], b] += 1.0


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
    lane's profile of :func:`lane_profile_at` (no clamping) is sampled at the bin centres;
    a bin's speed is the mean of the finite samples of the rows of its time bin, NaN if
    there is none.

    Returns ``(x_edges, t_edges, V)`` shaped as in :func:`speed_field`.
    """
    _check_bins(dx, dt_bin)
    x_edges = _x_edges(x_min, road_of(log).length, dx)
    t_edges = _t_edges(log, window, dt_bin)
    n_x, n_t = x_edges.size - 1, t_edges.size - 1
    centres = 0.5 * (x_edges[:-1] + x_edges[1:])
    rows = window_rows(log, window)
    it = _time_bin(log, window, rows, n_t, dt_bin)
    sums = np.zeros((n_t, n_x))
    counts = np.zeros((n_t, n_x))
    xs, active, lanes, speeds = log.x[rows], log.active[rows], log.lane[rows], log.v[rows]
    _field_sums(xs, active, lanes, speeds, int(lane), centres, np.asarray(it, dtype=np.int64),
                sums, counts)  # fmt: skip
    with np.errstate(invalid="ignore", divide="ignore"):
        V = np.where(counts > 0, sums / counts, np.nan)
    return x_edges, t_edges, V


def low_speed_region_volume(
    log: SimulationLog,
    window: MetricWindow,
    *,
    reference: SimulationLog | None = None,
    dx: float = DX_BIN,
    dt_bin: float = DT_BIN,
) -> float:
    r"""Low-speed region volume LSRV [m²] (paper "LSRV"; smaller is better).

    Definition, summed over lanes 1 and 2, on the bins of :func:`lane_speed_field` with
    ``x_min = road.control_zone_start`` (the cooperative control zone, the acceleration lane
    and everything downstream) over the window ``[t_start, t_end]``:

    .. math::

       \mathrm{LSRV} = \sum_{\text{lane}} \sum_{\text{bins}}
           \max(0,\; V^{u}_{b} - V_{b})\, \Delta x_b\, \Delta t_b

    with ``V_b`` the factual bin speed, ``V^u_b`` the bin speed of the undisturbed
    reference (same run, no merge) and ``Δx_b``, ``Δt_b`` the bin widths [m], [s]. Bins where
    either field is NaN contribute 0. Units: m/s · m · s = m². A run identical to its
    reference scores exactly 0.

    Returns
    -------
    float
        LSRV [m²], >= 0; NaN without a reference.
    """
    if reference is None:
        return math.nan
    check_reference(log, reference)
    x_min = road_of(log).control_zone_start
    total = 0.0
    for lane in (1, 2):
        x_edges, t_edges, V = lane_speed_field(
            log, window, lane=lane, x_min=x_min, dx=dx, dt_bin=dt_bin
        )
        _, _, V_u = lane_speed_field(
            reference, window, lane=lane, x_min=x_min, dx=dx, dt_bin=dt_bin
        )
        area = np.outer(np.diff(t_edges), np.diff(x_edges))
        both = np.isfinite(V) & np.isfinite(V_u)
        total += float(np.sum(np.maximum(0.0, V_u[both] - V[both]) * area[both]))
    return total
