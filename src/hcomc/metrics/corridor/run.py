"""Run a corridor on hcomc's engine: :func:`simulate_corridor` and its :class:`CorridorRun`.

A corridor (:mod:`hcomc.corridor`) runs as a scene of the one engine
(:func:`hcomc.sim.corridor_scene.corridor_scene`): its road as a lane table, its demand and
vehicle classes, with the paper's physics (Eq. 2 perception of human drivers, Eq. 1/3 car
following, MOBIL and gap acceptance, Eq. 4-6 lateral motion, Eq. 7 collisions) and the merge
controller its ``[control]`` table names at every on-ramp. The engine logs every vehicle at
every step; the run's measurements are read from that log (:mod:`hcomc.metrics.corridor.measure`,
:mod:`hcomc.metrics.corridor.trips`, :mod:`hcomc.metrics.corridor.events`) as tables: one row per
vehicle (trips), per detector, lane and period, per space-time cell, per collision, per
merge event, and the sampled trajectories.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from hcomc.corridor import Corridor
from hcomc.corridor.engine import scenario_only
from hcomc.corridor.layout import ramp_codes
from hcomc.corridor.model import MAX_DURATION
from hcomc.metrics.corridor.events import merge_events, merge_summary
from hcomc.metrics.corridor.measure import (
    backlog,
    collision_table,
    edie_cells,
    loops,
    trajectory_table,
)
from hcomc.metrics.corridor.trips import OUTCOMES, Released, trip_table
from hcomc.metrics.detectors import vehicle_rows
from hcomc.road import Kind
from hcomc.sim.corridor_scene import corridor_config, corridor_scene
from hcomc.sim.log import EventKind, SimulationLog

if TYPE_CHECKING:
    from hcomc.interface.listener import StepListener
    from hcomc.sim.engine import Simulation

__all__ = ["OUTCOMES", "CorridorRun", "simulate_corridor"]


@dataclass(frozen=True)
class CorridorRun:
    """What a corridor run measured (module docstring); tables as pandas DataFrames, and the
    engine's log of the run."""

    corridor: Corridor
    seed: int
    duration: float
    trips: pd.DataFrame
    detectors: pd.DataFrame
    grid: pd.DataFrame
    backlog: pd.DataFrame
    collisions: pd.DataFrame
    trajectories: pd.DataFrame | None
    vehicle_steps: int
    lane_changes: int
    wall_seconds: float
    collision_count: int
    merges: pd.DataFrame
    log: SimulationLog
    controller: str = "none"
    decisions: int = 0
    decision_seconds: float = 0.0

    def summary(self) -> dict[str, object]:
        """Run-level figures: vehicles per outcome, travel time and delay per origin,
        collisions, lane changes, the largest backlog per origin, and per on-ramp the
        vehicles that entered and merged, where (metres past the start of the acceleration
        lane), how many per hour, and its merge events (:func:`merge_summary`); with a
        controller, its decisions and their wall time."""
        trips = self.trips
        per_origin = {}
        for origin, rows in trips.groupby("origin", sort=False):
            done = rows[rows.outcome != "on_road"].dropna(subset=["travel_time"])
            per_origin[str(origin)] = {
                "vehicles": len(rows),
                "arrived": int(rows.arrive.notna().sum()),
                "mean_travel_time": _mean(done.travel_time),
                "mean_delay": _mean(done.delay),
                "max_backlog": int(self.backlog[str(origin)].max()) if len(self.backlog) else 0,
            }
        counts = trips.outcome.value_counts()
        ramps = {}
        for ramp in self.corridor.road.on_ramps:
            rows = trips[trips.origin == ramp.id]
            entered = rows[rows["insert"].notna()]
            merged = entered[entered.merge_time.notna()]
            ramps[ramp.id] = {
                "entered": len(entered),
                "merged": len(merged),
                "merged_share": len(merged) / len(entered) if len(entered) else None,
                "mean_merge_position": _mean(merged.merge_x - ramp.x),
                "merges_per_hour": 3600.0 * len(merged) / self.duration,
                "merge_events": merge_summary(self.merges, ramp.id),
            }
        return {
            "corridor": self.corridor.name,
            "seed": self.seed,
            "duration": self.duration,
            "vehicles": len(trips),
            **{k: int(counts.get(k, 0)) for k in OUTCOMES},
            "controller": self.controller,
            "decisions": self.decisions,
            "decision_seconds": self.decision_seconds,
            "collisions": self.collision_count,
            "lane_changes": self.lane_changes,
            "vehicle_steps": self.vehicle_steps,
            "wall_seconds": self.wall_seconds,
            "origins": per_origin,
            "on_ramps": ramps,
        }


def _mean(values: pd.Series) -> float | None:
    return float(values.mean()) if len(values) else None


def _refuse_scenario_keys(corridor: Corridor) -> None:
    """A ValueError naming the first key only hcomc's scenario engine runs (a warm-up, lane
    flows, a single release: :func:`hcomc.corridor.engine.scenario_only`)."""
    found = scenario_only(corridor)
    if found is not None:
        key, value = found
        raise ValueError(
            f"key '{key}' = {value!r}: a corridor run does not take it; allowed: it unset "
            "(it runs as one of the paper's conditions, 'hcomc simulate C1' ... 'C5')"
        )


def simulate_corridor(
    corridor: Corridor,
    *,
    seed: int | None = None,
    duration: float | None = None,
    trajectory_interval: float = 0.0,
    progress: Callable[[float, float], None] | None = None,
    listeners: Sequence[StepListener] = (),
) -> CorridorRun:
    """Run ``corridor``, with the merge controller its ``[control]`` table names at every
    on-ramp ("none": without).

    ``seed`` and ``duration`` [s] default to the corridor's; ``trajectory_interval`` [s]
    samples every vehicle's state that often (0: no trajectories; a multiple of the step);
    ``progress(t, duration)`` is called as the run advances; ``listeners`` act on the run
    between its steps (:class:`hcomc.interface.listener.StepListener`, e.g. the V2X channel,
    faults and shield of :class:`hcomc.robustness.impairments.Impairments`).
    """
    from hcomc.sim.engine import Simulation

    seed = corridor.corridor.seed if seed is None else seed
    duration = corridor.corridor.duration if duration is None else duration
    dt = corridor.corridor.step_length
    if not 0 < duration <= MAX_DURATION:  # checked before anything is allocated
        raise ValueError(f"duration = {duration!r} s: allowed: 0 < duration <= {MAX_DURATION:g}")
    every = round(trajectory_interval / dt) if trajectory_interval > 0 else 0
    if trajectory_interval > 0 and (every < 1 or abs(every * dt - trajectory_interval) > 1e-9):
        raise ValueError(
            f"trajectory_interval = {trajectory_interval} s: allowed: 0 or a multiple of the "
            f"step, {dt} s"
        )
    _refuse_scenario_keys(corridor)
    started = time.perf_counter()
    config = corridor_config(corridor, duration=duration, seed=seed, log_interval=dt)
    sim = Simulation(config, seed=seed, scene=corridor_scene(corridor), listeners=listeners)
    report = None
    if progress is not None:

        def report(step: int, total: int) -> None:
            progress(step * dt, total * dt)

    sim.run(report)
    wall = time.perf_counter() - started
    return _measured(corridor, sim, seed, duration, wall, every * dt)


def _released(c: Corridor, sim: Simulation) -> Released:
    """Who the run of corridor ``c`` released: its scene's demand and vehicle classes, with
    origins and destinations named by the lanes they release into and leave by. A stalled
    vehicle (:mod:`hcomc.sim.stalled`, the scene's last indices) is nobody's trip."""
    scene = sim.scene
    n = scene.demand.n - sim.stalled.size
    named = {code: ramp for ramp, code in ramp_codes(c.road).items()}
    origins = tuple(c.demand)
    destinations = ("exit", *(r.id for r in c.road.off_ramps))
    origin = [origins.index(named.get(code, "main")) for code in scene.demand.lane[:n].tolist()]
    leave = [destinations.index(named.get(code, "exit"))
             for code in scene.demand.route[:n].tolist()]  # fmt: skip
    return Released(
        origins=origins, destinations=destinations, classes=scene.classes,
        origin=np.array(origin, dtype=np.int64), destination=np.array(leave, dtype=np.int64),
        vclass=scene.vclass[:n], cav=scene.fleet.kind[:n] == int(Kind.CAV),
        depart=scene.demand.t[:n] + sim.config.warmup, desired=scene.fleet.matrix[0, :n],
        length=scene.fleet.length[:n],
    )  # fmt: skip


def _measured(c: Corridor, sim: Simulation, seed: int, duration: float, wall: float,
              interval: float) -> CorridorRun:  # fmt: skip
    """The run's tables, read from its log (module docstring)."""
    log = sim.log
    who = _released(c, sim)
    rows = vehicle_rows(log)
    trips = trip_table(c, who, log)
    decisions = list(sim.decisions)
    origin_of = np.array(who.origins, dtype=object)[who.origin]
    kinds = log.events["kind"]
    return CorridorRun(
        corridor=c, seed=seed, duration=duration, trips=trips,
        detectors=loops(c, log, rows), grid=edie_cells(c, rows, duration),
        backlog=backlog(who.origins, who.origin, who.depart, trips["insert"].to_numpy(),
                        c.detectors.period, duration, c.corridor.step_length),
        collisions=collision_table(log),
        trajectories=trajectory_table(c, log, interval) if interval > 0 else None,
        vehicle_steps=int(log.vehicle_steps),
        lane_changes=int((kinds == EventKind.LANE_CHANGE_START).sum()),
        wall_seconds=wall, collision_count=int((kinds == EventKind.COLLISION).sum()),
        merges=merge_events(c, log, rows, origin_of, who.cav, decisions), log=log,
        controller=c.control.controller, decisions=len(decisions),
        decision_seconds=sum(p.decision_ms for p in decisions) / 1000.0,
    )  # fmt: skip
