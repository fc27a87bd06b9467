"""A co-simulation run's state in our frame, and its reading back from SUMO.

:class:`CosimState` holds what :class:`hcomc.sumo.cosim.SumoSimulation` works on: the scenario,
seed, demand (the same draws as our engine), fleet and controller; the vehicles' state arrays,
the plans and decisions, and the preallocated log with its metadata. After each step SUMO's
vehicles are read back into those arrays in our frame (the network's x, y are ours; the lane
is the one the vehicle's centre is in, so it switches mid-manoeuvre as in our engine), and
insertions, exits, lane changes and merges are logged as they happen. Advancing SUMO and
commanding the key CAVs is :class:`~hcomc.sumo.cosim.SumoSimulation`'s.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from hcomc.config import ScenarioConfig
from hcomc.interface import Fleet, MergeController, MergeGroup, MergePlan, TrafficView
from hcomc.interface.listener import StepListener
from hcomc.rng import make_rng
from hcomc.road import Lane, lane_centre
from hcomc.sim.demand import generate_demand
from hcomc.sim.lane_table import L_END
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.manifest import build_manifest
from hcomc.sim.plan_execution import ActivePlan
from hcomc.sim.roads import paper_lanes, ramps_of
from hcomc.sim.scene import Scene
from hcomc.sim.stalled import blocked_lanes, with_stalled
from hcomc.sumo import import_libsumo
from hcomc.sumo.routes import vehicle_id

__all__ = ["CosimState"]

_SETTLED = 1e-3  # lateral offset [lane widths] below which a vehicle keeps its lane


class CosimState:
    """One co-simulation run's state (its parameters are those of
    :class:`hcomc.sumo.cosim.SumoSimulation`, the class to use)."""

    def __init__(
        self,
        config: ScenarioConfig,
        seed: int | None = None,
        controller: MergeController | None = None,
        *,
        counterfactual: bool = False,
        listeners: Sequence[StepListener] = (),
    ) -> None:
        self.counterfactual = counterfactual  # the undisturbed run: ramp vehicles removed
        if config.scenario != "merge":
            raise ValueError(f"scenario = '{config.scenario}': the SUMO engine runs 'merge' only")
        self.sumo = import_libsumo()
        self.config = config
        self.lanes = paper_lanes(config.road)  # the road's lane table, as our engine's
        self.ramps = ramps_of(self.lanes)  # the road as built, which the controllers see
        self.seed = config.seed if seed is None else seed
        self.rng = make_rng(self.seed)
        self.dt = config.dt
        self._draw_traffic()
        n = self.demand.n
        # the parameters SUMO's vehicles drive with (a listener may change them; ``fleet``
        # stays what the controllers know), and those each SUMO vehicle was last given
        self.driving = dataclasses.replace(self.fleet, matrix=self.fleet.matrix.copy())
        self._in_sumo = self.fleet.matrix.copy()
        if controller is None:
            from hcomc.control.registry import make_controller

            controller = make_controller(config)
        self.controller = controller
        self.x, self.y, self.v = np.zeros(n), np.zeros(n), np.zeros(n)
        self.a, self.heading = np.zeros(n), np.zeros(n)
        self.lane = self.demand.lane.copy()
        self.origin = self.demand.lane.copy()  # lane a manoeuvre started from
        self.active = np.zeros(n, dtype=bool)
        self.planned = np.zeros(n, dtype=bool)
        self.key_groups: dict[int, MergeGroup] = {}
        self.plans: list[ActivePlan] = []
        self.decisions: list[MergePlan] = []
        self.requests: list[tuple[TrafficView, MergeGroup]] = []  # what each plan was asked
        self.n_warmup = round(config.warmup / self.dt)
        self.n_steps = round(config.duration / self.dt)
        self._log_every = round(config.log_interval / self.dt)
        self.step_index = 0
        self.vehicle_steps = 0
        self.sumo_collisions = 0
        self.sumo_teleports = 0
        self._speed_set: set[int] = set()  # vehicles whose speed we impose this step
        self._lc_start: dict[int, float] = {}  # vehicle -> start of its running lane change
        self._outside: dict[int, float] = {}  # vehicle -> acceleration commanded from outside
        self._driven: set[int] = set()  # vehicles under an outside command in SUMO now
        self._held: set[int] = set()  # VRs whose commanded merge is not requested this step
        meta = build_manifest(
            seed=self.seed,
            config=config.model_dump(mode="json"),
            extra={"dt": self.dt, "log_interval": config.log_interval, "engine": "sumo",
                   "sumo_version": self._sumo_version()},
        )  # fmt: skip
        self.log = SimulationLog.allocate(
            self.n_steps // self._log_every + 1, n, dt=config.log_interval,
            kind=self.demand.kind, length=self.fleet.length, width=self.fleet.width, meta=meta,
        )  # fmt: skip
        if self.stalled.size:
            self.log.meta["stalled"] = self.stalled.tolist()
        self._rows = 0
        self.listeners = tuple(listeners)
        for listener in self.listeners:
            listener.attach(self)  # type: ignore[arg-type]  # SumoSimulation is a ListenedRun

    def _draw_traffic(self) -> None:
        """The demand and fleet, the same draws as our engine's, with the stalled vehicles
        (:mod:`hcomc.sim.stalled`) as its last columns; where the acceleration lane ends
        for the vehicles on it (before a stalled vehicle, where one stands)."""
        config = self.config
        demand = generate_demand(config, self.rng)
        fleet = Fleet.build(config, demand.kind, demand.scripted)
        scene, self.stalled = with_stalled(Scene(self.lanes, demand, fleet), config)
        self.demand, self.fleet = scene.demand, scene.fleet
        lanes = blocked_lanes(self.lanes, self.demand, self.fleet, self.stalled,
                              config.lane_change.min_gap)  # fmt: skip
        self.accel_end = float(lanes.floats[L_END, Lane.RAMP])

    @staticmethod
    def _sumo_version() -> str:
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("eclipse-sumo")
        except PackageNotFoundError:  # pragma: no cover - SUMO from elsewhere
            return "unknown"

    @property
    def t(self) -> float:
        """Current time [s]; t = 0 after the warm-up (SUMO time = t + warmup)."""
        return -self.config.warmup + self.step_index * self.dt

    @property
    def key_group(self) -> MergeGroup | None:
        """Key vehicles of the first ramp vehicle that entered the control zone (or None)."""
        return next(iter(self.key_groups.values()), None)

    def _record(self) -> None:
        self.log.record(self._rows, self.t, self.x, self.y, self.v, self.a, self.heading,
                        self.lane, self.active)  # fmt: skip
        self._rows += 1

    def _read_state(self, t: float) -> None:
        sim, veh = self.sumo.simulation, self.sumo.vehicle
        width = self.config.road.lane_width
        ramp = self.demand.lane == Lane.RAMP
        for name in sim.getDepartedIDList():
            i = int(name[1:])
            if self.counterfactual and ramp[i]:
                veh.remove(name)  # the undisturbed run: nothing merges
                continue
            if i in self.stalled:
                continue  # it stands from the start, released by no demand (as in our engine)
            self.log.add_event(t, EventKind.INSERTION, i, x=float(self.demand.x[i]),
                               value=t - float(self.demand.t[i]))  # fmt: skip
        for name in sim.getArrivedIDList():
            if self.counterfactual and ramp[int(name[1:])]:
                continue
            self.log.add_event(t, EventKind.EXIT, int(name[1:]), x=float(self.x[int(name[1:])]))
        self.sumo_teleports += sim.getStartingTeleportNumber()
        # on the road = in SUMO's network now (a vehicle being teleported is not)
        self.active[:] = False
        self.active[[int(name[1:]) for name in veh.getIDList()]] = True
        for i in np.flatnonzero(self.active).tolist():
            name = vehicle_id(i)
            self.x[i], self.y[i] = veh.getPosition(name)
            self.v[i] = veh.getSpeed(name)
            self.a[i] = veh.getAcceleration(name)
            self.heading[i] = np.radians(90.0 - veh.getAngle(name))
        ids = np.flatnonzero(self.active)
        lane = np.clip(np.rint(self.y[ids] / width).astype(np.int64) + 1, Lane.RAMP, Lane.MAIN_2)
        self.lane[ids] = lane
        settled = np.abs(self.y[ids] - lane_centre(lane, width)) < _SETTLED * width
        for i, s in zip(ids.tolist(), settled.tolist(), strict=True):
            if self.origin[i] == self.lane[i] and not s and i not in self._lc_start:
                self._lc_start[i] = t
                target = self.lane[i] + int(np.sign(self.y[i] - lane_centre(self.lane[i], width)))
                self.log.add_event(t, EventKind.LANE_CHANGE_START, i, x=self.x[i], value=target)
            elif s and self.origin[i] != self.lane[i]:
                self.log.add_event(t, EventKind.LANE_CHANGE_END, i, x=self.x[i],
                                   value=int(self.lane[i]))  # fmt: skip
                if self.origin[i] == Lane.RAMP:
                    self.log.add_event(t, EventKind.MERGE, i, x=self.x[i])
                self.origin[i] = self.lane[i]
                self._lc_start.pop(i, None)
            elif s:
                self._lc_start.pop(i, None)

    @property
    def target(self) -> np.ndarray:
        """(N,) the lane a lane change in progress goes to (the side the vehicle's centre is
        moving to, from its lateral offset), else ``origin``."""
        width = self.config.road.lane_width
        offset = np.sign(self.y - lane_centre(self.lane, width)).astype(np.int64)
        changing = self.changing()
        return np.where(changing, np.where(self.origin == self.lane, self.lane + offset,
                                           self.lane), self.origin)  # fmt: skip

    def changing(self) -> np.ndarray:
        """Vehicles in a lane-change manoeuvre (off their lane centre)."""
        mask = self.active & (self.origin != self.lane)
        mask[list(self._lc_start)] = True
        return mask
