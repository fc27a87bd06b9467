"""The on-ramp as a traffic engineer measures it: who entered, who merged, how long they stood,
how long the queue grew.

A *ramp vehicle* is one inserted at the ramp's start (``road.ramp_start``). It *merged* when
the log has its MERGE event. It *stands* while it is on the ramp or acceleration lane (lane
0) slower than :data:`STOPPED` m/s; the *queue* at a logged row is the number of ramp
vehicles standing then (a stalled vehicle, :mod:`hcomc.sim.stalled`, is none). Times are
over the logged (measured) rows only; a vehicle that entered in the warm-up counts with its
measured part.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from hcomc.road import Lane
from hcomc.sim.log import EventKind, SimulationLog

__all__ = ["RAMP_COLUMNS", "STOPPED", "ramp_summary", "ramp_vehicles"]

STOPPED = 0.5
"""Speed below which a vehicle on the ramp counts as standing [m/s] (a stop-and-go queue
creeps; 0.5 m/s is below any IDM crawl that still makes progress worth the name)."""

RAMP_COLUMNS = ("vehicle", "t_in", "merged", "t_merge", "standing_s")
"""Columns of :func:`ramp_vehicles`."""

_AT_START = 1e-6  # [m]


def _ramp_ids(log: SimulationLog) -> tuple[np.ndarray, np.ndarray]:
    start = float(log.meta["config"]["road"]["ramp_start"])
    ins = log.events_of(EventKind.INSERTION)
    on_ramp = np.abs(ins["x"] - start) <= _AT_START
    return ins["vehicle"][on_ramp].astype(np.int64), ins["t"][on_ramp].astype(np.float64)


def _standing(log: SimulationLog) -> tuple[pd.Series, np.ndarray]:
    """Seconds each vehicle stood on lane 0, and the number standing per logged row."""
    cells = log.long_columns()
    frame = pd.DataFrame({k: cells[k] for k in ("step", "vehicle", "v", "lane")})
    stalled = np.asarray(log.meta.get("stalled", []), dtype=np.int64)  # no ramp vehicles
    standing = frame[(frame["lane"] == Lane.RAMP) & (frame["v"] < STOPPED)
                     & ~frame["vehicle"].isin(stalled)]  # fmt: skip
    per_vehicle = standing.groupby("vehicle").size() * log.dt
    rows = np.zeros(log.t.size, dtype=np.int64)
    np.add.at(rows, standing["step"].to_numpy(np.int64), 1)
    return per_vehicle, rows


def ramp_vehicles(log: SimulationLog) -> pd.DataFrame:
    """One row per ramp vehicle of ``log`` (module docstring), in the order they entered;
    columns :data:`RAMP_COLUMNS`."""
    return _table(log, _standing(log)[0])


def _table(log: SimulationLog, stood: pd.Series) -> pd.DataFrame:
    """:func:`ramp_vehicles` with each vehicle's seconds standing already counted."""
    ids, t_in = _ramp_ids(log)
    merges = log.events_of(EventKind.MERGE)
    merged_at = dict(zip(merges["vehicle"].tolist(), merges["t"].tolist(), strict=True))
    return pd.DataFrame(
        {
            "vehicle": ids,
            "t_in": t_in,
            "merged": [int(i) in merged_at for i in ids],
            "t_merge": [merged_at.get(int(i), np.nan) for i in ids],
            "standing_s": [float(stood.get(int(i), 0.0)) for i in ids],
        },
        columns=list(RAMP_COLUMNS),
    )


def ramp_summary(log: SimulationLog) -> dict[str, float | int | None]:
    """``vehicles`` and ``merged`` (counts), ``merges_per_hour`` over the measured time,
    ``mean_standing_s`` and ``max_standing_s`` [s] of the ramp vehicles, ``max_queue`` and
    ``mean_queue`` (vehicles standing on the ramp, over the logged rows)."""
    stood, queue = _standing(log)
    table = _table(log, stood)
    recorded = queue[: log.n_recorded or queue.size]
    merged = table[table["merged"] & (table["t_merge"] >= 0)]
    duration = float(log.dt * recorded.size)
    has = len(table) > 0
    return {
        "vehicles": len(table),
        "merged": int(table["merged"].sum()),
        "merges_per_hour": 3600.0 * len(merged) / duration if duration > 0 else None,
        "mean_standing_s": float(table["standing_s"].mean()) if has else None,
        "max_standing_s": float(table["standing_s"].max()) if has else None,
        "max_queue": int(recorded.max()) if recorded.size else 0,
        "mean_queue": float(recorded.mean()) if recorded.size else 0.0,
    }
