"""Surrogate safety measures of the merge: TTC, DRAC, PET and collisions.

Pairs are the consecutive same-lane key-vehicle pairs of :mod:`hcomc.metrics.window`
(fixed key vehicles, logged lane, bumper gap); rows are those of the evaluation window.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from hcomc._typing import FloatArray
from hcomc.metrics.window import EPS_T, MetricWindow, key_pairs, times, window_rows
from hcomc.safety.surrogate import CLOSING_SPEED
from hcomc.sim.log import EventKind, SimulationLog

__all__ = [
    "CLOSING_SPEED",
    "collisions",
    "key_collisions",
    "max_drac",
    "min_ttc",
    "pet_at_merge",
]


def _first_crossing(t: FloatArray, pos: FloatArray, target: float) -> float:
    """First time ``pos`` reaches ``target`` (linear interpolation between rows), NaN if never.

    ``pos`` may hold NaN (inactive rows), which never count as reaching the target.
    """
    with np.errstate(invalid="ignore"):
        reached = pos >= target
    if not reached.any():
        return math.nan
    k = int(np.argmax(reached))
    if k == 0 or not np.isfinite(pos[k - 1]):
        return float(t[k])
    p0, p1 = float(pos[k - 1]), float(pos[k])
    return float(t[k - 1] + (target - p0) / (p1 - p0) * (t[k] - t[k - 1]))


def min_ttc(
    log: SimulationLog, window: MetricWindow, *, closing_speed: float = CLOSING_SPEED
) -> float:
    """Minimum time-to-collision among the key vehicles [s] (larger is better).

    Definition: over all rows in ``[t_start, t_end]`` and all consecutive same-lane
    key-vehicle pairs (as in :func:`critical_distance`) with closing speed
    ``v_f - v_l > closing_speed``, the minimum of ``max(gap, 0) / (v_f - v_l)``
    (an overlapping closing pair has TTC 0).

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.
    closing_speed : float
        Minimum closing speed [m/s], default 0.1.

    Returns
    -------
    float
        Minimum TTC [s]; ``inf`` if no pair ever closes.
    """
    return _min_ttc(*key_pairs(log, window, window_rows(log, window)), closing_speed)


def _min_ttc(
    gap: FloatArray, closing: FloatArray, valid: np.ndarray, closing_speed: float
) -> float:
    """:func:`min_ttc` of the pairs of :func:`~hcomc.metrics.window.key_pairs` [s]."""
    sel = valid & (closing > closing_speed)
    if not sel.any():
        return math.inf
    return float(np.min(np.maximum(gap[sel], 0.0) / closing[sel]))


def max_drac(
    log: SimulationLog, window: MetricWindow, *, closing_speed: float = CLOSING_SPEED
) -> float:
    """Maximum deceleration rate to avoid a crash among the key vehicles [m/s^2].

    Definition: over the same rows and pairs as :func:`min_ttc` (closing speed
    ``v_f - v_l > closing_speed``), the maximum of ``(v_f - v_l)**2 / (2 gap)``; a closing
    pair with ``gap <= 0`` (overlap) gives ``inf``.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.
    closing_speed : float
        Minimum closing speed [m/s], default 0.1.

    Returns
    -------
    float
        Maximum DRAC [m/s^2]; 0 if no pair ever closes.
    """
    return _max_drac(*key_pairs(log, window, window_rows(log, window)), closing_speed)


def _max_drac(
    gap: FloatArray, closing: FloatArray, valid: np.ndarray, closing_speed: float
) -> float:
    """:func:`max_drac` of the pairs of :func:`~hcomc.metrics.window.key_pairs` [m/s²]."""
    sel = valid & (closing > closing_speed)
    if not sel.any():
        return 0.0
    g, dv = gap[sel], closing[sel]
    drac = np.where(g > 0.0, dv * dv / (2.0 * np.where(g > 0.0, g, 1.0)), np.inf)
    return float(drac.max())


def closing_metrics(log: SimulationLog, window: MetricWindow) -> dict[Callable[..., float], float]:
    """:func:`min_ttc` and :func:`max_drac` (default closing speed), keyed by function: the
    values they return, from one table of key-vehicle pairs."""
    pairs = key_pairs(log, window, window_rows(log, window))
    return {min_ttc: _min_ttc(*pairs, CLOSING_SPEED), max_drac: _max_drac(*pairs, CLOSING_SPEED)}


def pet_at_merge(log: SimulationLog, window: MetricWindow) -> float:
    """Post-encroachment time at VR's merge point [s] (larger is better).

    Definition: let row ``r_c`` be the first window row in which VR's logged lane is 1 and
    ``x_c`` VR's front bumper there (the merge point). VR's new follower is the active
    lane-1 vehicle (any vehicle, key or not) with the largest ``x < x_c`` in row ``r_c``.
    Then ``PET = t_f - t_vr``, where ``t_vr`` is the first time at or after ``r_c`` that
    VR's rear ``x - L`` reaches ``x_c`` and ``t_f`` the first time the follower's front
    ``x`` reaches ``x_c``, both linearly interpolated between logged rows.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.

    Returns
    -------
    float
        PET [s] (negative only if the follower reaches x_c before VR's rear has cleared
        it). NaN if VR did not merge, is never logged in lane 1, has no follower, or VR's
        rear or the follower do not reach ``x_c`` by ``t_end``.
    """
    vr = int(window.group.get("VR", -1))
    if not window.merged or vr < 0:
        return math.nan
    rows = window_rows(log, window)
    in_lane1 = log.active[rows, vr] & (log.lane[rows, vr] == 1)
    if not in_lane1.any():
        return math.nan
    r_c = rows.start + int(np.argmax(in_lane1))
    x_c = float(log.x[r_c, vr])
    x_row = log.x[r_c].astype(np.float64)
    behind = log.active[r_c] & (log.lane[r_c] == 1) & (x_row < x_c)
    behind[vr] = False
    if not behind.any():
        return math.nan
    follower = int(np.argmax(np.where(behind, x_row, -np.inf)))
    after = slice(r_c, rows.stop)
    t = times(log)[after]
    rear = log.x[after, vr].astype(np.float64) - float(log.length[vr])
    t_vr = _first_crossing(t, rear, x_c)
    t_f = _first_crossing(t, log.x[after, follower].astype(np.float64), x_c)
    return float(t_f - t_vr)


def _collision_events(log: SimulationLog, window: MetricWindow) -> np.ndarray:
    ev = log.events_of(EventKind.COLLISION)
    if not (math.isfinite(window.t_start) and math.isfinite(window.t_end)):
        return ev[:0]
    inside = (ev["t"] >= window.t_start - EPS_T) & (ev["t"] <= window.t_end + EPS_T)
    return ev[inside]


def collisions(log: SimulationLog, window: MetricWindow) -> float:
    """Number of collisions in the window [count] (smaller is better; 0 expected).

    Definition: the number of COLLISION events (all vehicles) with
    ``t_start <= t <= t_end``. The engine logs one event per pair when their rectangles
    start to overlap.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.

    Returns
    -------
    float
        Count, as a float.
    """
    return float(_collision_events(log, window).size)


def key_collisions(log: SimulationLog, window: MetricWindow) -> float:
    """Number of collisions involving a key vehicle in the window [count].

    Definition: the COLLISION events of :func:`collisions` whose ``vehicle`` or ``other``
    is a present key vehicle.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.

    Returns
    -------
    float
        Count, as a float.
    """
    ev = _collision_events(log, window)
    keys = window.key_vehicles
    hit = np.isin(ev["vehicle"], keys) | np.isin(ev["other"], keys)
    return float(np.count_nonzero(hit))
