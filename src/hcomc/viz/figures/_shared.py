"""Helpers and marker styles shared by the figure modules of :mod:`hcomc.viz.figures`."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib import patheffects

from hcomc.sim.log import EventKind, SimulationLog
from hcomc.viz.common import (
    key_group,
    merge_time,
)

if TYPE_CHECKING:
    from hcomc._typing import FloatArray

_MAIN_LANES = (2, 1)  # top to bottom
_ALL_LANES = (2, 1, 0)
_OUTLINE = [patheffects.Stroke(linewidth=4.2, foreground="black"), patheffects.Normal()]
_LC_START: dict[str, Any] = {
    "marker": "o",
    "markersize": 5,
    "markerfacecolor": "white",
    "markeredgecolor": "k",
}
_LC_END: dict[str, Any] = {
    "marker": "o",
    "markersize": 4,
    "markerfacecolor": "black",
    "markeredgecolor": "k",
}
_MERGE: dict[str, Any] = {
    "marker": "*",
    "markersize": 13,
    "markerfacecolor": "gold",
    "markeredgecolor": "k",
}


def _times(log: SimulationLog) -> FloatArray:
    return np.asarray(log.t[: log.n_recorded], dtype=np.float64)


def _row_of(log: SimulationLog, t: float) -> int:
    """Index of the logged row nearest to time *t* (clipped to the recorded rows)."""
    times = _times(log)
    return int(np.clip(np.rint((t - times[0]) / log.dt), 0, times.size - 1))


def _speed_limits(values: Sequence[FloatArray]) -> tuple[float, float]:
    """Colour limits [m/s] covering all finite values, widened to whole m/s."""
    finite = [v[np.isfinite(v)] for v in values]
    finite = [v for v in finite if v.size]
    if not finite:
        return 0.0, 1.0
    lo = math.floor(min(float(v.min()) for v in finite))
    hi = math.ceil(max(float(v.max()) for v in finite))
    return float(lo), float(max(hi, lo + 1))


def _lane_events(
    log: SimulationLog, kind: EventKind, vehicles: Sequence[int] | None = None
) -> list[tuple[float, float, int, int]]:
    """``(t, x, vehicle, lane)`` of the events of *kind* inside the logged time span.

    The lane is the vehicle's logged lane at the event (the origin lane for a lane-change
    start, the target lane for an end, lane 1 for a merge); x falls back to the logged
    position when the event has none.
    """
    times = _times(log)
    if times.size == 0:
        return []
    out = []
    for ev in log.events_of(kind):
        t, i = float(ev["t"]), int(ev["vehicle"])
        if not times[0] - 1e-9 <= t <= times[-1] + 1e-9:
            continue
        if vehicles is not None and i not in vehicles:
            continue
        k = _row_of(log, t)
        x = float(ev["x"]) if math.isfinite(ev["x"]) else float(log.x[k, i])
        if kind is EventKind.LANE_CHANGE_START:
            lane = int(log.lane[k, i])
        elif kind is EventKind.MERGE:
            lane = 1
        else:
            lane = int(ev["value"]) if math.isfinite(ev["value"]) else int(log.lane[k, i])
        if lane >= 0 and math.isfinite(x):
            out.append((t, x, i, lane))
    return out


def _merge_of(log: SimulationLog) -> tuple[float, float]:
    """Time [s] and position [m] of the first plan's VR merge; NaN if none."""
    vr = key_group(log).get("VR", -1)
    return merge_time(log, vr) if vr >= 0 else (math.nan, math.nan)


def _is_merge(log: SimulationLog) -> bool:
    """Whether the run is a merge scenario (road zones mean something); True if unknown."""
    config = log.meta.get("config")
    return not isinstance(config, Mapping) or config.get("scenario", "merge") == "merge"
