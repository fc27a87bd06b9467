"""A corridor run as the replay page plays it: its sampled trajectories in the page's
arrays, its road, and its merge events on the timeline and in a table.

The run is a :class:`~hcomc.metrics.corridor.record.CorridorRecord` (its ``--out`` directory
read back, or a run in memory). Its samples carry no lateral position: a vehicle is drawn
on its logged lane's centre line and changes lane in one jump (where it crosses the line),
so each sample is placed by :func:`hcomc.corridor.layout.code_poses` (heading 0 on the
mainline, the ramp's slope on a ramp road) and the page moves a vehicle along its lane
between samples but never across lanes (``lane_jumps``): interpolating there would invent a
motion the engine did not make. A vehicle's length and width are those of its class
(``trips.csv``'s ``vclass`` in the corridor's ``[vehicles]``).

Row k of the page is sample step ``s0 + k`` (the first sampled step ``s0``), at the time the
samples record. ``x`` is the engine's position along the mainline, continued along ramp
roads, as ``trajectories.csv`` has it (float32: 1 mm on a 10 km road); ``dx`` is where the
vehicle is drawn minus ``x`` (non-zero on a sloping ramp road). The merge events are
``merges.csv``'s: each ramp vehicle's entry into its control zone with its key vehicles
then (their roles shown until the event's window ends: ``[merges] window_after`` after the
merge, when VR leaves the road or at the end), its merge, and the collisions of
``collisions.csv``. The engine's plans are not recorded, so the page shows none.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from hcomc.corridor.layout import code_poses
from hcomc.metrics.corridor.record import CorridorRecord, Trajectories
from hcomc.road import KEY_ROLES, Kind
from hcomc.sim.log import EventKind
from hcomc.sim.stalled import stalled_faults
from hcomc.viz.replay.corridor_road import corridor_road_shapes
from hcomc.viz.replay.decisions import ROLE_NAMES, json_ready
from hcomc.viz.replay.pack import STEPS, Columns, pack_fleet, pack_samples, partition

__all__ = ["SHIFT_STEP", "corridor_moment", "corridor_run_json", "merge_table"]

SHIFT_STEP = 1e-3
"""Nominal quantisation step of the ``dx`` cell array [m]."""

_KEYS = [role.lower() for role in KEY_ROLES[1:]]  # merges.csv's columns of VMC .. VNR


def _layout(samples: Trajectories, n_vehicles: int) -> tuple[Columns, np.ndarray, int]:
    """The vehicles' columns, each sample's row and the first sampled step."""
    s0 = int(samples.step.min())
    first, last = np.full(n_vehicles, -1), np.full(n_vehicles, -1)
    first[samples.ids] = samples.step[samples.start] - s0
    last[samples.ids] = samples.step[samples.stop - 1] - s0
    return partition(first, last), samples.step - s0, s0


def _stalled(record: CorridorRecord) -> np.ndarray:
    """The ids of the run's stalled vehicles (:mod:`hcomc.sim.stalled`): after every trip,
    one per ``stalled_vehicle`` entry of its ``[[faults]]``."""
    count = len(stalled_faults(record.corridor.faults))
    return len(record.trips) + np.arange(count, dtype=np.int64)


def _fleet(record: CorridorRecord, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kind, length and width [m] of vehicles 0 .. n - 1 (from their class; a stalled
    vehicle an HDV of the engine's size)."""
    from hcomc.sim.corridor_scene import corridor_config

    kind, length, width = np.zeros(n, dtype=np.int8), np.full(n, np.nan), np.full(n, np.nan)
    trips = record.trips
    classes = record.vehicle_classes()
    ids = trips.index.to_numpy(dtype=np.int64)
    kind[ids] = np.where(trips["cav"].to_numpy(dtype=bool), int(Kind.CAV), int(Kind.HDV))
    length[ids] = classes.map(lambda c: c.length).to_numpy(dtype=np.float64)
    width[ids] = classes.map(lambda c: c.width).to_numpy(dtype=np.float64)
    stalled = _stalled(record)
    stalled = stalled[stalled < n]
    if stalled.size:
        road = corridor_config(record.corridor).road
        kind[stalled], length[stalled], width[stalled] = Kind.HDV, road.vehicle_length, (
            road.vehicle_width)  # fmt: skip
    return kind, length, width


def merge_table(record: CorridorRecord) -> list[dict[str, Any]]:
    """The merge events of ``merges.csv`` by control-zone entry, JSON-ready (ids as int,
    NaN and infinities as None)."""
    out = []
    for row in record.merges.sort_values("zone_time", kind="stable").to_dict("records"):
        entry = {"vr": int(row["vr"]), "ramp": str(row["ramp"]), "cav": bool(row["cav"]),
                 "zone_time": float(row["zone_time"]), "merged": bool(row["merged"])}  # fmt: skip
        entry.update({key: int(row[key]) for key in _KEYS})
        for key in ("merge_time", "time_to_merge", "merge_position", "min_ttc", "max_drac",
                    "max_decel"):  # fmt: skip
            entry[key] = float(row[key])
        entry["plans"] = int(row["plans"]) if pd.notna(row["plans"]) else 0
        entry["final_mode"] = "" if pd.isna(row["final_mode"]) else str(row["final_mode"])
        entry["fallback"] = bool(row["fallback"]) if pd.notna(row["fallback"]) else False
        out.append(entry)
    return list(json_ready(out))


def _keys_text(event: dict[str, Any]) -> str:
    keys = [f"{role} {event[role.lower()]}" for role in KEY_ROLES[1:] if event[role.lower()] >= 0]
    return ", ".join(keys) if keys else "no key vehicles"


def _timeline(record: CorridorRecord, merges: list[dict[str, Any]], last_seen: np.ndarray,
              t_end: float) -> tuple[dict[str, Any], dict[str, Any]]:  # fmt: skip
    """The timeline's events (merges and collisions, control-zone entries) and the key
    roles of each merge event (module docstring)."""
    window = record.corridor.merges.window_after
    marks: list[tuple[float, int, int, int, str]] = []
    roles: list[tuple[float, int, int, float, int]] = []  # (from, vehicle, role, to, VR)
    zone_text = []
    for e in merges:
        vr, ramp = e["vr"], f"{e['ramp']}{', CAV' if e['cav'] else ''}"
        merged = e["merged"] and e["merge_time"] is not None
        outcome = f"merged at {e['merge_time']:.1f} s" if merged else "did not merge"
        zone_text.append(f"CONTROL ZONE ENTRY · VR {vr} ({ramp}) · {_keys_text(e)} · {outcome}")
        if merged:
            where = e["merge_position"]
            text = (f"MERGE · VR {vr} ({ramp}) · {where:.1f} m past the start of the "
                    f"acceleration lane, {e['time_to_merge']:.1f} s after its control-zone "
                    f"entry · {_keys_text(e)}")  # fmt: skip
            marks.append((e["merge_time"], int(EventKind.MERGE), vr, e["vmc"], text))
        seen = last_seen[vr] if vr < last_seen.size and math.isfinite(last_seen[vr]) else t_end
        end = min(e["merge_time"] + window if merged else math.inf, seen, t_end)
        for k, role in enumerate(KEY_ROLES):
            vehicle = vr if k == 0 else e[role.lower()]
            if vehicle >= 0:
                roles.append((e["zone_time"], vehicle, k, max(end, e["zone_time"]), vr))
    for c in record.collisions.to_dict("records"):
        one, other = int(c["vehicle"]), int(c["other"])
        text = f"COLLISION · vehicles {one} and {other} at x = {c['x']:.1f} m"
        marks.append((float(c["t"]), int(EventKind.COLLISION), one, other, text))
    marks.sort(key=lambda m: m[0])
    roles.sort(key=lambda r: r[0])
    stalled = _stalled(record)  # labelled all run, before the key roles
    roles = [(0.0, int(i), len(KEY_ROLES), t_end, -1) for i in stalled.tolist()] + roles
    events: dict[str, Any] = {
        "names": {int(k): k.name for k in EventKind},
        "t": [m[0] for m in marks], "kind": [m[1] for m in marks],
        "vehicle": [m[2] for m in marks], "other": [m[3] for m in marks],
        "text": [m[4] for m in marks],
        "zone_t": [e["zone_time"] for e in merges], "zone_vr": [e["vr"] for e in merges],
        "zone_text": zone_text,
    }  # fmt: skip
    table: dict[str, Any] = {
        "vehicle": [r[1] for r in roles], "role": [r[2] for r in roles],
        "t0": [r[0] for r in roles], "t1": [r[3] for r in roles], "plan": [-1] * len(roles),
        "vr": [r[4] for r in roles], "names": list(ROLE_NAMES),
    }  # fmt: skip
    return events, table


def corridor_run_json(record: CorridorRecord, title: str) -> dict[str, Any]:
    """Everything the page needs of one corridor run, JSON-ready (module docstring).

    Raises
    ------
    ValueError
        If the run has no trajectories (with how to record them) or a vehicle of an
        unknown class.
    """
    samples = record.require_trajectories()
    n = max(len(record.trips), int(samples.ids.max()) + 1)
    layout, rows, s0 = _layout(samples, n)
    n_rows = int(rows.max()) + 1
    t = (s0 + np.arange(n_rows)) * samples.interval
    t[rows] = samples.t
    px, py, heading = code_poses(record.corridor.road, samples.x, samples.code)
    values = {"x": samples.x, "lane": samples.lane, "y": py, "heading": heading, "v": samples.v,
              "a": samples.a, "dx": px - samples.x}  # fmt: skip
    steps = {**STEPS, "dx": SHIFT_STEP}
    arrays = pack_samples(t, layout, rows, layout.column[samples.vehicle], values, steps)
    kind, length, width = _fleet(record, n)
    arrays.update(pack_fleet(kind, length, width, layout))
    shapes = corridor_road_shapes(record.corridor).to_json()
    car = record.corridor.vehicles.get("car") or next(iter(record.corridor.vehicles.values()))
    shapes.update(vehicle_length=car.length, vehicle_width=car.width)
    last_seen = np.full(n, np.nan)
    last_seen[samples.ids] = samples.t[samples.stop - 1]
    merges = merge_table(record)
    events, roles = _timeline(record, merges, last_seen, float(t[-1]))
    note = (f"corridor run, sampled every {samples.interval:g} s: vehicles drawn on lane "
            "centre lines, a lane change as a jump")  # fmt: skip
    return json_ready({
        "title": title, "seed": record.seed, "dt": samples.interval, "rows": n_rows,
        "columns": max(layout.n_columns, 1), "vehicles": n, "road": shapes, "arrays": arrays,
        "plans": [], "roles": roles,
        "commanded": {"vehicle": [], "role": [], "t0": [], "t1": [], "what": []},
        "events": events, "merges": merges, "lane_jumps": True, "note": note,
    })  # fmt: skip


def corridor_moment(records: Sequence[CorridorRecord]) -> float:
    """A time worth showing first [s]: the earliest merge of the runs, at the middle of its
    lane change (where the engine moves VR onto the mainline); without one, the first run's
    first control-zone entry, or the middle of its samples."""
    middles = []
    for record in records:
        merged = record.merges[record.merges["merged"].astype(bool)]
        if len(merged):
            half = 0.5 * record.corridor.corridor.lane_change_duration
            middles.append(float(merged["merge_time"].min()) - half)
    if middles:
        return min(middles)
    first = records[0]
    if len(first.merges):
        return float(first.merges["zone_time"].min())
    t = first.require_trajectories().t
    return float(0.5 * (t.min() + t.max()))
