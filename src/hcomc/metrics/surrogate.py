"""Surrogate safety measures of the merge: TTC, DRAC, PET and collisions.

TTC and DRAC read the consecutive same-lane key-vehicle pairs of :mod:`hcomc.metrics.window`
(fixed key vehicles, bumper gap) with lanes taken from the vehicles' bodies: a key vehicle
whose body overlaps two lanes during a lane change is in both (:func:`body_pairs`). PET is
taken against the first vehicle whose front passes VR's merge point in VR's lane. Rows are
those of the evaluation window.

A vehicle is **in a lane change** in the logged rows with ``t_s <= t <= t_e`` between its
LANE_CHANGE_START event (time ``t_s``, ``value`` = target lane) and the next
LANE_CHANGE_END event (time ``t_e``; none: to the end of the log). The row logged at
``t_e`` is included because the engine logs a step's events at its start time and its state
at its end: that row still shows the body part-way. Its **body overlaps** lane ``L`` if
``abs(y - y_L) < (W + w) / 2``, with ``y`` its logged lateral position [m], ``y_L = (L - 1) W``
the lane's centre line, ``W`` the lane width (``road.lane_width``) and ``w`` its width [m]:
the engine's own test of which lanes a changer occupies (:mod:`hcomc.sim.step.motion`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.metrics.pairs import consecutive_pairs
from hcomc.metrics.window import EPS_T, MetricWindow, key_pairs, road_of, times, window_rows
from hcomc.road import N_LANES, Lane
from hcomc.safety.surrogate import CLOSING_SPEED
from hcomc.sim.log import EventKind, SimulationLog

__all__ = [
    "CLOSING_SPEED",
    "body_pairs",
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


def _change_targets(log: SimulationLog, vehicles: IntArray, t: FloatArray) -> IntArray:
    """(R, V) target lane of each vehicle's lane change in progress at the row times ``t``
    (``t_s <= t <= t_e``, see the module docstring), -1 where it is not changing."""
    out = np.full((t.size, vehicles.size), -1, dtype=np.int64)
    starts = log.events_of(EventKind.LANE_CHANGE_START)
    starts = starts[np.isin(starts["vehicle"], vehicles)]
    if not starts.size:
        return out
    ends = log.events_of(EventKind.LANE_CHANGE_END)
    for c, i in enumerate(vehicles.tolist()):
        s = starts[starts["vehicle"] == i]
        if not s.size:
            continue
        t_end = ends["t"][ends["vehicle"] == i]
        n_started = np.searchsorted(s["t"], t + EPS_T, side="right")
        n_ended = np.searchsorted(t_end, t - EPS_T, side="left")  # ended strictly before t
        on = n_started > n_ended
        out[on, c] = s["value"][n_started[on] - 1].astype(np.int64)
    return out


def _overlaps(y: FloatArray, lane: IntArray, width: FloatArray, lane_width: float) -> np.ndarray:
    """Whether a body at lateral position ``y`` [m] of ``width`` [m] overlaps ``lane``
    (``abs(y - (lane - 1) W) < (W + w) / 2``); False where ``y`` is NaN."""
    with np.errstate(invalid="ignore"):
        return np.abs(y - (lane - 1.0) * lane_width) < 0.5 * (lane_width + width)


def _second_lanes(log: SimulationLog, keys: IntArray, rows: slice) -> IntArray:
    """(R, K) second lane of each key vehicle, -1 if none: for an active vehicle in a lane
    change, the lane next to its logged lane on the side of its lateral offset from that
    lane's centre, if its body overlaps it (0 <= lane < 3)."""
    t = times(log)[rows]
    changing = _change_targets(log, keys, t) >= 0
    if not changing.any():
        return np.full(changing.shape, -1, dtype=np.int64)
    lane_width = road_of(log).lane_width
    lane = log.lane[rows, keys].astype(np.int64)
    y = log.y[rows, keys].astype(np.float64)
    offset = y - (lane - 1.0) * lane_width
    side = np.where(np.isfinite(offset), np.sign(offset), 0.0).astype(np.int64)
    other = lane + side
    width = log.width[keys].astype(np.float64)
    ok = (changing & log.active[rows, keys] & (side != 0) & (other >= 0) & (other < N_LANES)
          & _overlaps(y, other, width, lane_width))  # fmt: skip
    return np.where(ok, other, -1)


def body_pairs(
    log: SimulationLog, window: MetricWindow, rows: slice
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Gaps, closing speeds and validity of consecutive same-lane key vehicles, a body that
    overlaps two lanes counting in both.

    Every active key vehicle is an entry in its logged lane; a key vehicle in a lane change
    whose body overlaps the lane next to its logged lane on the side of its lateral offset
    (its origin lane after the logged lane switched at the change's middle, its target lane
    before) is a second entry in that lane. Per row, entries are sorted by (lane, x) and each
    neighbour pair of one lane is (follower, leader) as in
    :func:`~hcomc.metrics.window.key_pairs`, which this equals when no key vehicle's body
    overlaps two lanes. Returns ``(gap, closing, valid)`` of shape (R, P): ``gap`` =
    x_l - L_l - x_f [m], ``closing`` = v_f - v_l [m/s], ``valid`` True for a real pair.
    """
    keys = window.key_vehicles
    if keys.size < 2 or rows.stop <= rows.start:
        return key_pairs(log, window, rows)
    second = _second_lanes(log, keys, rows)
    doubled = second >= 0
    if not doubled.any():
        return key_pairs(log, window, rows)
    act, lane = log.active[rows, keys], log.lane[rows, keys]
    x, v = log.x[rows, keys], log.v[rows, keys]
    act = np.concatenate([act, doubled], axis=1)
    lane = np.concatenate([lane, np.where(doubled, second, lane).astype(lane.dtype)], axis=1)
    x, v = np.concatenate([x, x], axis=1), np.concatenate([v, v], axis=1)
    length = np.concatenate([log.length[keys], log.length[keys]])
    shape = (x.shape[0], x.shape[1] - 1)
    gap, closing, valid = np.empty(shape), np.empty(shape), np.empty(shape, dtype=bool)
    consecutive_pairs(act, x, v, lane, length, gap, closing, valid)
    return gap, closing, valid


def min_ttc(
    log: SimulationLog, window: MetricWindow, *, closing_speed: float = CLOSING_SPEED
) -> float:
    """Minimum time-to-collision among the key vehicles [s] (larger is better).

    Definition: over all rows in ``[t_start, t_end]`` and all consecutive same-lane
    key-vehicle pairs of :func:`body_pairs` (a key vehicle in a lane change counts in both
    lanes while its body overlaps both) with closing speed ``v_f - v_l > closing_speed``,
    the minimum of ``max(gap, 0) / (v_f - v_l)`` (an overlapping closing pair has TTC 0).

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
    return _min_ttc(*body_pairs(log, window, window_rows(log, window)), closing_speed)


def _min_ttc(
    gap: FloatArray, closing: FloatArray, valid: np.ndarray, closing_speed: float
) -> float:
    """:func:`min_ttc` of the pairs of :func:`body_pairs` [s]."""
    sel = valid & (closing > closing_speed)
    if not sel.any():
        return math.inf
    return float(np.min(np.maximum(gap[sel], 0.0) / closing[sel]))


def max_drac(
    log: SimulationLog, window: MetricWindow, *, closing_speed: float = CLOSING_SPEED
) -> float:
    """Maximum deceleration rate to avoid a crash among the key vehicles [m/s^2].

    Definition: over the same rows and pairs as :func:`min_ttc` (:func:`body_pairs`,
    closing speed ``v_f - v_l > closing_speed``), the maximum of
    ``(v_f - v_l)**2 / (2 gap)``; a closing pair with ``gap <= 0`` (overlap) gives ``inf``.

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
    return _max_drac(*body_pairs(log, window, window_rows(log, window)), closing_speed)


def _max_drac(
    gap: FloatArray, closing: FloatArray, valid: np.ndarray, closing_speed: float
) -> float:
    """:func:`max_drac` of the pairs of :func:`body_pairs` [m/s²]."""
    sel = valid & (closing > closing_speed)
    if not sel.any():
        return 0.0
    g, dv = gap[sel], closing[sel]
    drac = np.where(g > 0.0, dv * dv / (2.0 * np.where(g > 0.0, g, 1.0)), np.inf)
    return float(drac.max())


def closing_metrics(log: SimulationLog, window: MetricWindow) -> dict[Callable[..., float], float]:
    """:func:`min_ttc` and :func:`max_drac` (default closing speed), keyed by function: the
    values they return, from one table of key-vehicle pairs."""
    pairs = body_pairs(log, window, window_rows(log, window))
    return {min_ttc: _min_ttc(*pairs, CLOSING_SPEED), max_drac: _max_drac(*pairs, CLOSING_SPEED)}


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
    into lane 1 with its body overlapping lane 1 (module docstring). A vehicle changing away
    from lane 1 does not count, one changing into it counts once its body overlaps it.

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
    target = _change_targets(log, others, t)[at, cols]
    lane = log.lane[after, others][at, cols].astype(np.int64)
    in_lane = (target < 0) & (lane == lane_1)
    if (target == lane_1).any():
        y = log.y[after, others][at, cols].astype(np.float64)
        body = _overlaps(y, np.full(others.size, lane_1), log.width[others].astype(np.float64),
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
