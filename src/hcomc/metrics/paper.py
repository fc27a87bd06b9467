r"""The paper's merge metrics (Tables II-III): critical distance, average acceleration and
stabilisation time (fuel: :mod:`hcomc.metrics.fuel_distance`; LSRV: :mod:`hcomc.metrics.lsrv`),
with the labelled variant stabilisation time from the merge and the integrated disturbance
(Eq. 15's safety index at the merge: :mod:`hcomc.metrics.merge_safety`).

The paper names these metrics but does not define them precisely. Average acceleration,
stabilisation time and integrated disturbance measure the **disturbance caused by the
merge**: each key vehicle is compared with its own undisturbed counterpart, the same vehicle
in the same run without the merge (the ``reference`` log, see :mod:`hcomc.metrics.window`).
Without that comparison a vehicle that simply accelerates towards its desired speed would
count as disturbed.

**A common clock.** The headline stabilisation time is measured from VR's entry into the
control zone, the same instant for every controller on a seed. Measured from VR's merge
(:func:`stabilisation_time_from_merge`, a labelled variant) it rewards merging late: the
traffic's recovery takes about as long after any merge, so the time from the merge is
roughly a constant minus the merge time. :func:`integrated_disturbance` needs no clock.

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
for it, whereas a run without a ramp vehicle at all (empty group) scores 0 on the
disturbance metrics.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from hcomc._typing import FloatArray
from hcomc.metrics.leaders import lane_leaders
from hcomc.metrics.logged_profile import profile_along
from hcomc.metrics.window import (
    A_TOL,
    EPS_T,
    HOLD,
    V_TOL,
    MetricWindow,
    check_reference,
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
    "integrated_disturbance",
    "stabilisation_time",
    "stabilisation_time_from_merge",
    "vr_counterpart",
]


def critical_distance(log: SimulationLog, window: MetricWindow) -> float:
    """Critical distance [m] (paper "Crit. Dist."; larger is better).

    Definition: the minimum, over the present key vehicles and the logged rows with
    ``max(t_merge, t_start) <= t <= t_end``, of a key vehicle's bumper gap
    ``x_l - L_l - x_f`` to its *actual leader*: the nearest vehicle ahead of it in its
    logged lane, any vehicle on the road, key or not
    (:func:`hcomc.metrics.leaders.lane_leaders`). A non-key vehicle between two key
    vehicles is the follower's leader; rows in which a key vehicle has nobody ahead in its
    lane add nothing for it.

    Returns
    -------
    float
        Critical distance [m] (negative if two vehicles overlap); NaN if VR did not merge,
        or no key vehicle has a leader in those rows.
    """
    if not window.merged:
        return math.nan
    _, gap = lane_leaders(log, post_merge_rows(log, window), window.key_vehicles)
    found = np.isfinite(gap)
    return float(gap[found].min()) if found.any() else math.nan


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
    """Time from VR's entry into the control zone until the key vehicles are back to their
    undisturbed motion for good [s] (paper "Stab. Time"; smaller is better).

    The clock starts at ``t_start``, the same instant for every controller on a seed, so a
    late merge is not rewarded (:func:`stabilisation_time_from_merge` is).

    Definition (final settling): a logged row is *unsettled* if a valid deviation cell in it
    has ``abs(a - a_u) >= a_tol`` (0.05 m/s²) or ``abs(v - v_u) >= v_tol`` (0.5 m/s); rows
    without a valid cell are settled. Over all window rows ``[t_start, t_end]`` (the key
    vehicles other than VR are compared with their undisturbed selves before the merge too,
    VR from its merge on, so braking to open a gap before the merge counts), ``t_s`` is the
    time of the first row after the last unsettled one (``t_start`` if no row is unsettled),
    and the result is ``max(0, t_s - t_start)``: every disturbance counts, however long the
    quiet spell before it.

    Returns
    -------
    float
        Stabilisation time from control-zone entry [s]. 0 if the run has no ramp vehicle
        (empty group). **Censored**: if the settled tail ``[t_s, t_end]`` is shorter than
        ``hold`` (2 s), or the last row is unsettled, ``t_end - t_start`` (a lower bound).
        NaN without a reference or if VR did not merge.
    """
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):
        return ref
    rows = window_rows(log, window)
    unsettled = _unsettled(*deviations(log, window, ref, rows), a_tol, v_tol)
    return final_settling(times(log)[rows], unsettled, window.t_start, window.t_end, hold)


def stabilisation_time_from_merge(
    log: SimulationLog,
    window: MetricWindow,
    *,
    reference: SimulationLog | None = None,
    a_tol: float = A_TOL,
    v_tol: float = V_TOL,
    hold: float = HOLD,
) -> float:
    """Time from VR's merge until the key vehicles are back to their undisturbed motion for
    good [s] (a labelled variant; smaller is better, but it **favours late merges**: the
    traffic recovers about as long after any merge, so this is roughly a constant minus the
    merge time; compare controllers with :func:`stabilisation_time`).

    Definition (final settling, as :func:`stabilisation_time`, on another clock): a logged
    row is *unsettled* if a valid deviation cell in it has ``abs(a - a_u) >= a_tol``
    (0.05 m/s²) or ``abs(v - v_u) >= v_tol`` (0.5 m/s); rows without a valid cell are
    settled. Over the rows ``max(t_merge, t_start) <= t <= t_end`` only (a disturbance
    before the merge does not count), ``t_s`` is the time of the first row after the last
    unsettled one (``t_merge`` if no row is unsettled), and the result is
    ``max(0, t_s - t_merge)``. A merge between two rows adds up to one logging interval.

    Returns
    -------
    float
        Stabilisation time from the merge [s]. 0 if the run has no ramp vehicle (empty
        group). **Censored**: if the settled tail ``[t_s, t_end]`` is shorter than ``hold``
        (2 s), or the last row is unsettled, ``t_end - t_merge`` (a lower bound). NaN
        without a reference, if VR did not merge, or merged after the last logged row.
    """
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):
        return ref
    rows = post_merge_rows(log, window)
    if rows.stop <= rows.start:
        return math.nan
    unsettled = _unsettled(*deviations(log, window, ref, rows), a_tol, v_tol)
    return final_settling(times(log)[rows], unsettled, window.t_merge, window.t_end, hold)


def integrated_disturbance(
    log: SimulationLog, window: MetricWindow, *, reference: SimulationLog | None = None
) -> float:
    """The key vehicles' speed deviation from their undisturbed selves, integrated over the
    window [m] (smaller is better).

    Definition: ``sum abs(v - v_u) * dt`` over all valid deviation cells of the window rows
    ``[t_start, t_end]`` (module docstring: VR from its merge on, against the undisturbed
    traffic of its lane at its position), with ``dt = log.dt`` (rectangle rule, each logged
    row standing for one logging interval). Summed over vehicles, so the distance the key
    vehicles as a group lose (or gain) on their undisturbed selves, counted in both
    directions. It needs no clock: a late merge is not rewarded, and a disturbance counts by
    its size and duration, not by when it ends.

    Returns
    -------
    float
        Integrated disturbance [m]. 0 if the run has no ramp vehicle (empty group) or no
        cell is valid. NaN without a reference or if VR never merged.
    """
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):
        return ref
    _, dv, valid = deviations(log, window, ref, window_rows(log, window))
    return _integral_abs(dv, valid, log.dt)


def _integral_abs(dv: FloatArray, valid: np.ndarray, dt: float) -> float:
    """``sum abs(dv) dt`` over the valid cells [m]."""
    return float(np.abs(dv[valid]).sum() * dt)


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
    """:func:`average_acceleration`, :func:`stabilisation_time`,
    :func:`stabilisation_time_from_merge` and :func:`integrated_disturbance` (default
    tolerances), keyed by function: the values they return, from one table of deviation
    cells.

    The post-merge rows the stabilisation time from the merge reads are the tail of the
    window rows the others read, and a row's cells depend on that row alone, so the table of
    the window rows serves all four.
    """
    funcs = (average_acceleration, stabilisation_time, stabilisation_time_from_merge,
             integrated_disturbance)  # fmt: skip
    ref = reference_or_score(log, window, reference)
    if isinstance(ref, float):  # no cell is read
        return dict.fromkeys(funcs, ref)
    rows, post = window_rows(log, window), post_merge_rows(log, window)
    da, dv, valid = deviations(log, window, ref, rows)
    unsettled = _unsettled(da, dv, valid, A_TOL, V_TOL)
    t = times(log)
    from_merge = math.nan  # VR merged after the last logged row
    if post.stop > post.start:
        tail = unsettled[post.start - rows.start : post.stop - rows.start]
        from_merge = final_settling(t[post], tail, window.t_merge, window.t_end, HOLD)
    entry = final_settling(t[rows], unsettled, window.t_start, window.t_end, HOLD)
    return {average_acceleration: _mean_abs(da, valid), stabilisation_time: entry,
            stabilisation_time_from_merge: from_merge,
            integrated_disturbance: _integral_abs(dv, valid, log.dt)}  # fmt: skip
