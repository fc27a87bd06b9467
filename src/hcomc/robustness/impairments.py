"""What a run under faults adds to an engine, whichever engine moves the vehicles.

:class:`Impairments` is mixed into our engine (:class:`hcomc.robustness.engine.FaultedSimulation`)
and into the SUMO co-simulation (:class:`hcomc.sumo.faulted.FaultedSumoSimulation`):
the channel, the fault and the shield of one run; the controller's decision on the channel's
view, its record, and its plan sent to the vehicles (at once, late or never, then made
again); the degraded headway of CAVs whose leader went silent; and the count of collisions
with a commanded vehicle. Each engine says how a plan is put into force (``_execute``) and
whether its ramp vehicle can still act on one (``_may_execute``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.control.key_group import find_key_vehicles
from hcomc.control.validation import checked, name_of
from hcomc.interface import Fleet, MergeController, MergeGroup, MergePlan, Mode, TrafficView
from hcomc.road import Kind
from hcomc.robustness.channel import Channel
from hcomc.robustness.faults import Fault
from hcomc.robustness.settings import ChannelParams, FaultParams, ShieldParams
from hcomc.robustness.shield import Shield
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.neighbours import build_lane_index
from hcomc.sim.plan_execution import record_decision

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
    planned: BoolArray
    fleet: Fleet
    arrays: Any  # lane occupancy (x, lane, origin, target, active), and our engine's plans
    step_index: int
    n_warmup: int
    decisions: list[MergePlan]
    requests: list[tuple[TrafficView, MergeGroup]]
    key_groups: dict[int, MergeGroup]
    command: Callable[[int, float], None]  # drive a vehicle from outside (NaN: stop)
    _follow: Callable[[IntArray, IntArray], FloatArray]  # car following behind leaders
    _state: Callable[[], dict[str, np.ndarray]]  # the state a broadcast carries
    _view: Callable[[float], TrafficView]  # the true state, as a controller reads it
    _execute: Callable[[MergePlan, int], None]  # put decision k's plan into force
    _may_execute: Callable[[int], bool]  # whether VR is still on the ramp, not changing
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
        self._pending: list[tuple[float, int, MergePlan]] = []  # (arrival, decision, plan)
        self._broadcast_every = max(1, round(self.channel_params.period / self.dt))
        self.plans_lost = 0
        self.degraded_steps = 0
        self.commanded_at: dict[int, frozenset[int]] = {}  # step -> commanded vehicles

    def _channel_step(self, t: float) -> None:
        """Broadcast (every update period), deliver the messages and plans due at ``t``,
        and degrade the CAVs whose leader went silent; nothing on the ideal channel."""
        if self.channel_params.ideal:
            return
        if (self.step_index - self.n_warmup) % self._broadcast_every == 0:
            self.channel.broadcast(t, self._state())
        self.channel.deliver(t)
        self._deliver_plans(t)
        self._degrade(t)

    def _tell_fault_of_entry(self, groups_before: int, t: float) -> None:
        """Start the fault's clock if a ramp vehicle entered the control zone (its key
        vehicles were found) since there were ``groups_before`` key groups."""
        if len(self.key_groups) > groups_before:
            self.fault.on_entry(self, next(reversed(self.key_groups.values())), t)

    def _waiting(self) -> set[int]:
        """Ramp vehicles whose plan is on its way."""
        return {p.group.vr for _, _, p in self._pending}

    def _decision(self, vr: int, t: float) -> tuple[TrafficView, MergeGroup, MergePlan]:
        """Decide for ramp vehicle ``vr`` at ``t`` on the channel's view, record the decision
        (as the engines do: :func:`hcomc.sim.plan_execution.record_decision`) and send the
        plan; returns the view the controller saw, the key vehicles and the plan."""
        assert self.controller is not None
        self.planned[vr] = True
        self._next_plan.pop(vr, None)
        view = self._view(t)
        group = find_key_vehicles(view, vr)
        seen = view if self.channel_params.ideal else self.channel.view(view)
        plan = checked(self._decide(seen, group), seen, group, name_of(self.controller))
        record_decision(self, seen, group, plan, t)
        self._send(plan, len(self.decisions) - 1, t)
        return seen, group, plan

    def _send(self, plan: MergePlan, ident: int, t: float) -> None:
        """Execute decision ``ident`` now (ideal channel), when it arrives, or never (lost:
        its VR is planned again a replan period later)."""
        delay = 0.0 if self.channel_params.ideal else self.channel.plan_delay()
        if math.isinf(delay):
            self.plans_lost += 1
            self._next_plan[plan.group.vr] = t + self.config.control.replan_period
        elif delay == 0.0:
            self._execute(plan, ident)
        else:
            self._pending.append((t + delay, ident, plan))

    def _deliver_plans(self, t: float) -> None:
        """Execute the plans that arrived by ``t`` whose VR can still act on them."""
        arrived = [(ident, p) for when, ident, p in self._pending if when <= t + 1e-9]
        self._pending = [item for item in self._pending if item[0] > t + 1e-9]
        for ident, plan in arrived:
            if self._may_execute(plan.group.vr):
                self._execute(plan, ident)

    def _lost_due(self, t: float) -> list[int]:
        """Ramp vehicles whose last plan was lost and that are due for a new one."""
        due = [vr for vr, when in self._next_plan.items() if when <= t + 1e-9]
        return [vr for vr in due if self._may_execute(vr)]

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
        on_road = np.flatnonzero(self.active)
        index = build_lane_index(on_road, self.lane[on_road], self.x[on_road])
        leaders = index.leader_of(np.searchsorted(on_road, ids))
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
