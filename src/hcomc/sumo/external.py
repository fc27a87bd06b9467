"""Our merge metrics for trajectories from elsewhere (SUMO FCD, highD-style files).

A trajectory file has positions but no events, so the events the metrics need are derived from
the trajectories: insertion and exit (first and last row of a vehicle), lane-change end and,
for a vehicle that started on the ramp, the merge (the first row in lane 1 once its lateral
offset from the lane-1 centre is below 0.1 % of a lane width, i.e. the lateral motion is done),
collisions (the oriented-rectangle test of Eq. 7 between every pair of vehicles whose extents
overlap in the row; one event when an overlap starts). The key vehicles of each ramp vehicle
are found as our engine does (:func:`hcomc.control.key_group.find_key_vehicles`) in the
first row in which it is on the ramp inside the control zone, unless they are given.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.control.key_group import find_key_vehicles
from hcomc.equations.collision import vehicles_collide
from hcomc.interface import Fleet, MergeGroup, Ramp, TrafficView
from hcomc.metrics import compute_metrics, merge_window
from hcomc.road import Lane, lane_centre
from hcomc.sim.log import EventKind, SimulationLog

__all__ = [
    "MergeScore",
    "collision_events",
    "derive_events",
    "key_group_at_entry",
    "ramp_vehicles",
    "score_merges",
]

_SETTLED = 1e-3  # lateral offset [lane widths] below which a lane change is complete


def derive_events(log: SimulationLog, config: ScenarioConfig) -> None:
    """Add insertion, exit, lane-change start and end, merge and collision events to ``log``.

    A lane change is where the logged lane switches (the middle of the manoeuvre); it starts
    at the first row after the last one in which the vehicle sat on its origin lane's centre
    (within :data:`_SETTLED` lane widths) and ends at the first row in which it sits on the
    target lane's centre, as the engine's LANE_CHANGE_START and LANE_CHANGE_END events
    bracket the manoeuvre (the surrogate measures count a changing vehicle in both lanes
    between them)."""
    n_rows = log.n_recorded
    width = config.road.lane_width
    for i in np.flatnonzero(log.active[:n_rows].any(axis=0)).tolist():
        rows = np.flatnonzero(log.active[:n_rows, i])
        first, last = int(rows[0]), int(rows[-1])
        log.add_event(log.t[first], EventKind.INSERTION, i, x=float(log.x[first, i]))
        if last < n_rows - 1:
            log.add_event(log.t[last], EventKind.EXIT, i, x=float(log.x[last, i]))
        lanes = log.lane[rows, i].astype(np.int64)
        y = log.y[rows, i].astype(np.float64)
        for k in np.flatnonzero(np.diff(lanes)).tolist():
            origin, target = int(lanes[k]), int(lanes[k + 1])
            on_origin = np.flatnonzero(np.abs(y[: k + 1] - lane_centre(Lane(origin), width))
                                       < _SETTLED * width)  # fmt: skip
            s = int(on_origin[-1]) + 1 if on_origin.size else 0
            on_target = np.flatnonzero(np.abs(y[k + 1 :] - lane_centre(Lane(target), width))
                                       < _SETTLED * width)  # fmt: skip
            e = k + 1 + int(on_target[0]) if on_target.size else len(rows) - 1
            for r, kind in ((int(rows[min(s, k + 1)]), EventKind.LANE_CHANGE_START),
                            (int(rows[e]), EventKind.LANE_CHANGE_END)):  # fmt: skip
                log.add_event(log.t[r], kind, i, x=float(log.x[r, i]), value=target)
        if lanes[0] == Lane.RAMP:
            offset = np.abs(y - lane_centre(Lane.MAIN_1, width)) / width
            merged = (lanes == Lane.MAIN_1) & (offset < _SETTLED)
            if merged.any():
                r = int(rows[int(np.argmax(merged))])
                log.add_event(log.t[r], EventKind.MERGE, i, x=float(log.x[r, i]))
    for t, kind, i, j, x in collision_events(log):
        log.add_event(t, kind, i, other=j, x=x)


def collision_events(log: SimulationLog) -> list[tuple[float, EventKind, int, int, float]]:
    """``(t, COLLISION, i, j, x_i)`` when the rectangles of i and j start to overlap (Eq. 7)."""
    events: list[tuple[float, EventKind, int, int, float]] = []
    overlapping: set[tuple[int, int]] = set()
    for k in range(log.n_recorded):
        ids = np.flatnonzero(log.active[k])
        x = log.x[k, ids].astype(np.float64)
        reach = log.length[ids] + log.width[ids]
        a, b = np.triu_indices(ids.size, 1)
        near = np.abs(x[a] - x[b]) < np.maximum(reach[a], reach[b])
        a, b = ids[a[near]], ids[b[near]]
        now: set[tuple[int, int]] = set()
        if a.size:
            x_k, y_k = log.x[k].astype(np.float64), log.y[k].astype(np.float64)
            h_k, length, width = log.heading[k].astype(np.float64), log.length, log.width
            hit = vehicles_collide(
                x_k[a], y_k[a], h_k[a], length[a], width[a],
                x_k[b], y_k[b], h_k[b], length[b], width[b],
            )  # fmt: skip
            now = set(zip(a[hit].tolist(), b[hit].tolist(), strict=True))
        for i, j in sorted(now - overlapping):
            events.append((float(log.t[k]), EventKind.COLLISION, i, j, float(log.x[k, i])))
        overlapping = now
    return events


def ramp_vehicles(log: SimulationLog) -> list[int]:
    """Slots of the vehicles whose first logged lane is the ramp, by first appearance."""
    n_rows = log.n_recorded
    seen = log.active[:n_rows].any(axis=0)
    first = np.argmax(log.active[:n_rows], axis=0)
    on_ramp = seen & (log.lane[first, np.arange(log.n_vehicles)] == Lane.RAMP)
    slots = np.flatnonzero(on_ramp)
    return [int(i) for i in slots[np.argsort(first[slots], kind="stable")]]


def key_group_at_entry(log: SimulationLog, config: ScenarioConfig, vr: int) -> MergeGroup:
    """VR's key vehicles in the first row where it is on the ramp inside the control zone."""
    n_rows = log.n_recorded
    inside = (
        log.active[:n_rows, vr]
        & (log.lane[:n_rows, vr] == Lane.RAMP)
        & (log.x[:n_rows, vr] >= config.road.control_zone_start)
    )
    if not inside.any():
        return MergeGroup(vr=vr)
    k = int(np.argmax(inside))
    kind = log.kind.astype(np.int64)
    view = TrafficView(
        t=float(log.t[k]), x=np.nan_to_num(log.x[k].astype(np.float64), nan=-np.inf),
        v=np.nan_to_num(log.v[k].astype(np.float64)), a=np.nan_to_num(log.a[k].astype(np.float64)),
        lane=log.lane[k].astype(np.int64), active=log.active[k].copy(),
        changing=np.zeros(log.n_vehicles, dtype=bool),
        fleet=Fleet.build(config, kind, np.zeros(kind.size, dtype=bool)), config=config,
        ramp=Ramp.of(config.road),
    )  # fmt: skip
    return find_key_vehicles(view, vr)


@dataclass(frozen=True)
class MergeScore:
    """Metrics of one ramp vehicle's merge."""

    group: MergeGroup
    metrics: dict[str, float | bool | str]


def aligned_reference(
    reference: SimulationLog,
    reference_ids: Mapping[str, int],
    ids: Mapping[str, int],
    n_vehicles: int,
) -> SimulationLog:
    """The undisturbed run's log with its vehicle columns in the factual file's slots.

    Both files come from the same scenario, so vehicles are matched by their id; a vehicle of
    the factual run that is not in the reference (the ramp vehicle) is never active there.
    Rows must already match (same times).
    """
    n_rows = reference.n_recorded
    fields = ("x", "y", "v", "a", "heading", "lane", "active")
    cols = {name: np.zeros((n_rows, n_vehicles), dtype=getattr(reference, name).dtype)
            for name in fields}  # fmt: skip
    for name in ("x", "y", "v", "a", "heading"):
        cols[name][:] = np.nan
    cols["lane"][:] = -1
    kind = np.zeros(n_vehicles, dtype=np.int64)  # stored as int8 by allocate
    length = np.full(n_vehicles, float(np.nanmax(reference.length, initial=5.0)))
    width = np.full(n_vehicles, float(np.nanmax(reference.width, initial=1.8)))
    for name, slot in ids.items():
        j = reference_ids.get(name)
        if j is None:
            continue
        for field in fields:
            cols[field][:, slot] = getattr(reference, field)[:n_rows, j]
        kind[slot], length[slot], width[slot] = (
            reference.kind[j],
            reference.length[j],
            reference.width[j],
        )
    out = SimulationLog.allocate(n_rows, n_vehicles, dt=reference.dt, kind=kind, length=length,
                                 width=width, meta=dict(reference.meta))  # fmt: skip
    for k in range(n_rows):
        out.record(k, float(reference.t[k]), *(cols[f][k] for f in fields))
    return out


def score_merges(
    log: SimulationLog,
    config: ScenarioConfig,
    groups: Mapping[int, Mapping[str, int]] | None = None,
    reference: SimulationLog | None = None,
) -> list[MergeScore]:
    """Metrics of every ramp vehicle's merge (or of the given VR -> role -> slot groups).

    A given group may omit roles: the missing ones are found as our engine finds them.
    ``reference`` is the undisturbed run (same scenario without the ramp vehicle, aligned with
    :func:`aligned_reference`); without it the metrics that compare with it (average
    acceleration, stabilisation times, LSRV, fuel) are NaN.
    """
    wanted = groups if groups is not None else {vr: {} for vr in ramp_vehicles(log)}
    scores = []
    for vr, given in wanted.items():
        found = key_group_at_entry(log, config, vr).as_dict()
        roles = {**found, **{k.upper(): int(v) for k, v in given.items()}}
        group = MergeGroup(
            vr=vr, vmc=roles["VMC"], vmf=roles["VMF"], vmr=roles["VMR"], vnf=roles["VNF"],
            vnr=roles["VNR"],
        )  # fmt: skip
        window = merge_window(log, vr, group.as_dict())
        scores.append(MergeScore(group, compute_metrics(log, window, reference=reference)))
    return scores
