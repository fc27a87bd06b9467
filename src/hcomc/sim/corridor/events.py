"""Merge events of a corridor run as a table, and their summary per on-ramp.

One row per ramp vehicle (VR) that reached its on-ramp's control zone: its key vehicles
then (paper Section II-A), whether and where it merged, the surrogate safety over the
event's window (:mod:`hcomc.sim.corridor.plans`), and with a controller what was decided
for it. A VR that never merged is a row with ``merged`` False, never a gap in the table.
"""

from __future__ import annotations

from collections import defaultdict
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from hcomc.corridor import Corridor
from hcomc.road import KEY_ROLES, VMC
from hcomc.sim.corridor.fleet import CorridorFleet
from hcomc.sim.corridor.state import State

if TYPE_CHECKING:
    from hcomc.sim.corridor.control import CorridorControl

__all__ = ["EVENT_COLUMNS", "merge_events", "merge_summary"]

EVENT_COLUMNS = (
    "vr", "ramp", "cav", "zone_time", *[r.lower() for r in KEY_ROLES[1:]], "vmc_cav", "merged",
    "merge_time", "time_to_merge", "merge_position", "min_ttc", "max_drac", "max_decel",
    "vmc_speed_drop", "plans", "final_mode", "fallback", "released", "conflicts",
    "decision_ms",
)  # fmt: skip
"""Columns of :func:`merge_events` (times [s], positions [m] past the start of the
acceleration lane, speeds [m/s], decelerations [m/s^2]; ``min_ttc`` inf when nobody closed
in on a leader)."""


def _decided(control: CorridorControl | None) -> dict[int, dict[str, Any]]:
    def empty() -> dict[str, Any]:
        return {"plans": 0, "final_mode": "", "fallback": False, "conflicts": 0,
                "decision_ms": 0.0}  # fmt: skip

    out: dict[int, dict[str, Any]] = defaultdict(empty)
    for d in control.decisions if control is not None else []:
        row = out[d.plan.group.vr]
        row["plans"] += 1
        row["final_mode"] = d.plan.mode.name.lower()
        row["fallback"] |= d.plan.fallback
        row["conflicts"] += int(d.conflict)
        row["decision_ms"] += d.plan.decision_ms
    return out


def merge_events(c: Corridor, fleet: CorridorFleet, s: State,
                 control: CorridorControl | None) -> pd.DataFrame:  # fmt: skip
    """The merge events of a finished run (module docstring)."""
    vrs = np.flatnonzero(~np.isnan(s.ev_t))
    ramp_x = {r.id: r.x for r in c.road.on_ramps}
    origins = np.array(fleet.origins, dtype=object)[fleet.origin[vrs]]
    group = s.ev_group[vrs]
    vmc = group[:, VMC]
    decided = _decided(control)
    rows = [decided[int(vr)] for vr in vrs] if control is not None else []
    frame = pd.DataFrame(
        {
            "vr": vrs,
            "ramp": origins,
            "cav": fleet.cav[vrs],
            "zone_time": s.ev_t[vrs],
            **{role.lower(): group[:, k] for k, role in enumerate(KEY_ROLES) if k > 0},
            "vmc_cav": np.where(vmc >= 0, fleet.cav[np.maximum(vmc, 0)], False),
            "merged": ~np.isnan(s.merge_t[vrs]),
            "merge_time": s.merge_t[vrs],
            "time_to_merge": s.merge_t[vrs] - s.ev_t[vrs],
            "merge_position": s.merge_x[vrs] - np.array([ramp_x[o] for o in origins]),
            "min_ttc": s.ev_min_ttc[vrs],
            "max_drac": s.ev_max_drac[vrs],
            "max_decel": s.ev_max_decel[vrs],
            "vmc_speed_drop": s.ev_vmc_v[vrs] - s.ev_vmc_min_v[vrs],
            "plans": [r["plans"] for r in rows] if rows else 0,
            "final_mode": [r["final_mode"] for r in rows] if rows else "",
            "fallback": [r["fallback"] for r in rows] if rows else False,
            "released": s.ev_released[vrs],
            "conflicts": [r["conflicts"] for r in rows] if rows else 0,
            "decision_ms": [r["decision_ms"] for r in rows] if rows else 0.0,
        }
    )
    return frame[list(EVENT_COLUMNS)]


def _share(mask: pd.Series) -> float | None:
    return float(mask.mean()) if len(mask) else None


def _quantile(values: pd.Series, q: float) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.quantile(q)) if len(finite) else None


def merge_summary(merges: pd.DataFrame, ramp: str) -> dict[str, Any]:
    """Figures of one on-ramp's merge events: how many, merged share, time from the control
    zone to the merge, surrogate safety (the 5th percentile of the events' least TTC, the
    share of events whose least TTC is under 1.5 s, the largest DRAC and braking), and with
    a controller its plans, fallbacks, released merges and one-live-plan conflicts."""
    rows = merges[merges.ramp == ramp]
    merged = rows[rows.merged]
    return {
        "events": len(rows),
        "merged_share": _share(rows.merged),
        "mean_time_to_merge": float(merged.time_to_merge.mean()) if len(merged) else None,
        "min_ttc_p05": _quantile(rows.min_ttc, 0.05),
        "ttc_below_1_5s_share": _share(rows.min_ttc < 1.5),
        "max_drac": float(rows.max_drac.max()) if len(rows) else None,
        "max_decel": float(rows.max_decel.max()) if len(rows) else None,
        "mean_vmc_speed_drop": float(rows.vmc_speed_drop.mean()) if len(rows) else None,
        "plans": int(rows.plans.sum()),
        "fallbacks": int(rows.fallback.sum()),
        "released": int(rows.released.sum()),
        "conflicts": int(rows.conflicts.sum()),
    }
