r"""The paper's merge metrics (Tables II-III): critical distance, average acceleration,
stabilisation time and fuel.

The paper names these metrics but does not define them precisely. Average acceleration and
stabilisation time measure the **disturbance caused by the merge**: each key vehicle is
compared with its own undisturbed counterpart, the same vehicle in the same run without the
merge (the ``reference`` log, see :mod:`hcomc.metrics.window`). Without that comparison a
vehicle that simply accelerates towards its desired speed would count as disturbed.

**VR's counterpart.** VR does not exist in the undisturbed run. It enters these two metrics
from its merge completion ``t_merge`` on (before that it drives on the ramp and acceleration
lane, which is its own approach, not a disturbance of the traffic), and its undisturbed
speed and acceleration are those of the undisturbed traffic of its current lane at its
position: the linear interpolation, in x, between the reference run's vehicles of that lane
around VR (the nearest one beyond the ends; see
:func:`hcomc.metrics.lane_profile.lane_profile_at`).

A **deviation cell** (row, key vehicle) is *valid* if the row lies in the window, the vehicle
is active in the factual run and its counterpart exists (another key vehicle: active in the
reference in that row; VR: ``t >= t_merge`` and its logged lane is 1 or 2 with at least one
reference vehicle in it). Its deviations are ``da = a - a_u`` [m/s²] and ``dv = v - v_u``
[m/s].
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray
from hcomc.metrics.lane_profile import profile_along
from hcomc.metrics.window import (
    A_TOL,
    EPS_T,
    HOLD,
    V_TOL,
    MetricWindow,
    check_reference,
    key_pairs,
    post_merge_rows,
    times,
    window_rows,
)
from hcomc.models.fuel import FUEL_DEFAULT, FuelParams, fuel_consumed, fuel_rate_scalar
from hcomc.sim.log import SimulationLog

__all__ = [
    "average_acceleration",
    "critical_distance",
    "deviations",
    "fuel",
    "stabilisation_time",
]


def critical_distance(log: SimulationLog, window: MetricWindow) -> float:
    """Critical distance [m] (paper "Crit. Dist."; larger is better).

    Definition: the minimum bumper gap ``x_l - L_l - x_f`` over all consecutive same-lane
    pairs of present, active key vehicles (consecutive in x among key vehicles only, same
    logged lane) and all logged rows with ``max(t_merge, t_start) <= t <= t_end``.

    Returns
    -------
    float
        Critical distance [m]; NaN if VR did not merge or no two key vehicles share a
        lane in those rows.
    """
    if not window.merged:
        return math.nan
    gap, _, valid = key_pairs(log, window, post_merge_rows(log, window))
    return float(gap[valid].min()) if valid.any() else math.nan


def deviations(
    log: SimulationLog, window: MetricWindow, reference: SimulationLog, rows: slice
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """``(da, dv, valid)`` of the present key vehicles over ``rows``, each shaped (R, K).

    Columns follow ``window.key_vehicles``; see the module docstring for validity.
    """
    check_reference(log, reference)
    keys = window.key_vehicles
    a = log.a[rows, keys].astype(np.float64)
    v = log.v[rows, keys].astype(np.float64)
    a_u = reference.a[rows, keys].astype(np.float64)
    v_u = reference.v[rows, keys].astype(np.float64)
    valid = log.active[rows, keys] & reference.active[rows, keys]
    vr = window.vr
    if vr >= 0 and vr in keys:
        col = int(np.searchsorted(keys, vr))
        valid[:, col] = False
        t = times(log)[rows]
        after = log.active[rows, vr] & (t >= window.t_merge - EPS_T)  # NaN t_merge: never
        lanes = log.lane[rows, vr].astype(np.int64)
        lanes[~(after & ((lanes == 1) | (lanes == 2)))] = -1  # no counterpart: not profiled
        at = log.x[rows, vr].reshape(-1, 1)
        v_lane, a_lane = profile_along(
            reference, np.arange(log.n_steps)[rows], lanes, at, "v", "a", clamp=True
        )[:, :, 0]
        found = np.isfinite(v_lane)
        v_u[found, col], a_u[found, col] = v_lane[found], a_lane[found]
        valid[found, col] = True
    with np.errstate(invalid="ignore"):
        return a - a_u, v - v_u, valid & np.isfinite(a - a_u) & np.isfinite(v - v_u)


def average_acceleration(
    log: SimulationLog, window: MetricWindow, *, reference: SimulationLog | None = None
) -> float:
    """Average acceleration disturbance of the key vehicles [m/s²] (paper "Aver. Acc.").

    Definition: the mean of ``abs(a - a_u)`` over all valid deviation cells of the window
    rows ``[t_start, t_end]`` (pooled over vehicles and rows, every cell weighted equally).

    Returns
    -------
    float
        Mean ``abs(a - a_u)`` [m/s²]. 0 if the run has no ramp vehicle (empty group:
        nothing merges, nothing is disturbed). NaN without a reference, or if no cell is
        valid.
    """
    if not window.group:
        return 0.0
    if reference is None:
        return math.nan
    da, _, valid = deviations(log, window, reference, window_rows(log, window))
    return _mean_abs(da, valid)


def _mean_abs(da: FloatArray, valid: np.ndarray) -> float:
    """Mean ``abs(da)`` of the valid cells [m/s²], NaN without one."""
    return float(np.abs(da[valid]).mean()) if valid.any() else math.nan


def stabilisation_time(
    log: SimulationLog,
    window: MetricWindow,
    *,
    reference: SimulationLog | None = None,
    a_tol: float = A_TOL,
    v_tol: float = V_TOL,
    hold: float = HOLD,
) -> float:
    """Time the key vehicles need to return to their undisturbed motion [s] (paper "Stab.
    Time"; smaller is better).

    Definition: a logged row is *settled* if every valid deviation cell in it has
    ``abs(a - a_u) < a_tol`` (0.05 m/s²) and ``abs(v - v_u) < v_tol`` (0.5 m/s); rows without
    a valid cell are settled. The result is ``t_s - t_merge`` for the earliest row time
    ``t_s >= max(t_merge, t_start)`` such that every logged row with
    ``t_s <= t <= t_s + hold`` (hold = 2 s) is settled and ``t_s + hold <= t_end``. Since
    rows are discrete, a merge between rows adds up to one logging interval.

    Returns
    -------
    float
        Stabilisation time [s]. 0 if the run has no ramp vehicle (empty group). **Censored**:
        if no hold interval fits before ``t_end``, ``t_end - t_merge`` (a lower bound). NaN
        without a reference, if VR did not merge, or merged after the last logged row.
    """
    if not window.group:
        return 0.0
    if reference is None or not window.merged:
        return math.nan
    rows = post_merge_rows(log, window)
    if rows.stop <= rows.start:
        return math.nan
    da, dv, valid = deviations(log, window, reference, rows)
    return _settling_time(times(log)[rows], da, dv, valid, window, a_tol, v_tol, hold)


def _settling_time(
    t: FloatArray, da: FloatArray, dv: FloatArray, valid: np.ndarray, window: MetricWindow,
    a_tol: float, v_tol: float, hold: float,
) -> float:  # fmt: skip
    """:func:`stabilisation_time` from the deviation cells of the post-merge rows (times
    ``t`` [s])."""
    with np.errstate(invalid="ignore"):
        ok_cell = (np.abs(da) < a_tol) & (np.abs(dv) < v_tol)
    settled = np.all(~valid | ok_cell, axis=1)
    # rows r .. end[r] - 1 cover [t_r, t_r + hold]; all settled <=> count == length.
    end = np.searchsorted(t, t + hold + EPS_T, side="right")
    csum = np.concatenate(([0], np.cumsum(settled, dtype=np.int64)))
    start = np.arange(t.size)
    fits = t + hold <= window.t_end + EPS_T
    good = fits & settled & (csum[end] - csum[start] == end - start)
    if good.any():
        return float(t[int(np.argmax(good))] - window.t_merge)
    return float(window.t_end - window.t_merge)


def disturbance_metrics(
    log: SimulationLog, window: MetricWindow, reference: SimulationLog | None
) -> dict[Callable[..., float], float]:
    """:func:`average_acceleration` and :func:`stabilisation_time` (default tolerances),
    keyed by function: the values they return, from one table of deviation cells.

    The post-merge rows stabilisation time reads are the tail of the window rows average
    acceleration reads, and a row's cells depend on that row alone, so the table of the
    window rows serves both.
    """
    if not window.group or reference is None:  # no cell is read
        return {
            average_acceleration: average_acceleration(log, window, reference=reference),
            stabilisation_time: stabilisation_time(log, window, reference=reference),
        }
    rows, post = window_rows(log, window), post_merge_rows(log, window)
    da, dv, valid = deviations(log, window, reference, rows)
    settling = math.nan  # VR did not merge, or after the last logged row
    if window.merged and post.stop > post.start:
        tail = slice(post.start - rows.start, post.stop - rows.start)
        settling = _settling_time(times(log)[post], da[tail], dv[tail], valid[tail], window,
                                  A_TOL, V_TOL, HOLD)  # fmt: skip
    return {average_acceleration: _mean_abs(da, valid), stabilisation_time: settling}


def fuel(log: SimulationLog, window: MetricWindow, *, params: FuelParams = FUEL_DEFAULT) -> float:
    """Total fuel consumption of all vehicles in the window [L] (paper "Fuel Cons.").

    Definition: paper Eq. (16) (:func:`hcomc.models.fuel.fuel_consumed`, summing
    :func:`~hcomc.models.fuel.fuel_rate_scalar`) over every vehicle slot and the window rows,
    rectangle rule with the logging interval:
    ``F = log.dt / 1000 * Σ_rows Σ_vehicles fdot(v, a)``; inactive cells count as 0.

    Returns
    -------
    float
        Fuel [L].
    """
    rows = window_rows(log, window)
    if log.n_vehicles == 1:  # numpy sums a lone column pairwise, not row after row
        per_vehicle = fuel_consumed(log.v[rows], log.a[rows], log.dt, params, axis=0)
        return float(np.sum(per_vehicle))
    cells = log.cells
    sums = _rate_sums(cells["v"], cells["a"], log.slot, log.span, rows.start, rows.stop,
                      *params.coefficients())  # fmt: skip
    return float(np.sum(sums * (log.dt / 1000.0)))


@kernel
def _rate_sums(
    v: np.ndarray, a: np.ndarray, slot: np.ndarray, span: np.ndarray, r0: int, r1: int,
    b0: float, b1: float, b2: float, b3: float, c0: float, c1: float, c2: float,
    positive_only: float,
) -> FloatArray:  # fmt: skip
    """(N,) each vehicle's Eq. (16) rate [mL/s] summed over rows ``[r0, r1)`` of the stored
    cells ``v``, ``a`` (T, S), row after row, NaN rates (cells not logged) as 0: the column
    sums of ``numpy.nansum(fuel_rate(log.v[rows], log.a[rows]), axis=0)``, which numpy adds
    row after row for two columns or more."""
    sums = np.zeros(slot.size)
    for i in range(slot.size):
        s = slot[i]
        if s < 0:
            continue
        total = 0.0
        for k in range(max(r0, span[i, 0]), min(r1, span[i, 1])):
            rate = fuel_rate_scalar(np.float64(v[k, s]), np.float64(a[k, s]), b0, b1, b2, b3,
                                    c0, c1, c2, positive_only)  # fmt: skip
            if not math.isnan(rate):
                total += rate
        sums[i] = total
    return sums
