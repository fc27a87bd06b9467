"""Flow metrics of runs with a continuous ramp demand (sweeps).

* **throughput** [veh/h]: vehicles whose front crosses ``x_ref = accel_lane_end + 50 m`` during
  the logged window, per hour of window;
* **ramp delay** [s]: mean, over ramp vehicles that reached ``x_ref``, of their travel time
  from the ramp entry to ``x_ref`` minus the free-flow time at their desired speed.
"""

from __future__ import annotations

import numpy as np

from hcomc.metrics.window import road_of
from hcomc.road import Kind, Lane
from hcomc.sim.log import SimulationLog

DOWNSTREAM = 50.0  # [m] reference section beyond the acceleration-lane end


def _crossing_times(log: SimulationLog, x_ref: float) -> np.ndarray:
    """(N,) time each vehicle's front first crosses ``x_ref`` (NaN if it does not)."""
    x = np.where(log.active, log.x, np.nan).astype(np.float64)
    before, after = x[:-1], x[1:]
    crossing = (before < x_ref) & (after >= x_ref)
    rows = np.where(crossing.any(axis=0), crossing.argmax(axis=0), -1)
    n = np.arange(x.shape[1])
    ok = rows >= 0
    k = np.where(ok, rows, 0)
    x0, x1 = before[k, n], after[k, n]
    frac = np.where(ok, (x_ref - x0) / np.where(x1 > x0, x1 - x0, 1.0), 0.0)
    return np.where(ok, log.t[k] + frac * log.dt, np.nan)


def throughput(log: SimulationLog) -> float:
    """Vehicles per hour past ``accel_lane_end + 50 m`` over the logged window [veh/h]."""
    times = _crossing_times(log, road_of(log).accel_lane_end + DOWNSTREAM)
    span = float(log.t[-1] - log.t[0]) if log.t.size > 1 else 0.0
    return float(np.isfinite(times).sum() / span * 3600.0) if span > 0 else float("nan")


def ramp_delay(log: SimulationLog) -> float:
    """Mean delay of ramp vehicles between the ramp entry and ``accel_lane_end + 50 m`` [s]."""
    cfg = log.meta["config"]
    x_ref = road_of(log).accel_lane_end + DOWNSTREAM
    arrive = _crossing_times(log, x_ref)
    ramp = ((log.lane == Lane.RAMP) & log.active).any(axis=0)
    first = np.where(log.active.any(axis=0), log.active.argmax(axis=0), 0)
    entered = log.t[first]
    x_start = log.x[first, np.arange(log.x.shape[1])].astype(np.float64)
    v0 = np.where(log.kind == Kind.CAV, cfg["cav"]["desired_speed"], cfg["hdv"]["desired_speed"])
    ok = ramp & np.isfinite(arrive)
    delay = (arrive - entered) - (x_ref - x_start) / v0
    return float(delay[ok].mean()) if ok.any() else float("nan")
