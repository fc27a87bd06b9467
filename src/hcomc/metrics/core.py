r"""Evaluation metrics of one merge (DESIGN.md §5, MODELS.md §12, paper Tables II-III).

The paper names its metrics but does not define them; the definitions below are this
project's documented assumptions (MODELS.md §12), chosen to be consistent with the paper's
magnitudes. All metrics are pure, vectorised functions of a
:class:`~hcomc.sim.log.SimulationLog` and a :class:`MetricWindow`:

* the **evaluation window** ``[t_start, t_end]`` runs from VR's entry into the cooperative
  control zone to the last logged row; only logged rows with ``t_start <= t <= t_end`` are
  used unless a metric says otherwise (times compared with a tolerance of 1e-6 s);
* the **key vehicles** are the six roles VR, VMC, VMF, VMR, VNF, VNR of the merge group; a
  role mapped to -1 is missing and ignored ("present" key vehicles);
* **same lane** means the *logged* lane of the row (``log.lane``; a lane-changing vehicle
  switches lane at the lateral midpoint of its manoeuvre); **consecutive** key vehicles are
  neighbours in the order of ``x`` within one lane, *among key vehicles only*;
* the **bumper gap** of a follower f behind its leader l is
  :math:`x_l - L_l - x_f` [m] (``x`` is the front bumper, ``L`` the vehicle length);
* integrals over time use the **rectangle rule** with the logging interval ``log.dt``: each
  logged row stands for ``[t_k, t_k + dt)``.

====================  =======================================  =====  =======  ========
registry key          function                                 unit   better   NaN when
====================  =======================================  =====  =======  ========
critical_distance     :func:`critical_distance`                m      larger   no merge
average_acceleration  :func:`average_acceleration`             m/s^2  smaller  -
stabilisation_time    :func:`stabilisation_time`               s      smaller  no merge
lsrv                  :func:`low_speed_region_volume`          m^2    smaller  -
fuel                  :func:`fuel`                             L      smaller  -
min_ttc               :func:`min_ttc` (inf: never closing)     s      larger   -
max_drac              :func:`max_drac` (0: never closing)      m/s^2  smaller  -
pet                   :func:`pet_at_merge`                     s      larger   no merge
collisions            :func:`collisions`                       count  smaller  -
key_collisions        :func:`key_collisions`                   count  smaller  -
====================  =======================================  =====  =======  ========

Degenerate windows (no active key vehicle, no same-lane key pair after the merge, no
follower, an empty log) give NaN as documented per function.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.config import RoadParams
from hcomc.models.fuel import FUEL_DEFAULT, FuelParams, fuel_consumed
from hcomc.sim.log import EventKind, SimulationLog

__all__ = [
    "A_TOL",
    "CLOSING_SPEED",
    "HOLD",
    "KEY_ROLES",
    "METRICS",
    "V_TOL",
    "MetricSpec",
    "MetricWindow",
    "average_acceleration",
    "collisions",
    "compute_metrics",
    "critical_distance",
    "fuel",
    "key_collisions",
    "low_speed_region_volume",
    "max_drac",
    "merge_window",
    "min_ttc",
    "pet_at_merge",
    "reference_speed",
    "speed_field",
    "stabilisation_time",
]

KEY_ROLES: tuple[str, ...] = ("VR", "VMC", "VMF", "VMR", "VNF", "VNR")
"""Roles of the six key vehicles of a merge group (MODELS.md, control/base.py)."""

A_TOL = 0.05
"""Stabilisation tolerance on abs(a) [m/s^2] (MODELS.md §12)."""
V_TOL = 0.5
"""Stabilisation tolerance on abs(v - v_final) [m/s] (MODELS.md §12)."""
HOLD = 2.0
"""Time the stabilisation tolerances must hold continuously [s] (MODELS.md §12)."""
CLOSING_SPEED = 0.1
"""Minimum closing speed v_follower - v_leader for TTC and DRAC [m/s]."""
DX_BIN = 10.0
"""Space bin of the speed field [m] (MODELS.md §12)."""
DT_BIN = 0.5
"""Time bin of the speed field [s] (MODELS.md §12)."""

_EPS_T = 1e-6  # tolerance of time comparisons [s]
_EPS_BIN = 1e-9  # relative tolerance of bin assignment (float rounding of t/dt_bin)


# --------------------------------------------------------------------------- window
@dataclass(frozen=True)
class MetricWindow:
    """Evaluation window of one merge.

    Parameters
    ----------
    group : dict of str to int
        Role (``"VR"``, ``"VMC"``, ``"VMF"``, ``"VMR"``, ``"VNF"``, ``"VNR"``) -> vehicle
        slot; -1 (or an absent role) means the vehicle is missing.
    t_start : float
        Window start [s]: the first logged time VR is active inside the control zone.
    t_merge : float
        VR's merge completion [s] (its MERGE event); NaN if it never merged.
    t_end : float
        Window end [s]: the last logged time.
    """

    group: dict[str, int]
    t_start: float
    t_merge: float
    t_end: float

    @property
    def key_vehicles(self) -> IntArray:
        """Slots of the present key vehicles (roles not mapped to -1), sorted, unique."""
        idx = [int(i) for i in self.group.values() if int(i) >= 0]
        return np.unique(np.asarray(idx, dtype=np.int64))

    @property
    def merged(self) -> bool:
        """True if VR's merge completion time is known."""
        return math.isfinite(self.t_merge)


def _road(log: SimulationLog) -> RoadParams:
    try:
        road = log.meta["config"]["road"]
    except (KeyError, TypeError) as exc:
        raise ValueError(
            "metrics need the road geometry in log.meta['config']['road'] "
            "(the resolved scenario config)"
        ) from exc
    return RoadParams.model_validate(road)


def _times(log: SimulationLog) -> FloatArray:
    return np.asarray(log.t[: log.n_recorded], dtype=np.float64)


def _rows(log: SimulationLog, t0: float, t1: float) -> slice:
    """Contiguous rows with ``t0 <= t <= t1`` (row times are increasing)."""
    t = _times(log)
    if not (math.isfinite(t0) and math.isfinite(t1)):
        return slice(0, 0)
    idx = np.flatnonzero((t >= t0 - _EPS_T) & (t <= t1 + _EPS_T))
    if idx.size == 0:
        return slice(0, 0)
    return slice(int(idx[0]), int(idx[-1]) + 1)


def _window_rows(log: SimulationLog, window: MetricWindow) -> slice:
    return _rows(log, window.t_start, window.t_end)


def _post_merge_rows(log: SimulationLog, window: MetricWindow) -> slice:
    return _rows(log, max(window.t_merge, window.t_start), window.t_end)


def merge_window(log: SimulationLog, vr: int, group: Mapping[str, int]) -> MetricWindow:
    """Evaluation window of VR's merge.

    Parameters
    ----------
    log : SimulationLog
        Finished log; ``log.meta["config"]["road"]`` holds the road geometry.
    vr : int
        Slot of the merging vehicle VR.
    group : mapping of str to int
        Role -> vehicle slot of the key vehicles (-1 = missing), e.g.
        ``MergeGroup.as_dict()``.

    Returns
    -------
    MetricWindow
        ``t_start`` = first logged time [s] at which VR is active with
        ``x >= road.control_zone_start`` (= ``max(0, accel_lane_start -
        control_zone_length)``); if VR never is, the first logged time.
        ``t_merge`` = time [s] of VR's first MERGE event, NaN if none.
        ``t_end`` = last logged time [s]. An empty log gives NaN times.
    """
    t = _times(log)
    cz_start = _road(log).control_zone_start
    n = t.size
    inside = log.active[:n, vr] & (log.x[:n, vr].astype(np.float64) >= cz_start)
    first = int(np.argmax(inside)) if n else 0  # 0 if VR never enters: the first row
    t_start = float(t[first]) if n else math.nan
    t_end = float(t[-1]) if n else math.nan
    merges = log.events_of(EventKind.MERGE)
    merges = merges[merges["vehicle"] == vr]
    t_merge = float(merges["t"][0]) if merges.size else math.nan
    return MetricWindow(
        group={str(k): int(v) for k, v in group.items()},
        t_start=t_start,
        t_merge=t_merge,
        t_end=t_end,
    )


# --------------------------------------------------------------------------- helpers
def _key_pairs(
    log: SimulationLog, window: MetricWindow, rows: slice
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Gaps, closing speeds and validity of consecutive same-lane key-vehicle pairs.

    Returns ``(gap, closing, valid)``, each of shape (R, K - 1) for R rows and K present
    key vehicles: per row, the key vehicles are sorted by (logged lane, x), inactive ones
    last; pair j is (follower = sorted[j], leader = sorted[j + 1]), valid if both are
    active and in the same lane. ``gap`` = x_l - L_l - x_f [m], ``closing`` = v_f - v_l
    [m/s].
    """
    keys = window.key_vehicles
    n_rows = len(range(*rows.indices(log.n_steps)))
    if keys.size < 2 or n_rows == 0:
        empty = np.empty((n_rows, 0))
        return empty, empty, np.empty((n_rows, 0), dtype=bool)
    act = log.active[rows][:, keys]
    x = log.x[rows][:, keys].astype(np.float64)
    v = log.v[rows][:, keys].astype(np.float64)
    lane = log.lane[rows][:, keys].astype(np.int64)
    length = np.broadcast_to(log.length[keys].astype(np.float64), x.shape)
    lane_key = np.where(act, lane, np.iinfo(np.int64).max)
    x_key = np.where(act, x, np.inf)
    order = np.lexsort((x_key, lane_key), axis=1)  # by lane, then by x

    def s(arr: np.ndarray) -> np.ndarray:
        return np.take_along_axis(arr, order, axis=1)

    act_s, x_s, v_s, lane_s, len_s = s(act), s(x), s(v), s(lane), s(length)
    valid = act_s[:, :-1] & act_s[:, 1:] & (lane_s[:, :-1] == lane_s[:, 1:])
    gap = x_s[:, 1:] - len_s[:, 1:] - x_s[:, :-1]
    closing = v_s[:, :-1] - v_s[:, 1:]
    return gap, closing, valid


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


# --------------------------------------------------------------------------- v_ref
def reference_speed(log: SimulationLog, window: MetricWindow) -> float:
    """Undisturbed mainline speed v_ref [m/s].

    Definition: the mean of ``v`` over all active cells (row, vehicle) of the window rows
    with logged lane 1 or 2 and ``x < road.control_zone_start`` (upstream of the
    cooperative control zone, so undisturbed by the merge). If there is no such cell, the
    mean over all active lane-1/lane-2 cells of the window rows; NaN if there is none
    either.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.

    Returns
    -------
    float
        v_ref [m/s].
    """
    rows = _window_rows(log, window)
    lane = log.lane[rows]
    main = log.active[rows] & ((lane == 1) | (lane == 2))
    v = log.v[rows].astype(np.float64)
    upstream = main & (log.x[rows].astype(np.float64) < _road(log).control_zone_start)
    for mask in (upstream, main):
        if mask.any():
            return float(v[mask].mean())
    return math.nan


# --------------------------------------------------------------------------- metrics
def critical_distance(log: SimulationLog, window: MetricWindow) -> float:
    """Critical distance [m] (paper "Crit. Dist."; larger is better).

    Definition: the minimum bumper gap ``x_l - L_l - x_f`` over all consecutive same-lane
    pairs of present, active key vehicles (consecutive in x among key vehicles only, same
    logged lane) and all logged rows with ``max(t_merge, t_start) <= t <= t_end``.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.

    Returns
    -------
    float
        Critical distance [m]; NaN if VR did not merge or no two key vehicles share a
        lane in those rows.
    """
    if not window.merged:
        return math.nan
    gap, _, valid = _key_pairs(log, window, _post_merge_rows(log, window))
    return float(gap[valid].min()) if valid.any() else math.nan


def average_acceleration(log: SimulationLog, window: MetricWindow) -> float:
    """Average absolute acceleration of the key vehicles [m/s^2] (paper "Aver. Acc.").

    Definition: the mean of ``abs(a)`` over all cells (row, vehicle) with the vehicle a
    present key vehicle, active in that row, and the row in ``[t_start, t_end]`` (pooled
    over vehicles and rows, every active cell weighted equally).

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.

    Returns
    -------
    float
        Mean ``abs(a)`` [m/s^2]; NaN if no key vehicle is active in the window.
    """
    keys = window.key_vehicles
    rows = _window_rows(log, window)
    a = log.a[rows][:, keys].astype(np.float64)
    mask = log.active[rows][:, keys] & np.isfinite(a)
    return float(np.abs(a[mask]).mean()) if mask.any() else math.nan


def stabilisation_time(
    log: SimulationLog,
    window: MetricWindow,
    *,
    a_tol: float = A_TOL,
    v_tol: float = V_TOL,
    hold: float = HOLD,
) -> float:
    """Stabilisation time after the merge [s] (paper "Stab. Time"; smaller is better).

    Definition: a logged row is *settled* if every present key vehicle that is active in
    it has ``abs(a) < a_tol`` and ``abs(v - v_final) < v_tol``, where ``v_final`` is that
    vehicle's speed at its last active row in ``[t_start, t_end]`` (inactive vehicles do
    not constrain the row). The result is ``t_s - t_merge`` for the earliest row time
    ``t_s >= max(t_merge, t_start)`` such that every logged row with
    ``t_s <= t <= t_s + hold`` is settled and ``t_s + hold <= t_end`` (the hold is fully
    observed). Since rows are discrete, ``t_s`` is the first logged row at or after
    the merge, so a merge between rows adds up to one logging interval.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.
    a_tol : float
        Tolerance on ``abs(a)`` [m/s^2], default 0.05.
    v_tol : float
        Tolerance on ``abs(v - v_final)`` [m/s], default 0.5.
    hold : float
        Time the tolerances must hold continuously [s], default 2.

    Returns
    -------
    float
        Stabilisation time [s]. **Censored**: if no hold interval fits before ``t_end``,
        ``t_end - t_merge`` (a lower bound). NaN if VR did not merge, or merged after the
        last logged row.
    """
    if not window.merged:
        return math.nan
    rows_w = _window_rows(log, window)
    rows = _post_merge_rows(log, window)
    if rows.stop <= rows.start:
        return math.nan
    keys = window.key_vehicles
    t = _times(log)[rows]
    if keys.size == 0:
        return float(t[0] - window.t_merge)
    # v_final from the whole window: speed at each key vehicle's last active row.
    act_w = log.active[rows_w][:, keys]
    last = act_w.shape[0] - 1 - np.argmax(act_w[::-1], axis=0)
    v_final = np.where(act_w.any(axis=0), log.v[rows_w][last, np.arange(keys.size)], np.nan)
    act = log.active[rows][:, keys]
    a = log.a[rows][:, keys].astype(np.float64)
    v = log.v[rows][:, keys].astype(np.float64)
    ok_cell = (np.abs(a) < a_tol) & (np.abs(v - v_final) < v_tol)
    settled = np.all(~act | ok_cell, axis=1)
    # rows r .. end[r] - 1 cover [t_r, t_r + hold]; all settled <=> count == length.
    end = np.searchsorted(t, t + hold + _EPS_T, side="right")
    csum = np.concatenate(([0], np.cumsum(settled, dtype=np.int64)))
    fits = t + hold <= window.t_end + _EPS_T
    good = fits & settled & (csum[end] - csum[np.arange(t.size)] == end - np.arange(t.size))
    if good.any():
        return float(t[int(np.argmax(good))] - window.t_merge)
    return float(window.t_end - window.t_merge)


def _bins(
    log: SimulationLog, window: MetricWindow, dx: float, dt_bin: float
) -> tuple[FloatArray, FloatArray]:
    """Bin edges of the speed field: x over [0, road.length], t over [t_start, t_end + dt)."""
    if not (dx > 0 and dt_bin > 0):
        raise ValueError(f"bin sizes must be > 0, got dx={dx}, dt_bin={dt_bin}")
    length = _road(log).length
    n_x = max(1, math.ceil(length / dx - _EPS_BIN))
    x_edges = np.minimum(np.arange(n_x + 1, dtype=np.float64) * dx, length)
    if not (math.isfinite(window.t_start) and math.isfinite(window.t_end)):
        return x_edges, np.array([0.0, 0.0])
    span = window.t_end + log.dt - window.t_start
    n_t = max(1, math.ceil(span / dt_bin - _EPS_BIN))
    t_edges = window.t_start + np.arange(n_t + 1, dtype=np.float64) * dt_bin
    t_edges[-1] = min(t_edges[-1], window.t_end + log.dt)
    return x_edges, t_edges


def _binned(
    log: SimulationLog, window: MetricWindow, lane: int, dx: float, dt_bin: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Speed sums [m/s] and cell counts per (t bin, x bin) of one lane."""
    x_edges, t_edges = _bins(log, window, dx, dt_bin)
    n_x, n_t = x_edges.size - 1, t_edges.size - 1
    rows = _window_rows(log, window)
    x = log.x[rows].astype(np.float64)
    with np.errstate(invalid="ignore"):
        cell = log.active[rows] & (log.lane[rows] == lane) & (x >= 0.0) & (x <= x_edges[-1])
    r, c = np.nonzero(cell)
    t = _times(log)[rows][r]
    ix = np.clip(np.floor(x[r, c] / dx + _EPS_BIN), 0, n_x - 1).astype(np.int64)
    it = np.floor((t - window.t_start) / dt_bin + _EPS_BIN)
    it = np.clip(it, 0, n_t - 1).astype(np.int64)
    flat = it * n_x + ix
    v = log.v[rows][r, c].astype(np.float64)
    sums = np.bincount(flat, weights=v, minlength=n_t * n_x).reshape(n_t, n_x)
    counts = np.bincount(flat, minlength=n_t * n_x).reshape(n_t, n_x).astype(np.float64)
    return x_edges, t_edges, sums, counts


def speed_field(
    log: SimulationLog,
    window: MetricWindow,
    *,
    lane: int,
    dx: float = DX_BIN,
    dt_bin: float = DT_BIN,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Binned space-time speed field v(x, t) of one lane.

    Definition: the active cells (row, vehicle) of the window rows with logged lane
    ``lane`` and front bumper ``0 <= x <= road.length`` are binned by x into bins
    ``[k dx, (k+1) dx)`` over ``[0, road.length]`` (the last bin is closed and may be
    narrower) and by row time into bins ``[t_start + m dt_bin, t_start + (m+1) dt_bin)``
    over ``[t_start, t_end + log.dt)`` (each row stands for one logging interval, as in
    the rectangle rule; the last bin may be narrower). A bin's speed is the mean speed of
    its cells.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.
    lane : int
        Lane index (1 or 2; 0 = ramp also works).
    dx : float
        Space bin [m], default 10.
    dt_bin : float
        Time bin [s], default 0.5.

    Returns
    -------
    x_edges : numpy.ndarray, shape (n_x + 1,)
        Space bin edges [m].
    t_edges : numpy.ndarray, shape (n_t + 1,)
        Time bin edges [s].
    V : numpy.ndarray, shape (n_t, n_x)
        Mean speed per bin [m/s], NaN for empty bins; rows are time bins, so
        ``pcolormesh(x_edges, t_edges, V)`` (or ``pcolormesh(t_edges, x_edges, V.T)``)
        draws it.
    """
    x_edges, t_edges, sums, counts = _binned(log, window, lane, dx, dt_bin)
    with np.errstate(invalid="ignore", divide="ignore"):
        V = np.where(counts > 0, sums / counts, np.nan)
    return x_edges, t_edges, V


def low_speed_region_volume(
    log: SimulationLog,
    window: MetricWindow,
    *,
    v_ref: float | None = None,
    dx: float = DX_BIN,
    dt_bin: float = DT_BIN,
) -> float:
    r"""Low-speed region volume LSRV [m^2] (paper "LSRV"; smaller is better).

    Definition (MODELS.md §12), summed over lanes 1 and 2:

    .. math::

       \mathrm{LSRV} = \sum_{\text{lane}} \sum_{\text{bins}} \max(0, v_{ref} - V_{b})\,
                       \Delta x_b\, \Delta t_b

    with ``V_b`` the bin speed of :func:`speed_field` and ``Δx_b``, ``Δt_b`` the bin
    widths [m], [s]; empty bins contribute 0. Units: m/s · m · s = m².

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.
    v_ref : float or None
        Reference speed [m/s]; default :func:`reference_speed`.
    dx : float
        Space bin [m], default 10.
    dt_bin : float
        Time bin [s], default 0.5.

    Returns
    -------
    float
        LSRV [m^2], >= 0 (0 if no mainline cell is in the window).
    """
    if v_ref is None:
        v_ref = reference_speed(log, window)
    total = 0.0
    for lane in (1, 2):
        x_edges, t_edges, sums, counts = _binned(log, window, lane, dx, dt_bin)
        occupied = counts > 0
        if not occupied.any():
            continue
        area = np.outer(np.diff(t_edges), np.diff(x_edges))
        deficit = np.maximum(0.0, v_ref - sums[occupied] / counts[occupied])
        total += float(np.sum(deficit * area[occupied]))
    return total


def fuel(log: SimulationLog, window: MetricWindow, *, params: FuelParams = FUEL_DEFAULT) -> float:
    """Total fuel consumption of all vehicles in the window [L] (paper "Fuel Cons.").

    Definition: paper Eq. (16) via :func:`hcomc.models.fuel.fuel_consumed` over every
    vehicle slot and the window rows, rectangle rule with the logging interval:
    ``F = log.dt / 1000 * Σ_rows Σ_vehicles fdot(v, a)``; inactive cells count as 0.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window.
    params : FuelParams
        Fuel-model coefficients, default :data:`hcomc.models.fuel.FUEL_DEFAULT`.

    Returns
    -------
    float
        Fuel [L].
    """
    rows = _window_rows(log, window)
    per_vehicle = fuel_consumed(log.v[rows], log.a[rows], log.dt, params, axis=0)
    return float(np.sum(per_vehicle))


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
    gap, closing, valid = _key_pairs(log, window, _window_rows(log, window))
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
    gap, closing, valid = _key_pairs(log, window, _window_rows(log, window))
    sel = valid & (closing > closing_speed)
    if not sel.any():
        return 0.0
    g, dv = gap[sel], closing[sel]
    drac = np.where(g > 0.0, dv * dv / (2.0 * np.where(g > 0.0, g, 1.0)), np.inf)
    return float(drac.max())


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
    rows = _window_rows(log, window)
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
    t = _times(log)[after]
    rear = log.x[after, vr].astype(np.float64) - float(log.length[vr])
    t_vr = _first_crossing(t, rear, x_c)
    t_f = _first_crossing(t, log.x[after, follower].astype(np.float64), x_c)
    return float(t_f - t_vr)


def _collision_events(log: SimulationLog, window: MetricWindow) -> np.ndarray:
    ev = log.events_of(EventKind.COLLISION)
    if not (math.isfinite(window.t_start) and math.isfinite(window.t_end)):
        return ev[:0]
    inside = (ev["t"] >= window.t_start - _EPS_T) & (ev["t"] <= window.t_end + _EPS_T)
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


# --------------------------------------------------------------------------- registry
@dataclass(frozen=True)
class MetricSpec:
    """A registered metric.

    Parameters
    ----------
    name : str
        Registry key and results-table column.
    unit : str
        Unit of the value.
    better : {"larger", "smaller"}
        Which direction is better.
    func : callable
        ``func(log, window, **kwargs) -> float``.
    description : str
        One-line definition.
    """

    name: str
    unit: str
    better: Literal["larger", "smaller"]
    func: Callable[..., float]
    description: str


_SPECS = (
    MetricSpec(
        name="critical_distance",
        unit="m",
        better="larger",
        func=critical_distance,
        description="min bumper gap of consecutive same-lane key vehicles, merge to window end",
    ),
    MetricSpec(
        name="average_acceleration",
        unit="m/s²",
        better="smaller",
        func=average_acceleration,
        description="mean abs(a) over the active key-vehicle cells of the window",
    ),
    MetricSpec(
        name="stabilisation_time",
        unit="s",
        better="smaller",
        func=stabilisation_time,
        description="merge until all key vehicles hold abs(a) < 0.05, abs(v - v_final) < 0.5 "
        "for 2 s (censored at the window end)",
    ),
    MetricSpec(
        name="lsrv",
        unit="m²",
        better="smaller",
        func=low_speed_region_volume,
        description="Σ over lanes 1, 2 of ∫∫ max(0, v_ref - v(x, t)) dx dt on 10 m x 0.5 s bins",
    ),
    MetricSpec(
        name="fuel",
        unit="L",
        better="smaller",
        func=fuel,
        description="Eq. 16 fuel of all vehicles over the window",
    ),
    MetricSpec(
        name="min_ttc",
        unit="s",
        better="larger",
        func=min_ttc,
        description="min gap / closing speed of consecutive same-lane key vehicles",
    ),
    MetricSpec(
        name="max_drac",
        unit="m/s²",
        better="smaller",
        func=max_drac,
        description="max closing speed² / (2 gap) of consecutive same-lane key vehicles",
    ),
    MetricSpec(
        name="pet",
        unit="s",
        better="larger",
        func=pet_at_merge,
        description="post-encroachment time of VR's new lane-1 follower at VR's merge point",
    ),
    MetricSpec(
        name="collisions",
        unit="count",
        better="smaller",
        func=collisions,
        description="COLLISION events in the window, all vehicles",
    ),
    MetricSpec(
        name="key_collisions",
        unit="count",
        better="smaller",
        func=key_collisions,
        description="COLLISION events in the window involving a key vehicle",
    ),
)

METRICS: dict[str, MetricSpec] = {spec.name: spec for spec in _SPECS}
"""Registry of all metrics, keyed by results-table column name."""


def compute_metrics(log: SimulationLog, window: MetricWindow) -> dict[str, float]:
    """Evaluate every metric of :data:`METRICS`.

    Parameters
    ----------
    log : SimulationLog
        The run's log.
    window : MetricWindow
        Evaluation window (see :func:`merge_window`).

    Returns
    -------
    dict of str to float
        Registry key -> value, in registry order. The reference speed of
        :func:`reference_speed` is computed once and passed to the metrics that take a
        ``v_ref`` keyword.
    """
    v_ref = reference_speed(log, window)
    out: dict[str, float] = {}
    for name, spec in METRICS.items():
        kwargs = {"v_ref": v_ref} if "v_ref" in inspect.signature(spec.func).parameters else {}
        out[name] = float(spec.func(log, window, **kwargs))
    return out
