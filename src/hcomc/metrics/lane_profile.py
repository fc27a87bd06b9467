r"""The lane profile of one logged row: the one implementation behind the lane speed fields
(:mod:`hcomc.metrics.speed_field`) and VR's undisturbed counterpart
(:mod:`hcomc.metrics.paper`, used by the disturbance metrics and LSRV).

Definition: in a logged row, lane ``lane``'s profile of a per-vehicle value (speed [m/s],
acceleration [m/s²]) at positions ``x`` [m] is :func:`numpy.interp` of ``x`` over the
*knots* of the lane, its active vehicles sorted by position (ties in vehicle order, NaN
positions last, as numpy sorts): NaN outside their range, or with ``clamp`` the nearest
vehicle's value; NaN everywhere if the lane is empty in that row.

The kernels visit the rows of a window in the log's stored cells (T, S) through the roster
of :func:`hcomc.sim.log.slots.active_columns` (the columns of each row's vehicles on the
road, in vehicle order), so they read only the cells on the road. Every caller goes through
:func:`lane_knots` and :func:`profile_from_knots`; :mod:`hcomc.metrics.logged_profile` reads
a log's rows for them.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray

__all__ = [
    "field_sums",
    "interp_ascending_into",
    "interp_into",
    "lane_knots",
    "lane_profile_of",
    "profile_from_knots",
    "profile_rows",
]

_SMALL_SORT = 40  # knots sorted by insertion up to this count (quadratic at worst), then merged


@kernel(inline="always")
def _before(a: float, b: float) -> bool:
    """Sort order of positions: numpy's (and numba's) ``a < b`` with NaN after numbers."""
    return a < b or (math.isnan(b) and not math.isnan(a))


@kernel
def lane_knots(
    candidates: np.ndarray, x_row: np.ndarray, lane_row: np.ndarray, lane: int,
    cols: np.ndarray, xs: np.ndarray,
) -> int:  # fmt: skip
    """The knots of lane ``lane`` in one row: ``m`` = their number, ``cols[:m]`` their
    columns, ``xs[:m]`` their positions [m] (float64), sorted stably by position.

    ``candidates`` are the columns of the row's active vehicles in vehicle order (a row of
    :func:`~hcomc.sim.log.slots.active_columns`); ``x_row`` and ``lane_row`` the row's
    stored positions and lanes. ``cols`` and ``xs`` need room for every candidate. The
    stable order makes ties come out in vehicle order, as :func:`numpy.argsort` with
    ``kind="stable"`` of the row's positions in vehicle order would.
    """
    m = 0
    # Vehicles enter upstream, so vehicle order runs mostly downstream to upstream: taken in
    # reverse, the knots arrive nearly sorted and the insertion sort below moves few of them.
    for e in range(candidates.size - 1, -1, -1):
        c = candidates[e]
        if lane_row[c] == lane:
            cols[m], xs[m] = c, x_row[c]
            m += 1
    if m <= _SMALL_SORT:
        # Insertion sort moving each knot before the equal ones: those were taken before it,
        # so they come later in vehicle order, and ties end in vehicle order.
        for i in range(1, m):
            key_x, key_c = xs[i], cols[i]
            j = i - 1
            while j >= 0 and not _before(xs[j], key_x):
                xs[j + 1], cols[j + 1] = xs[j], cols[j]
                j -= 1
            xs[j + 1], cols[j + 1] = key_x, key_c
    else:  # numba's stable mergesort of the knots in vehicle order: the same order
        xs[:m], cols[:m] = xs[:m][::-1].copy(), cols[:m][::-1].copy()
        order = np.argsort(xs[:m], kind="mergesort")
        xs[:m], cols[:m] = xs[:m][order], cols[:m][order]
    return m


@kernel
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


@kernel(inline="always")
def _slope(x0: float, x1: float, f0: float, f1: float) -> float:
    """Slope of the segment (x0, f0)-(x1, f1), as :func:`numpy.interp` computes it."""
    return (f1 - f0) / (x1 - x0)


@kernel(inline="always")
def _on_segment(xv: float, x0: float, x1: float, f0: float, f1: float, slope: float) -> float:
    """:func:`numpy.interp`'s value at ``xv`` on the segment (x0, f0)-(x1, f1) of slope
    ``slope``: from the left knot, and a NaN (an infinite slope) retried from the right one."""
    value = slope * (xv - x0) + f0
    if math.isnan(value):
        value = slope * (xv - x1) + f1
        if math.isnan(value) and f0 == f1:
            value = f0
    return value


@kernel
def interp_into(
    x: np.ndarray, xp: np.ndarray, fp: np.ndarray, left: float, right: float, out: np.ndarray
) -> None:
    """``out[:] = numpy.interp(x, xp, fp, left, right)``, value for value: numpy's
    arithmetic and special cases (an exact knot or the last one gives its ``fp``; a NaN from
    an infinite slope is retried from the right knot; one knot has its own rule) for
    ascending ``xp`` (one knot at least, ties allowed)."""
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
            else:
                slope = _slope(xp[j], xp[j + 1], fp[j], fp[j + 1])
                out[i] = _on_segment(xv, xp[j], xp[j + 1], fp[j], fp[j + 1], slope)


@kernel
def interp_ascending_into(
    x: np.ndarray, xp: np.ndarray, fp: np.ndarray, left: float, right: float, out: np.ndarray
) -> None:
    """:func:`interp_into` for ascending queries ``x`` without NaN (the bin centres of a
    speed field): the same values, found segment by segment instead of by bisection, with
    each segment's slope computed once."""
    n, n_x = xp.size, x.size
    if n == 1 or math.isnan(xp[n - 1]):  # numpy's special cases: the general loop
        interp_into(x, xp, fp, left, right, out)
        return
    i = 0
    while i < n_x and x[i] < xp[0]:
        out[i] = left
        i += 1
    for j in range(n - 1):  # queries in [xp[j], xp[j + 1]): segment j (ties: none)
        x0, x1, f0, f1 = xp[j], xp[j + 1], fp[j], fp[j + 1]
        if i == n_x or x[i] >= x1:
            continue
        slope = _slope(x0, x1, f0, f1)
        while i < n_x and x[i] < x1:
            xv = x[i]
            out[i] = f0 if xv == x0 else _on_segment(xv, x0, x1, f0, f1, slope)
            i += 1
    while i < n_x:  # the last knot itself, then beyond
        out[i] = fp[n - 1] if x[i] == xp[n - 1] else right
        i += 1


@kernel
def profile_from_knots(
    m: int, cols: np.ndarray, xs: np.ndarray, value_row: np.ndarray, x: np.ndarray,
    clamp: bool, ascending: bool, ys: np.ndarray, out: np.ndarray,
) -> None:  # fmt: skip
    """The lane profile of ``value_row`` (the row's stored values) at ``x`` into ``out``,
    from the ``m`` knots of :func:`lane_knots`; ``ascending``: ``x`` is ascending without
    NaN (:func:`interp_ascending_into`); ``ys`` is scratch of at least ``m``."""
    if m == 0:
        out[:] = math.nan
        return
    for q in range(m):
        ys[q] = value_row[cols[q]]
    left, right = (ys[0], ys[m - 1]) if clamp else (math.nan, math.nan)
    if ascending:
        interp_ascending_into(x, xs[:m], ys[:m], left, right, out)
    else:
        interp_into(x, xs[:m], ys[:m], left, right, out)


@kernel
def profile_rows(
    x_store: np.ndarray, lane_store: np.ndarray, values: tuple[np.ndarray, ...],
    start: np.ndarray, column: np.ndarray, r0: int, rows: np.ndarray, lanes: np.ndarray,
    x: np.ndarray, clamp: bool, out: np.ndarray,
) -> None:  # fmt: skip
    """Row by row, the profile of lane ``lanes[k]`` at positions ``x[k]`` in row ``rows[k]``.

    ``x_store``, ``lane_store`` and each of ``values`` (stored arrays (T, S) of one dtype)
    are read through the roster ``start, column`` of
    :func:`~hcomc.sim.log.slots.active_columns` over rows ``[r0, r0 + start.size - 1)``,
    which hold ``rows`` (R,). ``lanes`` (R,) is the lane to profile per row, negative for
    none (NaN); ``x`` (R, Q) the positions [m]; ``out`` (len(values), R, Q) receives the
    profile of ``values[p]`` in ``out[p]``.
    """
    width = 0
    for k in range(start.size - 1):
        width = max(width, start[k + 1] - start[k])
    cols = np.empty(width, dtype=np.int64)
    xs, ys = np.empty(width), np.empty(width)
    for k in range(rows.size):
        if lanes[k] < 0:
            out[:, k, :] = math.nan
            continue
        r = rows[k]
        candidates = column[start[r - r0] : start[r - r0 + 1]]
        m = lane_knots(candidates, x_store[r], lane_store[r], lanes[k], cols, xs)
        for p in range(len(values)):
            profile_from_knots(m, cols, xs, values[p][r], x[k], clamp, False, ys, out[p, k])


def lane_profile_of(
    x_row: np.ndarray, active_row: np.ndarray, lane_row: np.ndarray, lane: int, x: FloatArray,
    clamp: bool, *value_rows: np.ndarray,
) -> list[FloatArray]:  # fmt: skip
    """:func:`~hcomc.metrics.logged_profile.lane_profile_at` on one row's arrays (N,) (e.g.
    ``log.x[row]``, ``log.active[row]``, ``log.lane[row]``): each of ``value_rows`` (e.g.
    ``log.v[row]``) interpolated at ``x`` [m] between the active vehicles of ``lane``
    (sorted by position, ties in vehicle order), as :func:`numpy.interp` does."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    x_row, lane_row = np.asarray(x_row)[None, :], np.asarray(lane_row)[None, :]
    column = np.flatnonzero(np.asarray(active_row, dtype=bool)).astype(np.int64)
    start = np.array([0, column.size], dtype=np.int64)
    lanes = np.array([lane], dtype=np.int64)
    out = []
    for values in value_rows:
        profile = np.empty((1, 1, x.size))
        profile_rows(x_row, lane_row, (np.asarray(values)[None, :],), start, column, 0,
                     np.zeros(1, dtype=np.int64), lanes, x.reshape(1, -1), bool(clamp),
                     profile)  # fmt: skip
        out.append(profile[0, 0].reshape(x.shape))
    return out


@kernel
def field_sums(
    x_store: np.ndarray, lane_store: np.ndarray, v_store: np.ndarray, start: np.ndarray,
    column: np.ndarray, r0: int, lanes: np.ndarray, centres: np.ndarray, it: np.ndarray,
    sums: np.ndarray, counts: np.ndarray,
) -> None:  # fmt: skip
    """Add each row's profile of lane ``lanes[q]`` at ``centres`` (its finite samples) to the
    row's time bin ``it[k]`` of ``sums[q]`` and ``counts[q]`` (each (n_t, n_x)); row
    ``r0 + k`` of the stored arrays is read through the roster ``start, column``
    (:func:`~hcomc.sim.log.slots.active_columns`)."""
    width = 0
    for k in range(it.size):
        width = max(width, start[k + 1] - start[k])
    cols = np.empty(width, dtype=np.int64)
    xs, ys = np.empty(width), np.empty(width)
    v = np.empty(centres.size)
    for k in range(it.size):
        r = r0 + k
        candidates = column[start[k] : start[k + 1]]
        for q in range(lanes.size):
            m = lane_knots(candidates, x_store[r], lane_store[r], lanes[q], cols, xs)
            if m == 0:
                continue  # an empty lane samples nothing
            profile_from_knots(m, cols, xs, v_store[r], centres, False, True, ys, v)
            lane_sums, lane_counts = sums[q, it[k]], counts[q, it[k]]
            for b in range(centres.size):
                # Adding 0 for a sample that is not finite changes no sum (they start at +0
                # and never become -0) and leaves the loop without a branch.
                finite = np.isfinite(v[b])
                lane_sums[b] += v[b] if finite else 0.0
                lane_counts[b] += 1.0 if finite else 0.0
