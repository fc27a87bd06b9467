r"""The evaluation window of one merge, its key vehicles, and the undisturbed reference.

Conventions shared by every metric:

* the **key vehicles** are the six roles VR, VMC, VMF, VMR, VNF, VNR found when VR enters the
  cooperative control zone, *before any control acts* (``log.meta["key_groups"]``), so every
  controller is measured on the same physical vehicles; a role mapped to -1 is missing and
  ignored ("present" key vehicles);
* the **evaluation window** ``[t_start, t_end]`` runs from VR's entry into the control zone
  to the last logged row; only logged rows with ``t_start <= t <= t_end`` are used unless a
  metric says otherwise (times compared with a tolerance of 1e-6 s); ``t_merge`` is VR's
  merge completion (its MERGE event, the end of its lane change into lane 1);
* the **undisturbed reference** is the log of the same scenario and seed in which no ramp
  vehicle is released (``Simulation(..., counterfactual=True)``): same demand, same random
  streams, nothing merges. It has the same rows and vehicle columns as the factual log, so a
  vehicle's undisturbed state is read from the same cell;
* **same lane** means the *logged* lane of the row; a vehicle's **actual leader** is the
  nearest vehicle ahead of it in its lane, key or not (critical distance, U_safe at the
  merge; :mod:`hcomc.metrics.leaders`); TTC and DRAC take lanes from the bodies instead, a
  vehicle in a lane change counting in both lanes while its body overlaps both
  (:mod:`hcomc.metrics.bodies`); the **bumper
  gap** of a follower f behind its leader l is :math:`x_l - L_l - x_f` [m] (``x`` is the
  front bumper, ``L`` the vehicle length);
* integrals over time use the **rectangle rule** with the logging interval ``log.dt``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.config import RoadParams
from hcomc.road import KEY_ROLES
from hcomc.sim.log import EventKind, SimulationLog

__all__ = [
    "A_TOL",
    "HOLD",
    "KEY_ROLES",
    "V_TOL",
    "MetricWindow",
    "key_window",
    "merge_window",
]

A_TOL = 0.05
"""Stabilisation tolerance on abs(a - a_undisturbed) [m/s^2]."""
V_TOL = 0.5
"""Stabilisation tolerance on abs(v - v_undisturbed) [m/s]."""
HOLD = 2.0
"""Time the stabilisation tolerances must hold continuously [s]."""

EPS_T = 1e-6  # tolerance of time comparisons [s]


@dataclass(frozen=True)
class MetricWindow:
    """Evaluation window of one merge.

    Parameters
    ----------
    group : dict of str to int
        Role (``"VR"``, ``"VMC"``, ``"VMF"``, ``"VMR"``, ``"VNF"``, ``"VNR"``) -> vehicle
        slot; -1 (or an absent role) means the vehicle is missing. An empty group means the
        run has no ramp vehicle (nothing merges).
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
    def vr(self) -> int:
        """VR's slot, -1 if the run has no ramp vehicle."""
        return int(self.group.get("VR", -1))

    @property
    def merged(self) -> bool:
        """True if VR's merge completion time is known."""
        return math.isfinite(self.t_merge)


def road_of(log: SimulationLog) -> RoadParams:
    """The road geometry of the run (``log.meta["config"]["road"]``).

    The one reader of a log's geometry: metrics, figures and the animation all use it, so a
    log without geometry fails everywhere the same way instead of being drawn on a default
    road.

    Raises
    ------
    ValueError
        If the log's metadata holds no road section.
    pydantic.ValidationError
        If the stored road section is invalid.
    """
    return RoadParams.model_validate(recorded_section(log, "road", "the road geometry"))


def recorded_section(log: SimulationLog, section: str, what: str) -> Any:
    """``log.meta["config"][section]``: a section of the resolved scenario config the run
    recorded; ValueError naming ``what`` is missing if the log holds none."""
    try:
        return log.meta["config"][section]
    except (KeyError, TypeError) as exc:
        raise ValueError(
            f"{what} is missing from log.meta['config']['{section}'] "
            "(the resolved scenario config a run records)"
        ) from exc


def times(log: SimulationLog) -> FloatArray:
    """Logged row times [s]."""
    return np.asarray(log.t[: log.n_recorded], dtype=np.float64)


def rows_between(log: SimulationLog, t0: float, t1: float) -> slice:
    """Contiguous rows with ``t0 <= t <= t1`` (row times are increasing)."""
    t = times(log)
    if not (math.isfinite(t0) and math.isfinite(t1)):
        return slice(0, 0)
    idx = np.flatnonzero((t >= t0 - EPS_T) & (t <= t1 + EPS_T))
    if idx.size == 0:
        return slice(0, 0)
    return slice(int(idx[0]), int(idx[-1]) + 1)


def window_rows(log: SimulationLog, window: MetricWindow) -> slice:
    """Rows of ``[t_start, t_end]``."""
    return rows_between(log, window.t_start, window.t_end)


def post_merge_rows(log: SimulationLog, window: MetricWindow) -> slice:
    """Rows of ``[max(t_merge, t_start), t_end]`` (empty if VR never merged)."""
    return rows_between(log, max(window.t_merge, window.t_start), window.t_end)


def merge_window(log: SimulationLog, vr: int, group: Mapping[str, int]) -> MetricWindow:
    """Evaluation window of VR's merge (the lower-level API: any VR and group).

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
        ``x >= road.control_zone_start``; if VR never is, the first logged time.
        ``t_merge`` = time [s] of VR's first MERGE event, NaN if none.
        ``t_end`` = last logged time [s]. An empty log gives NaN times.
    """
    t = times(log)
    cz_start = road_of(log).control_zone_start
    n = t.size
    inside = log.active[:n, vr] & (log.x[:n, vr].astype(np.float64) >= cz_start)
    first = int(np.argmax(inside)) if n else 0  # 0 if VR never enters: the first row
    merges = log.events_of(EventKind.MERGE)
    merges = merges[merges["vehicle"] == vr]
    return MetricWindow(
        group={str(k): int(v) for k, v in group.items()},
        t_start=float(t[first]) if n else math.nan,
        t_merge=float(merges["t"][0]) if merges.size else math.nan,
        t_end=float(t[-1]) if n else math.nan,
    )


def key_window(log: SimulationLog) -> MetricWindow:
    """Window of the run's first key group (``log.meta["key_groups"][0]``).

    The key group is recorded by the engine when the first ramp vehicle enters the control
    zone, for every run and before any control acts. A run without one (no ramp vehicle
    reached the control zone) gets an empty group and the whole log as window, with
    ``t_merge`` NaN.
    """
    groups = log.meta.get("key_groups") or []
    if not groups:
        t = times(log)
        lo, hi = (float(t[0]), float(t[-1])) if t.size else (math.nan, math.nan)
        return MetricWindow(group={}, t_start=lo, t_merge=math.nan, t_end=hi)
    first = groups[0]
    group = {role: int(first[role]) for role in KEY_ROLES if role in first}
    return merge_window(log, group["VR"], group)


def check_reference(log: SimulationLog, reference: SimulationLog) -> None:
    """The reference must be the same run's counterfactual: same rows and vehicle columns."""
    n, m = log.n_recorded, reference.n_recorded
    if n != m or log.x.shape[1] != reference.x.shape[1]:
        raise ValueError(
            f"reference log has {m} rows x {reference.x.shape[1]} vehicles, the log "
            f"{n} x {log.x.shape[1]}; allowed: the same scenario and seed run with "
            "counterfactual=True"
        )
    if not np.allclose(log.t[:n], reference.t[:m], atol=EPS_T):
        raise ValueError("reference log row times differ from the log's; allowed: same config")


def reference_or_score(
    log: SimulationLog, window: MetricWindow, reference: SimulationLog | None
) -> SimulationLog | float:
    """The checked reference a disturbance metric compares the run with, or the score of a
    run there is nothing to compare: 0 for a run without a ramp vehicle (empty group:
    nothing merges, nothing is disturbed); NaN without a reference, or if VR never merged
    (an outcome, not an undisturbed run)."""
    if not window.group:
        return 0.0
    if reference is None:
        return math.nan
    check_reference(log, reference)
    return reference if window.merged else math.nan
