"""What a run under faults adds to an engine, whichever engine moves the vehicles.

:class:`Impairments` is mixed into our engine (:class:`hcomc.robustness.engine.FaultedSimulation`)
and into the SUMO co-simulation (:class:`hcomc.sumo.faulted.FaultedSumoSimulation`):
the channel, the fault and the shield of one run, the controller's decision on the channel's
view, the degraded headway of CAVs whose leader went silent, and the count of collisions
with a commanded vehicle.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.control.base import MergeController, MergeGroup, MergePlan, Mode
from hcomc.road import Kind
from hcomc.robustness.channel import Channel
from hcomc.robustness.faults import Fault
from hcomc.robustness.settings import ChannelParams, FaultParams, ShieldParams
from hcomc.robustness.shield import Shield
from hcomc.sim.fleet import Fleet
from hcomc.sim.log import EventKind, SimulationLog

__all__ = ["Impairments"]


class Impairments:
    """The channel, fault and shield of a run, and what both engines do with them."""

    # provided by the engine it is mixed into
    config: ScenarioConfig
    seed: int
    dt: float
    x: FloatArray
    v: FloatArray
    a: FloatArray
    lane: IntArray
    origin: IntArray
    active: BoolArray
    fleet: Fleet
    arrays: Any  # lane occupancy (x, lane, origin, target, active), and our engine's plans
    command: Callable[[int, float], None]  # drive a vehicle from outside (NaN: stop)
    _follow: Callable[[IntArray, IntArray], FloatArray]  # car following behind leaders
    _state: Callable[[], dict[str, np.ndarray]]  # the state a broadcast carries
    controller: MergeController | None
    rng: np.random.Generator
    log: SimulationLog

    def _impair(
        self,
        channel: ChannelParams | None,
        fault: FaultParams | None,
        shield: ShieldParams | None,
        driving_matrix: FloatArray,
    ) -> None:
        """Set up the run's impairments; the engine drives with the parameters of
        ``driving_matrix`` (which faults and degraded headways change), the controllers
        predict with the nominal ones."""
        config = self.config
        self.channel_params = channel or ChannelParams()
        self.channel = Channel(
            self.channel_params, self.x.size, config.road.accel_lane_start, self.seed
        )
        self.fault = Fault(fault or FaultParams(), config, self.seed)
        self.shield = Shield(shield or ShieldParams(), config)
        self.nominal_fleet = dataclasses.replace(self.fleet, matrix=self.fleet.matrix.copy())
        self.driving = dataclasses.replace(self.fleet, matrix=driving_matrix)
        self._next_plan: dict[int, float] = {}  # VR -> earliest next decision after a loss
        self._broadcast_every = max(1, round(self.channel_params.period / self.dt))
        self.plans_lost = 0
        self.degraded_steps = 0
        self.commanded_at: dict[int, frozenset[int]] = {}  # step -> commanded vehicles

    def _decide(self, view: Any, group: MergeGroup) -> MergePlan:
        """The controller's plan, or the safe default when a key vehicle was never heard."""
        assert self.controller is not None
        missing = [int(i) for i in group.as_array() if i >= 0 and not view.active[i]]
        if missing:
            return MergePlan(group, Mode.NONE, view.t, fallback=True,
                             reason=f"no V2X message from vehicles {missing}")  # fmt: skip
        return self.controller.plan(view, group, self.rng.spawn(1)[0])

    def _degrade(self, t: float) -> None:
        """CAVs behind a CAV whose newest message is stale drive with the degraded headway."""
        T = self.driving.T
        ids = np.flatnonzero(self.active & (self.fleet.kind == Kind.CAV))
        T[ids] = self.nominal_fleet.T[ids]
        if ids.size == 0:
            return
        leaders = self.shield.leaders_in_lane(self, ids)
        has = leaders >= 0
        stale = np.zeros(ids.size, dtype=bool)
        stale[has] = (self.fleet.kind[leaders[has]] == Kind.CAV) & (
            t - self.channel.heard[leaders[has]] > self.channel_params.stale_after
        )
        T[ids[stale]] = self.channel_params.degraded_time_headway
        self.degraded_steps += int(stale.sum())

    def collisions_commanded(self) -> int:
        """COLLISION events with a vehicle that a live plan commanded in that step."""
        count = 0
        for e in self.log.events_of(EventKind.COLLISION):
            step = round((float(e["t"]) + self.config.warmup) / self.dt)
            commanded = self.commanded_at.get(step, frozenset()) | self.commanded_at.get(
                step - 1, frozenset()
            )
            count += int(int(e["vehicle"]) in commanded or int(e["other"]) in commanded)
        return count
