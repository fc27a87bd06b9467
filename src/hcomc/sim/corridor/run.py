"""Run a corridor in hcomc's engine: :func:`simulate_corridor` and its :class:`CorridorRun`.

The compiled step (:mod:`hcomc.sim.corridor.step`, :mod:`hcomc.sim.corridor.motion`) runs in
chunks of simulated time; between chunks Python only grows the trajectory buffer (when
trajectories are sampled) and reports progress, and with a merge controller a chunk ends
early whenever ramp vehicles await a decision (:mod:`hcomc.sim.corridor.control`). A run
returns its measurements as tables: one row per vehicle (trips), per detector, lane and
period, per space-time cell, per collision, per merge event, and the sampled trajectories.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from hcomc.corridor import Corridor
from hcomc.corridor.engine import scenario_only
from hcomc.corridor.model import MAX_DURATION
from hcomc.sim.corridor.control import CorridorControl
from hcomc.sim.corridor.events import merge_events, merge_summary
from hcomc.sim.corridor.fleet import CorridorFleet
from hcomc.sim.corridor.layout import Layout
from hcomc.sim.corridor.motion import advance
from hcomc.sim.corridor.setup import allocate, build_fleet, build_layout, vehicles_of
from hcomc.sim.corridor.state import (
    ARRIVED,
    C_COLLISIONS,
    C_LANE_CHANGES,
    C_PENDING,
    C_ROWS,
    C_SAMPLE_EVERY,
    C_STEP,
    C_VEHICLE_STEPS,
    COLLISION_COLUMNS,
    D_COUNT,
    D_INVERSE_SPEED,
    D_LENGTH,
    D_OCCUPIED,
    D_SPEED,
    G_DISTANCE,
    G_TIME,
    ON_ROAD,
    P_CELL,
    P_PERIOD,
    TRAJECTORY_COLUMNS,
    State,
    trajectory_buffer,
)  # fmt: skip
from hcomc.sim.corridor.trips import free_flow_times

__all__ = ["CorridorRun", "simulate_corridor"]

CHUNK = 60.0
"""Simulated seconds per call of the compiled loop."""

GROWTH = 1.25
"""The trajectory buffer grows to this times what the next chunk may need."""


@dataclass(frozen=True)
class CorridorRun:
    """What a corridor run measured (module docstring); tables as pandas DataFrames.
    ``collisions`` holds the first 1024 collisions, ``collision_count`` counts them all."""

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


OUTCOMES = ("arrived", "missed_exit", "on_road", "not_inserted")
"""A vehicle's outcome: arrived at its destination; arrived at the mainline's end after
missing its off-ramp; still on the road at the end; never inserted (backlog)."""


DETECTOR_COLUMNS = ("x", "lane", "begin", "end", "count", "flow", "speed", "harmonic_speed",
                    "occupancy", "mean_length")  # fmt: skip
"""Columns of :attr:`CorridorRun.detectors` (one row per loop, mainline lane and period)."""


def _mean(values: pd.Series) -> float | None:
    return float(values.mean()) if len(values) else None


def _refuse_scenario_keys(corridor: Corridor) -> None:
    """A ValueError naming the first key only hcomc's scenario engine runs (a warm-up, lane
    flows, a single release: :func:`hcomc.corridor.engine.scenario_only`)."""
    found = scenario_only(corridor)
    if found is not None:
        key, value = found
        raise ValueError(
            f"key '{key}' = {value!r}: the corridor engine does not run it; allowed: it unset "
            "(it runs in hcomc's scenario engine, for corridors of the paper's layout)"
        )


def simulate_corridor(
    corridor: Corridor,
    *,
    seed: int | None = None,
    duration: float | None = None,
    trajectory_interval: float = 0.0,
    progress: Callable[[float, float], None] | None = None,
) -> CorridorRun:
    """Run ``corridor``, with the merge controller its ``[control]`` table names at every
    on-ramp (:mod:`hcomc.sim.corridor.control`; "none": without).

    ``seed`` and ``duration`` [s] default to the corridor's; ``trajectory_interval`` [s]
    samples every vehicle's state that often (0: no trajectories; a multiple of the step);
    ``progress(t, duration)`` is called after each chunk.
    """
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
    layout = build_layout(corridor)
    fleet = build_fleet(corridor, layout, seed, duration)
    vehicles = vehicles_of(fleet)
    control = None
    if corridor.control.controller != "none":
        control = CorridorControl.build(corridor, layout, fleet, vehicles, seed)
    state = allocate(corridor, layout, fleet, duration, every, controlled=control is not None)
    n_steps = round(duration / dt)
    per_chunk = max(1, round(CHUNK / dt))
    reported = 0.0
    while state.counters[C_STEP] < n_steps:
        steps = min(per_chunk, n_steps - int(state.counters[C_STEP]))
        if every:
            state = _room_for_samples(state, fleet, steps, every, dt)
        advance(layout, vehicles, state, steps)  # returns early when VRs await a decision
        t = float(state.counters[C_STEP] * dt)
        if control is not None and state.counters[C_PENDING]:
            control.decide(state, t)
        if progress is not None and (t - reported >= CHUNK or t >= duration):
            progress(t, duration)
            reported = t
    wall = time.perf_counter() - started
    return _result(corridor, layout, fleet, state, seed, duration, wall, control)


def _room_for_samples(state: State, fleet: CorridorFleet, steps: int, every: int,
                      dt: float) -> State:  # fmt: skip
    """``state`` with a trajectory buffer that holds the next ``steps`` steps' samples."""
    t_end = (int(state.counters[C_STEP]) + steps) * dt
    could = int(np.count_nonzero((state.status != ARRIVED) & (fleet.depart <= t_end + 1e-9)))
    rows = int(state.counters[C_ROWS])
    need = rows + (steps // every + 1) * could
    if need <= state.traj_t.size:
        return state
    grown = trajectory_buffer(int(need * GROWTH))  # a quarter more: the copies stay few
    for name, new in grown.items():
        new[:rows] = getattr(state, name)[:rows]
    return state._replace(**grown)


def _result(c: Corridor, layout: Layout, fleet: CorridorFleet, s: State, seed: int,
            duration: float, wall: float,
            control: CorridorControl | None) -> CorridorRun:  # fmt: skip
    rows = int(s.counters[C_ROWS])
    trajectories = None
    if s.counters[C_SAMPLE_EVERY]:  # the buffer's columns, not copied
        columns = {name: getattr(s, f"traj_{name}")[:rows] for name in TRAJECTORY_COLUMNS}
        trajectories = pd.DataFrame(columns, copy=False)
    n_coll = min(int(s.counters[C_COLLISIONS]), s.collisions.shape[0])
    collisions = pd.DataFrame(s.collisions[:n_coll], columns=list(COLLISION_COLUMNS))
    return CorridorRun(
        corridor=c,
        seed=seed,
        duration=duration,
        trips=_trips(c, layout, fleet, s),
        detectors=_detectors(s, layout),
        grid=_grid(s, layout),
        backlog=pd.DataFrame(s.backlog.T, columns=list(fleet.origins)).assign(
            begin=lambda d: d.index * c.detectors.period
        ),
        collisions=collisions,
        trajectories=trajectories,
        vehicle_steps=int(s.counters[C_VEHICLE_STEPS]),
        lane_changes=int(s.counters[C_LANE_CHANGES]),
        wall_seconds=wall,
        collision_count=int(s.counters[C_COLLISIONS]),
        merges=merge_events(c, fleet, s, control),
        controller=c.control.controller,
        decisions=len(control.decisions) if control else 0,
        decision_seconds=control.decision_seconds if control else 0.0,
    )


def _trips(c: Corridor, layout: Layout, fleet: CorridorFleet, s: State) -> pd.DataFrame:
    outcome = np.where(
        s.status == ARRIVED,
        np.where(s.missed, "missed_exit", "arrived"),
        np.where(s.status == ON_ROAD, "on_road", "not_inserted"),
    )
    travel = s.arrive_t - s.insert_t
    free, route = free_flow_times(c, layout, fleet, s.missed)
    return pd.DataFrame(
        {
            "id": np.arange(fleet.depart.size),
            "origin": np.array(fleet.origins, dtype=object)[fleet.origin],
            "destination": np.array(fleet.destinations, dtype=object)[fleet.destination],
            "vclass": np.array(fleet.classes, dtype=object)[fleet.vclass],
            "cav": fleet.cav,
            "depart": fleet.depart,
            "insert": s.insert_t,
            "arrive": s.arrive_t,
            "outcome": outcome,
            "merge_time": s.merge_t,
            "merge_x": s.merge_x,
            "travel_time": travel,
            "delay": travel - free,
            "route_length": route,
        }
    )


def _detectors(s: State, layout: Layout) -> pd.DataFrame:
    det, period = s.detectors, float(s.params[P_PERIOD])
    rows = []
    for k, x in enumerate(s.det_x):
        section = int(np.searchsorted(layout.sec_x0, x, side="right") - 1)
        for lane in range(int(layout.sec_lanes[section])):
            for p in range(det.shape[2]):
                sums = det[k, lane, p]
                count, speed, length = sums[D_COUNT], sums[D_SPEED], sums[D_LENGTH]
                inverse, occupied = sums[D_INVERSE_SPEED], sums[D_OCCUPIED]
                rows.append({
                    "x": float(x), "lane": lane, "begin": p * period, "end": (p + 1) * period,
                    "count": int(count), "flow": 3600.0 * count / period,
                    "speed": speed / count if count else math.nan,
                    "harmonic_speed": count / inverse if count else math.nan,
                    "occupancy": 100.0 * occupied / period,
                    "mean_length": length / count if count else math.nan,
                })  # fmt: skip
    return pd.DataFrame(rows, columns=list(DETECTOR_COLUMNS))


def _grid(s: State, layout: Layout) -> pd.DataFrame:
    cell, cell_t = float(s.params[P_CELL]), float(s.params[P_PERIOD])
    cells, periods = s.grid.shape[:2]
    ix, it = np.meshgrid(np.arange(cells), np.arange(periods), indexing="ij")
    return pd.DataFrame({
        "x0": (ix * cell).ravel(), "x1": np.minimum((ix + 1) * cell, layout.length).ravel(),
        "t0": (it * cell_t).ravel(), "t1": ((it + 1) * cell_t).ravel(),
        "distance": s.grid[:, :, G_DISTANCE].ravel(), "time": s.grid[:, :, G_TIME].ravel(),
    })  # fmt: skip
