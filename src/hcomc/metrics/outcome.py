"""The outcome of one merge: whether VR merged, when, how long it waited, in which sequence.

A run in which the ramp vehicle never merged is an *outcome*, not a run without disturbance:
the disturbance metrics of such a run are NaN (nothing to compare), and its record here says
what happened instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hcomc.metrics.window import EPS_T, MetricWindow
from hcomc.sim.log import EventKind, SimulationLog

__all__ = ["OUTCOME_FIELDS", "MergeOutcome", "merge_outcome", "realised_sequence"]


@dataclass(frozen=True)
class MergeOutcome:
    """What became of VR's merge.

    Parameters
    ----------
    merged : bool
        VR completed its merge into lane 1 (its MERGE event) within the log.
    merge_time : float
        ``t_merge - t_start`` [s]: from VR's entry into the control zone to its merge
        completion; NaN if it did not merge.
    ramp_wait : float
        Time VR stood waiting at the end of the acceleration lane [s]: from its RAMP_WAIT
        event (the engine's: on the ramp, not changing lane, slower than 0.1 m/s within
        20 m of the lane end) to the start of its next lane change (its first
        LANE_CHANGE_START event after the wait), or to the last logged row if it never
        started one (then a lower bound). 0 if VR never waited; NaN without a ramp vehicle.
    sequence : str
        ``"ahead"`` or ``"behind"`` the VMC identified at control-zone entry
        (:func:`realised_sequence`); ``""`` without a merge or a VMC.
    """

    merged: bool
    merge_time: float
    ramp_wait: float
    sequence: str

    def as_dict(self) -> dict[str, bool | float | str]:
        """The fields by name, in :data:`OUTCOME_FIELDS` order."""
        return {name: getattr(self, name) for name in OUTCOME_FIELDS}


OUTCOME_FIELDS = ("merged", "merge_time", "ramp_wait", "sequence")
"""Names of the :class:`MergeOutcome` fields, as :func:`~hcomc.metrics.compute_metrics`
returns them after the metrics."""


def realised_sequence(log: SimulationLog, vr: int, vmc: int) -> str:
    """Where VR merged relative to the VMC identified at control-zone entry: "ahead" or
    "behind" (its position at VR's merge completion), "" without a merge or a VMC."""
    merges = log.events_of(EventKind.MERGE)
    t = merges["t"][merges["vehicle"] == vr]
    if vr < 0 or vmc < 0 or t.size == 0:
        return ""
    row = int(np.argmin(np.abs(log.t[: log.n_recorded] - t[0])))
    if not log.active[row, vmc]:
        return ""
    return "ahead" if log.x[row, vr] > log.x[row, vmc] else "behind"


def ramp_wait(log: SimulationLog, vr: int) -> float:
    """:attr:`MergeOutcome.ramp_wait` of vehicle ``vr`` [s]."""
    if vr < 0:
        return math.nan
    events = log.events
    mine = events[events["vehicle"] == vr]
    waits = mine["t"][mine["kind"] == EventKind.RAMP_WAIT]
    if waits.size == 0:
        return 0.0
    t_wait = float(waits[0])
    starts = mine["t"][mine["kind"] == EventKind.LANE_CHANGE_START]
    starts = starts[starts >= t_wait - EPS_T]
    n = log.n_recorded
    t_go = float(starts[0]) if starts.size else (float(log.t[n - 1]) if n else t_wait)
    return max(0.0, t_go - t_wait)


def merge_outcome(log: SimulationLog, window: MetricWindow) -> MergeOutcome:
    """The :class:`MergeOutcome` of the window's VR (merged: ``window.t_merge`` is known); a
    run without a ramp vehicle (empty group) did not merge, waited NaN and has no sequence."""
    vr, vmc = window.vr, int(window.group.get("VMC", -1))
    merged = window.merged
    return MergeOutcome(
        merged=merged,
        merge_time=window.t_merge - window.t_start if merged else math.nan,
        ramp_wait=ramp_wait(log, vr),
        sequence=realised_sequence(log, vr, vmc) if merged else "",
    )
