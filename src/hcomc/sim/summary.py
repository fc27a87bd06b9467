"""Run summary: the figures ``hcomc simulate`` prints, computed from a SimulationLog."""

from __future__ import annotations

from typing import Any

import numpy as np

from hcomc.equations.fuel import fuel_consumed
from hcomc.road import Kind, Lane
from hcomc.sim.log import EventKind, SimulationLog


def summarise(log: SimulationLog) -> dict[str, Any]:
    """Vehicles, merges, collisions, ramp waits, mean speed per lane [m/s] and fuel [L].

    Fuel is Eq. 16 summed over all vehicles in the logged window.
    """
    events = log.events
    kinds = events["kind"]
    seen = log.logged_vehicles()
    # Statistics over the cells of vehicles on the road are taken over the stored columns:
    # every stored cell outside a vehicle's time on the road holds the fill value (inactive,
    # NaN), so this needs no (T, N) array, however many vehicles the run had.
    cells = log.cells
    speed = {}
    for lane in Lane:
        on = cells["active"] & (cells["lane"] == lane)
        key = "ramp" if lane == Lane.RAMP else f"lane_{int(lane)}"
        speed[key] = float(np.mean(cells["v"][on])) if on.any() else None
    v, a = cells["v"].astype(np.float64), cells["a"].astype(np.float64)
    return {
        "vehicles": int(seen.sum()),
        "cavs": int((seen & (log.kind == Kind.CAV)).sum()),
        "merges": int((kinds == EventKind.MERGE).sum()),
        "collisions": int((kinds == EventKind.COLLISION).sum()),
        "ramp_waits": int((kinds == EventKind.RAMP_WAIT).sum()),
        "lane_changes": int((kinds == EventKind.LANE_CHANGE_START).sum()),
        "mean_speed": speed,
        "fuel_l": float(fuel_consumed(v, a, log.dt, axis=None)),
        "vehicle_steps": int(log.meta.get("vehicle_steps", log.vehicle_steps)),
        "duration_s": float(log.t[-1] - log.t[0]) if log.t.size else 0.0,
    }
