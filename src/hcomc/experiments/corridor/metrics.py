"""Corridor metrics: what a comparison measures on a corridor run.

A corridor run (:class:`hcomc.metrics.corridor.CorridorRun`) has many vehicles and many merges,
so its metrics are run-level figures computed from its tables: one row per vehicle
(``trips``) and one per merge event (``merges``: every ramp vehicle that reached its on-ramp's
control zone, merged or not). :data:`CORRIDOR_METRICS` is their registry: name, label with
unit, the better direction (what a paired comparison's ``favours`` reads) and definition.

Failures are outcomes, never holes: a ramp vehicle that never merged stays an event and
lowers ``merged_share``; a vehicle still on the road when the run ends has no travel time but
is missing from ``completed_trips``. The merge-event figures are those of
:func:`hcomc.metrics.corridor.events.merge_summary` (what ``hcomc simulate CORRIDOR`` prints per
on-ramp) taken over every on-ramp's events together, so the two never disagree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pandas as pd

from hcomc.metrics.corridor.events import merge_summary


@dataclass(frozen=True)
class CorridorMetric:
    """A registered corridor metric: a column of the runs table."""

    name: str
    label: str  # short name with unit, for tables and figures
    better: Literal["larger", "smaller"]
    description: str


CORRIDOR_METRICS: dict[str, CorridorMetric] = {
    m.name: m
    for m in (
        CorridorMetric("travel_time", "Travel time [s]", "smaller",
                       "mean travel time of the vehicles that completed their trip (arrived, "
                       "or reached the mainline's end after missing their exit)"),
        CorridorMetric("travel_time_main", "Travel time, main [s]", "smaller",
                       "the same over the completed trips that started on the mainline"),
        CorridorMetric("delay", "Delay [s]", "smaller",
                       "mean delay of the completed trips: travel time minus the free-flow "
                       "time of the route"),
        CorridorMetric("completed_trips", "Completed trips", "larger",
                       "vehicles that completed their trip within the run"),
        CorridorMetric("merged_share", "Merged share", "larger",
                       "share of the merge events whose ramp vehicle merged before the run "
                       "ended"),
        CorridorMetric("time_to_merge", "Zone to merge [s]", "smaller",
                       "mean time from the control zone to the completed merge, over the "
                       "merged events"),
        CorridorMetric("min_ttc_p05", "Least TTC, 5 % [s]", "larger",
                       "5th percentile of the events' least time to collision, over the "
                       "events with a finite one (someone closed in on a leader)"),
        CorridorMetric("ttc_below_1_5s_share", "TTC < 1.5 s share", "smaller",
                       "share of the merge events whose least time to collision is under "
                       "1.5 s"),
        CorridorMetric("max_drac_p95", "Max DRAC, 95 % [m/s²]", "smaller",
                       "95th percentile of the events' largest deceleration rate to avoid a "
                       "crash, over the events with a finite one"),
        CorridorMetric("collisions", "Collisions", "smaller", "collisions in the run"),
        CorridorMetric("fallbacks", "Fallbacks", "smaller",
                       "merge events in which the controller fell back to a safe plan"),
    )
}  # fmt: skip
"""Registry of the corridor metrics, keyed by runs-table column, in display order."""

COUNTS = ("events", "merged_events", "vehicles", "on_road", "not_inserted", "plans")
"""Further columns of a corridor run's row (counts that explain the metrics)."""

_ALL = "*"
"""The pseudo on-ramp under which every event is summarised together."""


def _value(x: Any) -> float:
    """A summary figure as a float (NaN for an undefined one)."""
    return math.nan if x is None else float(x)


def finite_quantile(values: pd.Series, q: float) -> float:
    """The ``q`` quantile (linear interpolation) of the finite values; NaN if there are none
    (as :func:`~hcomc.metrics.corridor.events.merge_summary` takes its TTC percentile)."""
    x = pd.to_numeric(values, errors="coerce").to_numpy(np.float64)
    x = x[np.isfinite(x)]
    return float(np.quantile(x, q)) if x.size else math.nan


def corridor_metrics(trips: pd.DataFrame, merges: pd.DataFrame, collisions: int) -> dict[str, Any]:
    """Every metric of :data:`CORRIDOR_METRICS` and the :data:`COUNTS` of one run, from its
    trips and merge events and its number of collisions; ``merged``: whether every merge
    event merged (False for a run without any; see :func:`run_merged`)."""
    done = trips[trips["outcome"].isin(("arrived", "missed_exit"))]
    done = done[np.isfinite(done["travel_time"].to_numpy(np.float64))]
    events = merge_summary(merges.assign(ramp=_ALL), _ALL)
    values: dict[str, Any] = {
        "travel_time": _mean(done["travel_time"]),
        "travel_time_main": _mean(done.loc[done["origin"] == "main", "travel_time"]),
        "delay": _mean(done["delay"]),
        "completed_trips": float(len(done)),
        "merged_share": _value(events["merged_share"]),
        "time_to_merge": _value(events["mean_time_to_merge"]),
        "min_ttc_p05": _value(events["min_ttc_p05"]),
        "ttc_below_1_5s_share": _value(events["ttc_below_1_5s_share"]),
        "max_drac_p95": finite_quantile(merges["max_drac"], 0.95),
        "collisions": float(collisions),
        "fallbacks": float(events["fallbacks"]),
    }
    merged_events = int(merges["merged"].sum())
    counts = {
        "events": len(merges),
        "merged_events": merged_events,
        "vehicles": len(trips),
        "on_road": int((trips["outcome"] == "on_road").sum()),
        "not_inserted": int((trips["outcome"] == "not_inserted").sum()),
        "plans": int(events["plans"]),
    }
    return {"merged": run_merged(len(merges), merged_events), **values, **counts}


def run_merged(events: int, merged_events: int) -> bool:
    """The run-level ``merged`` of a corridor run: every ramp vehicle that reached a control
    zone merged before the run ended (a run without any merge event has no merge that
    succeeded, so it is False). Merge success of a comparison counts these runs; the
    corridor metrics are paired whatever it says, since they are defined for every run."""
    return events > 0 and merged_events == events


def _mean(values: pd.Series) -> float:
    return float(values.mean()) if len(values) else math.nan


__all__ = [
    "CORRIDOR_METRICS",
    "COUNTS",
    "CorridorMetric",
    "corridor_metrics",
    "finite_quantile",
    "run_merged",
]
