"""Merge events of a corridor run as a table, and their summary per on-ramp.

One row per ramp vehicle (VR) that reached its on-ramp's control zone: its key vehicles
then (paper Section II-A, found by the engine in every run, with or without a controller,
so that runs compare the same vehicles), whether and where it merged, the surrogate safety
over the event's window, and with a controller what was decided for it. A VR that never
merged is a row with ``merged`` False, never a gap in the table.

The event's window runs from VR's entry into the control zone to ``window_after`` seconds
after its merge (to the end of the log when it did not merge). Over it, each of VR, VMC,
VMR and VNR is measured against its leader in its logged lane, at every logged row in
which it closes in at :data:`~hcomc.safety.surrogate.CLOSING_SPEED` or more (as
:mod:`hcomc.metrics.surrogate` on the paper's scene): the least time to collision (gap /
closing speed), the largest deceleration rate to avoid a crash (closing speed^2 / 2 gap),
the hardest braking of the four, and VMC's lowest speed.
"""

from __future__ import annotations

from collections import defaultdict
from typing import Any

import numpy as np
import pandas as pd

from hcomc.corridor import Corridor
from hcomc.interface import MergePlan
from hcomc.metrics.cell_passes import closing_cells
from hcomc.metrics.corridor.trips import first_event
from hcomc.metrics.detectors import VehicleRows, column_takers
from hcomc.road import KEY_ROLES, VMC, VMR, VNR, VR
from hcomc.safety.surrogate import CLOSING_SPEED
from hcomc.sim.log import EventKind, SimulationLog

__all__ = ["EVENT_COLUMNS", "closing_in", "merge_events", "merge_summary"]

EVENT_COLUMNS = (
    "vr", "ramp", "cav", "zone_time", *[r.lower() for r in KEY_ROLES[1:]], "vmc_cav", "merged",
    "merge_time", "time_to_merge", "merge_position", "min_ttc", "max_drac", "max_decel",
    "vmc_speed_drop", "plans", "final_mode", "fallback", "decision_ms",
)  # fmt: skip
"""Columns of :func:`merge_events` (times [s], positions [m] past the start of the
acceleration lane, speeds [m/s], decelerations [m/s^2]; ``min_ttc`` inf when nobody closed
in on a leader)."""

_DTYPES = {
    **dict.fromkeys(EVENT_COLUMNS, np.float64),
    **dict.fromkeys(("vr", *[r.lower() for r in KEY_ROLES[1:]], "plans"), np.int64),
    **dict.fromkeys(("cav", "vmc_cav", "merged", "fallback"), np.bool_),
    "ramp": object, "final_mode": object,
}  # fmt: skip
"""The columns' types (an empty table has them too)."""

_WATCHED = (VR, VMC, VMR, VNR)


def _decided(decisions: list[MergePlan]) -> dict[int, dict[str, Any]]:
    def empty() -> dict[str, Any]:
        return {"plans": 0, "final_mode": "", "fallback": False, "decision_ms": 0.0}

    out: dict[int, dict[str, Any]] = defaultdict(empty)
    for plan in decisions:
        row = out[plan.group.vr]
        row["plans"] += 1
        row["final_mode"] = plan.mode.name.lower()
        row["fallback"] |= plan.fallback
        row["decision_ms"] += plan.decision_ms
    return out


def closing_in(log: SimulationLog, rows: VehicleRows) -> tuple[np.ndarray, np.ndarray]:
    """(T, S) time to collision [s] and deceleration rate to avoid a crash [m/s^2] of every
    stored cell's vehicle against its leader in its logged lane, where it closes in at
    :data:`CLOSING_SPEED` or more (inf and 0 elsewhere):
    :func:`~hcomc.metrics.cell_passes.closing_cells` over the
    log's cells, each column's vehicle taken from ``rows`` (its length)."""
    cells = log.cells
    length = np.zeros(log.n_vehicles, dtype=np.float32)
    length[rows.vehicle] = rows.length
    first, takers = column_takers(log)
    return closing_cells(cells["active"], cells["x"], cells["v"], cells["lane"], length,
                          log.slot, first, takers, CLOSING_SPEED)  # fmt: skip


def _window_safety(
    log: SimulationLog, closing: tuple[np.ndarray, np.ndarray], group: np.ndarray, r0: int,
    r1: int,
) -> tuple[float, ...]:  # fmt: skip
    """(least TTC, largest DRAC, hardest braking, VMC's speed at r0 minus its lowest) of the
    watched key vehicles over rows [r0, r1) (module docstring)."""
    ttc_cells, drac_cells = closing
    cells = log.cells
    ttc, drac, decel, drop = np.inf, 0.0, 0.0, 0.0
    for role in _WATCHED:
        i = int(group[role])
        if i < 0 or log.slot[i] < 0:
            continue
        s = int(log.slot[i])
        lo, hi = max(r0, int(log.span[i, 0])), min(r1, int(log.span[i, 1]), log.n_recorded)
        on = np.flatnonzero(cells["active"][lo:hi, s]) + lo
        if on.size == 0:
            continue
        ttc = min(ttc, float(ttc_cells[on, s].min()))
        drac = max(drac, float(drac_cells[on, s].max()))
        decel = max(decel, float(np.max(-cells["a"][on, s])))
        if role == VMC:
            speed = cells["v"][on, s]
            drop = float(speed[0] - speed.min())
    return ttc, drac, decel, drop


def merge_events(
    c: Corridor, log: SimulationLog, rows: VehicleRows, origin_of: np.ndarray, cav: np.ndarray,
    decisions: list[MergePlan],
) -> pd.DataFrame:  # fmt: skip
    """The merge events of a finished run (module docstring); ``rows`` are its log's
    :func:`~hcomc.metrics.detectors.vehicle_rows`, ``origin_of`` names each vehicle's
    origin, ``cav`` says whether it is a CAV."""
    groups = log.meta.get("key_groups") or []
    ramp_x = {r.id: r.x for r in c.road.on_ramps}
    merged_t, merged_x = first_event(log, EventKind.MERGE, cav.size)
    decided = _decided(decisions)
    closing = closing_in(log, rows) if groups else (np.empty((0, 0)), np.empty((0, 0)))
    out = []
    for entry in groups:
        group = np.array([int(entry[role]) for role in KEY_ROLES])
        vr, t0 = int(group[VR]), float(entry["t"])
        t1 = merged_t[vr] + c.merges.window_after if np.isfinite(merged_t[vr]) else np.inf
        r0 = int(np.searchsorted(log.t[: log.n_recorded], t0 - 1e-9))
        r1 = int(np.searchsorted(log.t[: log.n_recorded], t1 + 1e-9, side="right"))
        ttc, drac, decel, drop = _window_safety(log, closing, group, r0, max(r1, r0 + 1))
        vmc = int(group[VMC])
        out.append({
            "vr": vr, "ramp": str(origin_of[vr]), "cav": bool(cav[vr]), "zone_time": t0,
            **{role.lower(): int(group[k]) for k, role in enumerate(KEY_ROLES) if k > 0},
            "vmc_cav": bool(cav[vmc]) if vmc >= 0 else False,
            "merged": bool(np.isfinite(merged_t[vr])), "merge_time": merged_t[vr],
            "time_to_merge": merged_t[vr] - t0,
            "merge_position": merged_x[vr] - ramp_x[str(origin_of[vr])],
            "min_ttc": ttc, "max_drac": drac, "max_decel": decel, "vmc_speed_drop": drop,
            **decided[vr],
        })  # fmt: skip
    return pd.DataFrame(out, columns=list(EVENT_COLUMNS)).astype(_DTYPES)


def _share(mask: pd.Series) -> float | None:
    return float(mask.mean()) if len(mask) else None


def _quantile(values: pd.Series, q: float) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.quantile(q)) if len(finite) else None


def merge_summary(merges: pd.DataFrame, ramp: str) -> dict[str, Any]:
    """Figures of one on-ramp's merge events: how many, merged share, time from the control
    zone to the merge, surrogate safety (the 5th percentile of the events' least TTC, the
    share of events whose least TTC is under 1.5 s, the largest DRAC and braking), and with
    a controller its plans and fallbacks."""
    rows = merges[merges.ramp == ramp]
    merged = rows[rows.merged.astype(bool)]
    return {
        "events": len(rows),
        "merged_share": _share(rows.merged.astype(bool)),
        "mean_time_to_merge": float(merged.time_to_merge.mean()) if len(merged) else None,
        "min_ttc_p05": _quantile(rows.min_ttc, 0.05),
        "ttc_below_1_5s_share": _share(rows.min_ttc < 1.5),
        "max_drac": float(rows.max_drac.max()) if len(rows) else None,
        "max_decel": float(rows.max_decel.max()) if len(rows) else None,
        "mean_vmc_speed_drop": float(rows.vmc_speed_drop.mean()) if len(rows) else None,
        "plans": int(rows.plans.sum()),
        "fallbacks": int(rows.fallback.astype(bool).sum()),
    }
