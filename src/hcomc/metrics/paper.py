r"""The paper's merge metrics (Tables II-III): critical distance, average acceleration and
stabilisation time (fuel: :mod:`hcomc.metrics.fuel_distance`; LSRV: :mod:`hcomc.metrics.lsrv`).

The paper names these metrics but does not define them precisely. Average acceleration and
stabilisation time measure the **disturbance caused by the merge**: each key vehicle is
compared with its own undisturbed counterpart, the same vehicle in the same run without the
merge (the ``reference`` log, see :mod:`hcomc.metrics.window`). Without that comparison a
vehicle that simply accelerates towards its desired speed would count as disturbed.

**VR's counterpart.** VR does not exist in the undisturbed run. It enters these metrics
from its merge completion ``t_merge`` on (before that it drives on the ramp and acceleration
lane, which is its own approach, not a disturbance of the traffic), and its undisturbed
speed and acceleration are those of the undisturbed traffic of its current lane at its
position: the linear interpolation, in x, between the reference run's vehicles of that lane
around VR (the nearest one beyond the ends; see
:func:`hcomc.metrics.logged_profile.lane_profile_at`).

A **deviation cell** (row, key vehicle) is *valid* if the row lies in the window, the vehicle
is active in the factual run and its counterpart exists (another key vehicle: active in the
reference in that row; VR: ``t >= t_merge`` and its logged lane is 1 or 2 with at least one
reference vehicle in it). Its deviations are ``da = a - a_u`` [m/s²] and ``dv = v - v_u``
[m/s].

**No merge.** A run whose ramp vehicle never merged is an outcome
(:func:`hcomc.metrics.outcome.merge_outcome`), not an undisturbed run: these metrics are NaN
for it, whereas a run without a ramp vehicle at all (empty group) scores 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from hcomc._typing import FloatArray
from hcomc.metrics.logged_profile import profile_along
from hcomc.metrics.window import (
    A_TOL,
    EPS_T,
    HOLD,
    V_TOL,
    MetricWindow,
    check_reference,
    key_pairs,
    post_merge_rows,
    reference_or_score,
    times,
    window_rows,
)
from hcomc.sim.log import SimulationLog

__all__ = [
    "average_acceleration",
    "critical_distance",
    "deviations",
    "disturbance_metrics",
    "final_settling",
    "stabilisation_time",
    "stabilisation_time_entry",
    "vr_counterpart",
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
        v_lane, a_lane = vr_counterpart(log, window, reference, rows, "v", "a")
        found = np.isfinite(v_lane)
        valid[:, col] = found
        v_u[found, col], a_u[found, col] = v_lane[found], a_lane[found]
    with np.errstate(invalid="ignore"):
        return a - a_u, v - v_u, valid & np.isfinite(a - a_u) & np.isfinite(v - v_u)


def vr_counterpart(
    log: SimulationLog, window: MetricWindow, reference: SimulationLog, rows: slice,
    *names: str,
) -> FloatArray:  # fmt: skip
    """VR's undisturbed values ``names`` (e.g. ``"v"``, ``"a"``) over ``rows``:
    (len(names), R), NaN where it has no counterpart (before ``t_merge``, inactive, off
    lanes 1 and 2, or an empty lane in the reference); see the module docstring."""
    vr = window.vr
    t = times(log)[rows]
    after = log.active[rows, vr] & (t >= window.t_merge - EPS_T)  # NaN t_merge: never
    lanes = log.lane[rows, vr].astype(np.int64)
    lanes[~(after & ((lanes == 1) | (lanes == 2)))] = -1  # no counterpart: not profiled
    at = log.x[rows, vr].reshape(-1, 1)
    rows_idx = np.arange(log.n_steps)[rows]
    return profile_along(reference, rows_idx, lanes, at, *names, clamp=True)[:, :, 0]


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
        nothing merges, nothing is disturbed). NaN without a reference, if VR never merged,
        or if no cell is valid.
    """
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):
        return ref
    da, _, valid = deviations(log, window, ref, window_rows(log, window))
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
    """Time from the merge until the key vehicles are back to their undisturbed motion for
    good [s] (paper "Stab. Time"; smaller is better).

    Definition (final settling): a logged row is *unsettled* if a valid deviation cell in it
    has ``abs(a - a_u) >= a_tol`` (0.05 m/s²) or ``abs(v - v_u) >= v_tol`` (0.5 m/s); rows
    without a valid cell are settled. Over the rows ``max(t_merge, t_start) <= t <= t_end``,
    ``t_s`` is the time of the first row after the last unsettled one (``t_merge`` if no
    row is unsettled), and the result is ``max(0, t_s - t_merge)``: every disturbance after
    the merge counts, however long the quiet spell before it. A merge between two rows
    adds up to one logging interval.

    Returns
    -------
    float
        Stabilisation time [s]. 0 if the run has no ramp vehicle (empty group).
        **Censored**: if the settled tail ``[t_s, t_end]`` is shorter than ``hold`` (2 s),
        or the last row is unsettled, ``t_end - t_merge`` (a lower bound). NaN without a
        reference, if VR did not merge, or merged after the last logged row.
    """
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):
        return ref
    rows = post_merge_rows(log, window)
    if rows.stop <= rows.start:
        return math.nan
    unsettled = _unsettled(*deviations(log, window, ref, rows), a_tol, v_tol)
    return final_settling(times(log)[rows], unsettled, window.t_merge, window.t_end, hold)


def stabilisation_time_entry(
    log: SimulationLog,
    window: MetricWindow,
    *,
    reference: SimulationLog | None = None,
    a_tol: float = A_TOL,
    v_tol: float = V_TOL,
    hold: float = HOLD,
) -> float:
    """Time from VR's entry into the control zone until the key vehicles are back to their
    undisturbed motion for good [s] (smaller is better).

    Definition: :func:`stabilisation_time` over all window rows ``[t_start, t_end]``,
    measured from ``t_start``: the key vehicles other than VR are compared with their
    undisturbed selves before the merge too (VR from its merge on), so braking to open a gap
    before the merge counts. ``max(0, t_s - t_start)``, censored at ``t_end - t_start``.

    Returns
    -------
    float
        Stabilisation time from control-zone entry [s]; 0 without a ramp vehicle; NaN
        without a reference or if VR did not merge.
    """
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):
        return ref
    rows = window_rows(log, window)
    unsettled = _unsettled(*deviations(log, window, ref, rows), a_tol, v_tol)
    return final_settling(times(log)[rows], unsettled, window.t_start, window.t_end, hold)


def _unsettled(
    da: FloatArray, dv: FloatArray, valid: np.ndarray, a_tol: float, v_tol: float
) -> np.ndarray:
    """(R,) rows with a valid deviation cell outside the tolerances."""
    with np.errstate(invalid="ignore"):
        ok_cell = (np.abs(da) < a_tol) & (np.abs(dv) < v_tol)
    return np.any(valid & ~ok_cell, axis=1)


def final_settling(
    t: FloatArray, unsettled: np.ndarray, t0: float, t_end: float, hold: float
) -> float:
    """Final settling time after ``t0`` [s] from rows at times ``t`` (ascending) and their
    ``unsettled`` flags: ``max(0, t_s - t0)`` with ``t_s`` the time of the first row after
    the last unsettled one (``t0`` if none is), censored at ``t_end - t0`` when the last row
    is unsettled or ``t_s + hold > t_end``."""
    late = np.flatnonzero(unsettled)
    if late.size == 0:
        t_s = t0
    elif late[-1] + 1 < t.size:
        t_s = float(t[late[-1] + 1])
    else:
        return float(t_end - t0)
    if t_s + hold > t_end + EPS_T:
        return float(t_end - t0)
    return max(0.0, float(t_s - t0))


def disturbance_metrics(
    log: SimulationLog, window: MetricWindow, reference: SimulationLog | None
) -> dict[Callable[..., float], float]:
    """:func:`average_acceleration`, :func:`stabilisation_time` and
    :func:`stabilisation_time_entry` (default tolerances), keyed by function: the values
    they return, from one table of deviation cells.

    The post-merge rows stabilisation time reads are the tail of the window rows the other
    two read, and a row's cells depend on that row alone, so the table of the window rows
    serves all three.
    """
    funcs = (average_acceleration, stabilisation_time, stabilisation_time_entry)
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):  # no cell is read
        return dict.fromkeys(funcs, ref)
    rows, post = window_rows(log, window), post_merge_rows(log, window)
    da, dv, valid = deviations(log, window, ref, rows)
    unsettled = _unsettled(da, dv, valid, A_TOL, V_TOL)
    t = times(log)
    settling = math.nan  # VR merged after the last logged row
    if post.stop > post.start:
        tail = unsettled[post.start - rows.start : post.stop - rows.start]
        settling = final_settling(t[post], tail, window.t_merge, window.t_end, HOLD)
    entry = final_settling(t[rows], unsettled, window.t_start, window.t_end, HOLD)
    return {average_acceleration: _mean_abs(da, valid), stabilisation_time: settling,
            stabilisation_time_entry: entry}  # fmt: skip
