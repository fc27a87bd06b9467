"""Surrogate safety measures of the merge: TTC, DRAC, PET and collisions.

TTC and DRAC read every follower-leader pair of a lane in which a key vehicle takes part, as
follower or as leader, the other vehicle key or not, with lanes taken from the vehicles'
bodies: a vehicle whose body overlaps two lanes during a lane change is in both, as the
engine's followers see it (:func:`hcomc.metrics.bodies.body_pairs`). PET is taken against
the first vehicle whose front passes VR's merge point in VR's lane. Rows are those of the
evaluation window. Lane changes and body overlaps are defined in :mod:`hcomc.metrics.bodies`.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from hcomc._typing import FloatArray
from hcomc.metrics.bodies import body_pairs, change_targets, overlaps
from hcomc.metrics.window import EPS_T, MetricWindow, road_of, times, window_rows
from hcomc.road import Lane
from hcomc.safety.surrogate import CLOSING_SPEED
from hcomc.sim.log import EventKind, SimulationLog

__all__ = [
    "CLOSING_SPEED",
    "collisions",
    "key_collisions",
    "max_drac",
    "min_ttc",
    "pairs_min_ttc",
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


def _key_pairs(log: SimulationLog, window: MetricWindow) -> tuple[FloatArray, FloatArray]:
    """Gaps and closing speeds of the window's pairs with a key vehicle (module docstring)."""
    return body_pairs(log, window_rows(log, window), window.key_vehicles)


def min_ttc(
    log: SimulationLog, window: MetricWindow, *, closing_speed: float = CLOSING_SPEED
) -> float:
    """Minimum time-to-collision of the key vehicles [s] (larger is better).

    Definition: over all rows in ``[t_start, t_end]`` and every follower-leader pair of a
    lane in which a key vehicle is the follower or the leader (any other vehicle; a vehicle
    in a lane change counts in both lanes while its body overlaps both,
    :func:`hcomc.metrics.bodies.body_pairs`) with closing speed ``v_f - v_l >
    closing_speed``, the minimum of ``max(gap, 0) / (v_f - v_l)`` (an overlapping closing
    pair has TTC 0).

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
    return pairs_min_ttc(*_key_pairs(log, window), closing_speed)


def pairs_min_ttc(gap: FloatArray, closing: FloatArray, closing_speed: float) -> float:
    """:func:`min_ttc` of the pairs of :func:`hcomc.metrics.bodies.body_pairs` [s]."""
    sel = closing > closing_speed
    if not sel.any():
        return math.inf
    return float(np.min(np.maximum(gap[sel], 0.0) / closing[sel]))


def max_drac(
    log: SimulationLog, window: MetricWindow, *, closing_speed: float = CLOSING_SPEED
) -> float:
    """Maximum deceleration rate to avoid a crash of the key vehicles [m/s^2].

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
    return _max_drac(*_key_pairs(log, window), closing_speed)


def _max_drac(gap: FloatArray, closing: FloatArray, closing_speed: float) -> float:
    """:func:`max_drac` of the pairs of :func:`hcomc.metrics.bodies.body_pairs` [m/s²]."""
    sel = closing > closing_speed
    if not sel.any():
        return 0.0
    g, dv = gap[sel], closing[sel]
    drac = np.where(g > 0.0, dv * dv / (2.0 * np.where(g > 0.0, g, 1.0)), np.inf)
    return float(drac.max())


def closing_metrics(log: SimulationLog, window: MetricWindow) -> dict[Callable[..., float], float]:
    """:func:`min_ttc` and :func:`max_drac` (default closing speed), keyed by function: the
    values they return, from one table of pairs."""
    pairs = _key_pairs(log, window)
    return {
        min_ttc: pairs_min_ttc(*pairs, CLOSING_SPEED),
        max_drac: _max_drac(*pairs, CLOSING_SPEED),
    }


def pet_at_merge(log: SimulationLog, window: MetricWindow) -> float:
    """Post-encroachment time at VR's merge point [s] (larger is better).

    Definition: let row ``r_c`` be the first window row in which VR's logged lane is 1 and
    ``x_c`` VR's front bumper there (the merge point, the conflict point in lane 1). Then
    ``PET = t_f - t_vr``: ``t_vr`` is the first time at or after ``r_c`` that VR's rear
    ``x - L`` reaches ``x_c``; ``t_f`` the earliest time at which the front ``x`` of another
    vehicle (key or not) active behind it in row ``r_c`` (``x < x_c``, any lane) reaches
    ``x_c`` in lane 1, both linearly interpolated between logged rows. A vehicle passes in
    lane 1 if, in the first row its front is at or past ``x_c``, its *target* lane is 1 and
    its body is in lane 1: not in a lane change and logged in lane 1, or in a lane change
    into lane 1 with its body overlapping lane 1 (:mod:`hcomc.metrics.bodies`). A vehicle
    changing away from lane 1 does not count, one changing into it counts once its body
    overlaps it.

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
        it). NaN if VR did not merge, is never logged in lane 1, no vehicle passes ``x_c``
        in lane 1 after ``r_c`` by ``t_end``, or VR's rear does not reach ``x_c`` by then.
    """
    vr = int(window.group.get("VR", -1))
    if not window.merged or vr < 0:
        return math.nan
    rows = window_rows(log, window)
    lane_1 = int(Lane.MAIN_1)
    in_lane1 = log.active[rows, vr] & (log.lane[rows, vr] == lane_1)
    if not in_lane1.any():
        return math.nan
    r_c = rows.start + int(np.argmax(in_lane1))
    x_c = float(log.x[r_c, vr])
    behind = log.active[r_c] & (log.x[r_c].astype(np.float64) < x_c)
    behind[vr] = False
    others = np.flatnonzero(behind)
    after = slice(r_c, rows.stop)
    t = times(log)[after]
    rear = log.x[after, vr].astype(np.float64) - float(log.length[vr])
    t_vr = _first_crossing(t, rear, x_c)
    if not others.size:
        return math.nan
    x = log.x[after, others].astype(np.float64)
    with np.errstate(invalid="ignore"):
        reached = x >= x_c
    passes = reached.any(axis=0)
    at = np.argmax(reached, axis=0)  # each vehicle's first row at or past x_c
    cols = np.arange(others.size)
    target = change_targets(log, others, t)[at, cols]
    lane = log.lane[after, others][at, cols].astype(np.int64)
    in_lane = (target < 0) & (lane == lane_1)
    if (target == lane_1).any():
        y = log.y[after, others][at, cols].astype(np.float64)
        body = overlaps(y, np.full(others.size, lane_1), log.width[others].astype(np.float64),
                        road_of(log).lane_width)  # fmt: skip
        in_lane |= (target == lane_1) & body
    t_f = min((_first_crossing(t, x[:, c], x_c) for c in np.flatnonzero(passes & in_lane)),
              default=math.nan)  # fmt: skip
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
