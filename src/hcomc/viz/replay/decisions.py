"""What the replay page shows of a run's decisions: each merge plan with the interval it was
live, its virtual vehicles and predicted path, the key roles and the commanded vehicles over
time, and the events of the timeline.

Everything is read from the log: the plan records (``log.meta["plans"]``,
:class:`hcomc.sim.log.plans.PlanRecord`), the key groups (``log.meta["key_groups"]``) and the
events. A plan is **live** from its decision time ``t0`` until its VR is planned anew, its
merge is complete (MERGE event) or it leaves the road, whichever comes first (the engine's
rule, :mod:`hcomc.sim.plan_execution`). The log does not record the engine's per-step command
flags, so **commanded** is derived from the live plan as the engine sets the flags when it
adopts a plan: a CAV VR with a merge position follows the plan, VMC whenever the mode is
not ``none``, VNR within the horizon when the plan has VV2; a FALLBACK event after ``t0``
ends VR's command (and, in lateral mode, VMC's and VNR's).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hcomc.equations.lane_change import lateral_offset
from hcomc.equations.virtual_vehicle import cubic_state
from hcomc.road import KEY_ROLES, Kind, Lane, lane_centre
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.log.plans import PlanRecord, plan_records

__all__ = [
    "ROLE_NAMES", "PlanSpan", "decisions_json", "json_ready", "moment_of_interest",
    "plan_spans", "timeline_events",
]  # fmt: skip

ROLE_NAMES = (*KEY_ROLES, "STALLED")
"""The roles the replay labels: the key roles of Section II-A, then a stalled vehicle."""

MERGE_PATH_POINTS = 25
"""Points of a plan's drawn merge path (the quintic of Eqs. 4-6)."""

_GHOSTS = (  # virtual vehicle, its lane, the key vehicle whose size it takes
    ("VV0", "vv0", Lane.RAMP, "VMF"),
    ("VV1", "vv1", Lane.MAIN_1, "VR"),
    ("VV2", "vv2", Lane.MAIN_2, "VMC"),
)
_HIDDEN_EVENTS = (EventKind.INSERTION, EventKind.EXIT)  # one per vehicle: not timeline marks


@dataclass(frozen=True)
class PlanSpan:
    """One plan and when it was live: ``[start, end)`` [s], ``ended`` by "replan",
    "merge", "exit" or "end of run"; ``fallback_t`` is the first FALLBACK of its VR after
    ``t0`` within the span (NaN: none)."""

    index: int
    record: PlanRecord
    start: float
    end: float
    ended: str
    fallback_t: float


def _first_after(events: np.ndarray, kind: EventKind, vehicle: int, t: float) -> float:
    """Time of the first event of ``kind`` about ``vehicle`` at or after t (inf: none)."""
    hit = events[(events["kind"] == kind) & (events["vehicle"] == vehicle) & (events["t"] >= t)]
    return float(hit["t"].min()) if hit.size else math.inf


def plan_spans(log: SimulationLog) -> list[PlanSpan]:
    """The plans of ``log`` in decision order, each with the interval it was live."""
    records = plan_records(log)
    events = log.events
    t_last = float(log.t[log.n_recorded - 1]) if log.n_recorded else 0.0
    spans = []
    for k, rec in enumerate(records):
        vr = rec.vehicle("VR")
        later = [r.t0 for r in records[k + 1 :] if r.vehicle("VR") == vr and r.t0 >= rec.t0]
        ends = {
            "replan": min(later, default=math.inf),
            "merge": _first_after(events, EventKind.MERGE, vr, rec.t0),
            "exit": _first_after(events, EventKind.EXIT, vr, rec.t0),
        }
        ended = min(ends, key=lambda name: ends[name])
        end = ends[ended]
        if not math.isfinite(end):
            ended, end = "end of run", t_last
        fallback = events[(events["kind"] == EventKind.FALLBACK) & (events["vehicle"] == vr)
                          & (events["t"] > rec.t0) & (events["t"] < end)]  # fmt: skip
        fallback_t = float(fallback["t"].min()) if fallback.size else math.nan
        spans.append(PlanSpan(k, rec, rec.t0, end, ended, fallback_t))
    return spans


def _ghosts(span: PlanSpan, times: np.ndarray, log: SimulationLog, width: float) -> list[dict]:
    """Each virtual vehicle of the plan at the logged rows of its horizon while the plan is
    live: the cubic of Eq. 9 (:func:`hcomc.equations.virtual_vehicle.cubic_state`)."""
    rec = span.record
    stop = min(rec.t0 + rec.horizon, span.end) if math.isfinite(rec.horizon) else span.end
    rows = np.flatnonzero((times >= rec.t0 - 1e-9) & (times <= stop + 1e-9))
    out = []
    for label, key, lane, owner in _GHOSTS:
        coefficients = getattr(rec, key)
        if coefficients is None or rows.size == 0:
            continue
        k = rec.vehicle(owner)
        size = (float(log.length[k]), float(log.width[k])) if k >= 0 else (math.nan, math.nan)
        x = cubic_state(np.asarray(coefficients), times[rows] - rec.t0)[0]
        ticks = cubic_state(np.asarray(coefficients), np.arange(0.0, rec.horizon + 1e-9))[0]
        out.append({
            "label": label, "y": float(lane_centre(int(lane), width)), "length": size[0],
            "width": size[1], "row": int(rows[0]), "x": np.round(x, 3).tolist(),
            "ticks": np.round(ticks, 3).tolist(),
        })  # fmt: skip
    return out


def _merge_path(rec: PlanRecord, log: SimulationLog, width: float) -> list[list[float]]:
    """VR's planned lane change: the quintic of Eqs. 4-6 from the merge position on the
    acceleration lane to lane 1, over VR's speed at the decision times its planned
    duration (empty without a merge position)."""
    vr = rec.vehicle("VR")
    row = int(np.searchsorted(log.t[: log.n_recorded], rec.t0 - 1e-9))
    if not (math.isfinite(rec.merge_x) and math.isfinite(rec.vr_duration)) or vr < 0:
        return []
    speed = float(log.v[min(row, log.n_recorded - 1), vr])
    if not math.isfinite(speed) or speed <= 0.0:
        return []
    x0, xf = rec.merge_x, rec.merge_x + speed * rec.vr_duration
    y0, yf = (float(lane_centre(int(lane), width)) for lane in (Lane.RAMP, Lane.MAIN_1))
    xs = np.linspace(x0, xf, MERGE_PATH_POINTS)
    ys = lateral_offset(xs, x0, xf, y0, yf)[0]
    return np.round(np.column_stack([xs, ys]), 3).tolist()


def _commanded(span: PlanSpan, log: SimulationLog) -> list[tuple[int, str, float, float, str]]:
    """(vehicle, role, from, to, what) of the vehicles the live plan commands."""
    rec, out = span.record, []
    vr, vmc, vnr = rec.vehicle("VR"), rec.vehicle("VMC"), rec.vehicle("VNR")
    released = span.fallback_t if math.isfinite(span.fallback_t) else span.end
    lateral = rec.mode == "lateral"
    if vr >= 0 and log.kind[vr] == Kind.CAV and math.isfinite(rec.merge_x):
        out.append((vr, "VR", span.start, released, "follows the plan (VV0, planned merge)"))
    if vmc >= 0 and rec.mode != "none":
        what = "changes to lane 2" if lateral else "follows VV1"
        out.append((vmc, "VMC", span.start, released if lateral else span.end, what))
    if vnr >= 0 and rec.vv2 is not None:
        stop = min(rec.t0 + rec.horizon, released if lateral else span.end)
        out.append((vnr, "VNR", span.start, stop, "follows VV2"))
    return [c for c in out if c[3] > c[2]]


def _roles(log: SimulationLog, spans: list[PlanSpan]) -> list[tuple[int, int, float, float, int]]:
    """(vehicle, role index, from, to, plan) of the key roles, in order of their start (a
    later entry overrides an earlier one for the same vehicle): each key group from the VR's
    entry into the control zone (plan -1), each plan's group from its decision (its index),
    until the VR is planned anew or leaves the road; before them a stalled vehicle
    (:mod:`hcomc.sim.stalled`) as the role after the key roles (:data:`ROLE_NAMES`), all
    run."""
    t_last = float(log.t[log.n_recorded - 1]) if log.n_recorded else 0.0
    events = log.events
    groups = [(float(g["t"]), -1, {r: int(g.get(r, -1)) for r in KEY_ROLES})
              for g in log.meta.get("key_groups") or []]  # fmt: skip
    groups += [(s.start, s.index, dict(s.record.group)) for s in spans]
    groups.sort(key=lambda entry: entry[0])  # stable: a key group before a plan made with it
    out = []
    for t0, plan, group in groups:
        vr = group.get("VR", -1)
        if vr < 0:
            continue
        later = [t for t, _, g in groups if g.get("VR") == vr and t > t0]
        end = min(min(later, default=math.inf), _first_after(events, EventKind.EXIT, vr, t0))
        end = end if math.isfinite(end) else t_last
        for role_index, role in enumerate(KEY_ROLES):
            k = group.get(role, -1)
            if k >= 0:
                out.append((k, role_index, t0, end, plan))
    t_first = float(log.t[0]) if log.n_recorded else 0.0
    stalled = [(int(i), len(KEY_ROLES), t_first, t_last, -1) for i in log.meta.get("stalled", [])]
    return stalled + out


def timeline_events(log: SimulationLog) -> dict[str, Any]:
    """The events the timeline marks, as columns (every kind but insertions and exits), and
    each VR's entry into the control zone (its key group)."""
    ev = log.events
    ev = ev[~np.isin(ev["kind"], [int(k) for k in _HIDDEN_EVENTS])]
    entries = log.meta.get("key_groups") or []
    return {
        "names": {int(k): k.name for k in EventKind},
        "t": ev["t"].tolist(),
        "kind": ev["kind"].astype(int).tolist(),
        "vehicle": ev["vehicle"].astype(int).tolist(),
        "other": ev["other"].astype(int).tolist(),
        "value": [v if math.isfinite(v) else None for v in ev["value"].tolist()],
        "zone_t": [float(g["t"]) for g in entries],
        "zone_vr": [int(g["VR"]) for g in entries],
    }


def json_ready(value: Any) -> Any:
    """``value`` with non-finite floats as None (JSON has no NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    return value


def decisions_json(log: SimulationLog, lane_width: float) -> dict[str, Any]:
    """Plans (each record with its live interval, virtual vehicles and merge path), key
    roles, commanded vehicles and timeline events of ``log``, JSON-ready."""
    times = np.asarray(log.t[: log.n_recorded], dtype=np.float64)
    spans = plan_spans(log)
    plans = []
    for s in spans:
        entry = s.record.to_json()
        entry.update(index=s.index, start=s.start, end=s.end, ended=s.ended,
                     fallback_t=s.fallback_t, ghosts=_ghosts(s, times, log, lane_width),
                     merge_path=_merge_path(s.record, log, lane_width))  # fmt: skip
        plans.append(entry)
    commanded = [c for s in spans for c in _commanded(s, log)]
    roles = _roles(log, spans)
    return json_ready({
        "plans": plans,
        "roles": {"vehicle": [r[0] for r in roles], "role": [r[1] for r in roles],
                  "t0": [r[2] for r in roles], "t1": [r[3] for r in roles],
                  "plan": [r[4] for r in roles], "names": list(ROLE_NAMES)},
        "commanded": {"vehicle": [c[0] for c in commanded], "role": [c[1] for c in commanded],
                      "t0": [c[2] for c in commanded], "t1": [c[3] for c in commanded],
                      "what": [c[4] for c in commanded]},
        "events": timeline_events(log),
    })  # fmt: skip


def _merge_middle(log: SimulationLog) -> float:
    """The middle of the first ramp vehicle's merge, from its lane change's start to its
    MERGE event [s]; NaN if it did not merge."""
    groups = log.meta.get("key_groups") or []
    if not groups:
        return math.nan
    vr, t_zone = int(groups[0]["VR"]), float(groups[0]["t"])
    merge = _first_after(log.events, EventKind.MERGE, vr, t_zone)
    start = _first_after(log.events, EventKind.LANE_CHANGE_START, vr, t_zone)
    return 0.5 * (start + merge) if math.isfinite(merge) else math.nan


def moment_of_interest(logs: Sequence[SimulationLog]) -> float:
    """A time worth showing first [s]: the middle of the earliest of the runs' first merges
    (:func:`_merge_middle`); without one, the first run's first entry into the control
    zone, or the middle of that run."""
    middles = [m for m in map(_merge_middle, logs) if math.isfinite(m)]
    if middles:
        return min(middles)
    groups = logs[0].meta.get("key_groups") or []
    t = logs[0].t[: logs[0].n_recorded]
    return float(groups[0]["t"]) if groups else float(0.5 * (t[0] + t[-1]))
