"""A co-simulation in SUMO with a V2X channel, an injected fault and a safety shield.

:class:`FaultedSumoSimulation` is :class:`hcomc.sumo.cosim.SumoSimulation` (SUMO moves every
vehicle, our controller commands the key CAVs) with the channel, faults and shield of
:class:`hcomc.robustness.engine.FaultedSimulation`, acted out through TraCI:

* the controller plans on the channel's view, and its plan is executed when it arrives,
  or never (VR is planned again a replan period later); a CAV whose CAV leader is silent
  for longer than ``stale_after`` gets the degraded time headway as its SUMO ``tau``;
* a fault or the shield drives a vehicle from outside with ``setSpeed(v + a dt)`` under
  speed mode 0 (no SUMO check: the acceleration is clipped to the emergency deceleration
  and the speed to v >= 0, as our engine does) and lane-change mode 0 (no change of its
  own); an aggressive human driver's ``tau``, ``minGap`` and ``accel`` are set on its SUMO
  vehicle;
* the shield brakes commanded vehicles (the same RSS rule) and gates VR's commanded merge:
  unsafe, the change waits; three vehicle lengths before the lane end the co-simulation
  hands VR back to SUMO's own merging, as without the shield.

With the ideal channel, no fault and no shield the run is the co-simulation's nominal run.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.interface import MergeController, MergePlan, Mode, follow
from hcomc.road import Kind, Lane, lane_centre
from hcomc.robustness.impairments import Impairments
from hcomc.robustness.settings import ChannelParams, FaultParams, ShieldParams
from hcomc.robustness.shield import Override
from hcomc.sim.plan_execution import ActivePlan, commanded
from hcomc.sumo.cosim import _COMMANDED_LC_MODE, _DEFAULT_LC_MODE, SumoSimulation
from hcomc.sumo.routes import vehicle_id

__all__ = ["FaultedSumoSimulation"]

_FREE_SPEED_MODE = 0  # a vehicle driven from outside: SUMO checks nothing
_DEFAULT_SPEED_MODE = 31
_NO_LANE_CHANGES = 0


class FaultedSumoSimulation(Impairments, SumoSimulation):
    """One SUMO co-simulation of ``config`` with ``seed`` under ``channel``, ``fault`` and
    ``shield``."""

    def __init__(
        self,
        config: ScenarioConfig,
        seed: int | None = None,
        controller: MergeController | None = None,
        *,
        channel: ChannelParams | None = None,
        fault: FaultParams | None = None,
        shield: ShieldParams | None = None,
    ) -> None:
        super().__init__(config, seed, controller)
        self._impair(channel, fault, shield, self.fleet.matrix.copy())
        self._outside: dict[int, float] = {}  # vehicle -> acceleration a fault or shield sets
        self._driven: set[int] = set()  # vehicles under an outside command in SUMO now
        self._in_sumo = self.fleet.matrix.copy()  # the parameters each SUMO vehicle has

    # ----------------------------------------------------------------- step
    def step(self) -> None:
        """Channel, fault and shield on the state of ``t``, then the co-simulation's step."""
        if self.step_index >= self.n_warmup:
            self._between_steps()
        if not (self.plans or self._speed_set):  # else the step's speed commands do it
            self._drive_outside()
        super().step()

    def _between_steps(self) -> None:
        t = self.t
        self._channel_step(t)
        self.fault.act(self, t)
        self._sync_parameters()
        ids = np.flatnonzero(commanded(self.plans, self.x.size))
        if self.shield.params.enabled:
            self.shield.brake(self, t, ids)
        if ids.size:
            self.commanded_at[self.step_index] = frozenset(ids.tolist())

    def _command_speeds(self) -> None:
        """The plans' commands, then the outside ones, which replace them."""
        super()._command_speeds()
        self._drive_outside()

    def _drive_outside(self) -> None:
        """Impose the faults' and the shield's accelerations; hand back the vehicles whose
        outside command ended."""
        veh = self.sumo.vehicle
        ended = [i for i in self._driven - self._outside.keys() if self.active[i]]
        by_plan = commanded(self.plans, self.x.size) if ended else np.zeros(0, dtype=bool)
        for i in ended:
            name = vehicle_id(i)
            veh.setSpeedMode(name, _DEFAULT_SPEED_MODE)
            planned = i in self._speed_set or by_plan[i]
            veh.setLaneChangeMode(name, _COMMANDED_LC_MODE if planned else _DEFAULT_LC_MODE)
            if i not in self._speed_set:
                veh.setSpeed(name, -1.0)
        for i, accel in self._outside.items():
            if self.active[i]:
                name = vehicle_id(i)
                acc = max(accel, -self.config.lane_change.emergency_decel)
                veh.setSpeedMode(name, _FREE_SPEED_MODE)
                veh.setLaneChangeMode(name, _NO_LANE_CHANGES)
                veh.setSpeed(name, max(0.0, float(self.v[i]) + acc * self.dt))
        self._driven = set(self._outside)

    def command(self, i: int, accel: float) -> None:
        """Drive vehicle ``i`` with ``accel`` [m/s^2] from the next step on; NaN hands it back."""
        if math.isnan(accel):
            self._outside.pop(i, None)
        else:
            self._outside[i] = float(accel)

    def _sync_parameters(self) -> None:
        """Give SUMO the time headway, jam gap and acceleration the vehicles drive with."""
        changed = self.active & (self._in_sumo != self.driving.matrix).any(axis=0)
        for i in np.flatnonzero(changed).tolist():
            name = vehicle_id(i)
            self.sumo.vehicle.setTau(name, float(self.driving.T[i]))
            self.sumo.vehicle.setMinGap(name, float(self.driving.s0[i]))
            self.sumo.vehicle.setAccel(name, float(self.driving.a[i]))
            self._in_sumo[:, i] = self.driving.matrix[:, i]

    # ---------------------------------------------------------------- state
    def _state(self) -> dict[str, np.ndarray]:
        return {"x": self.x, "v": self.v, "a": self.a, "lane": self.lane,
                "active": self.active, "changing": self.changing()}  # fmt: skip

    @property
    def arrays(self) -> SimpleNamespace:
        """Lane occupancy for the shield: ``origin`` and ``target`` of a change (the lane the
        vehicle's centre is moving to, from its lateral offset)."""
        width = self.config.road.lane_width
        offset = np.sign(self.y - lane_centre(self.lane, width)).astype(np.int64)
        changing = self.changing()
        target = np.where(changing & (self.origin == self.lane), self.lane + offset, self.lane)
        return SimpleNamespace(x=self.x, lane=self.lane, origin=self.origin, target=target,
                               active=self.active)  # fmt: skip

    def _follow(self, ids: IntArray, leader: IntArray) -> FloatArray:
        """Our car following (Eq. 1-3) behind ``leader``."""
        s = self.x[leader] - self.fleet.length[leader] - self.x[ids]
        return follow(self.fleet, ids, s, self.v[ids], self.v[leader], self.a[leader])

    # ---------------------------------------------------------------- plans
    def _key_vehicles(self, ids: np.ndarray, t: float) -> None:
        before = len(self.key_groups)
        super()._key_vehicles(ids, t)
        self._tell_fault_of_entry(before, t)
        for vr in self._lost_due(t):
            self._plan(vr, t)

    def _plan(self, vr: int, t: float) -> None:
        """A decision on the channel's view (none while VR's last plan is on its way)."""
        if vr not in self._waiting():
            self._decision(vr, t)

    def _may_execute(self, vr: int) -> bool:
        """Whether ramp vehicle ``vr`` is in SUMO, on the ramp and not changing lanes."""
        return bool(self.active[vr] and self.lane[vr] == Lane.RAMP and not self.changing()[vr])

    def _execute(self, plan: MergePlan, ident: int) -> None:
        """Execute ``plan`` (replacing its VR's live plan), as the co-simulation does, less
        the commands of a vehicle that ignores them (``ident``: its decision's index)."""
        vr = plan.group.vr
        ignores = self.fault.ignores(plan)
        cav = self.fleet.kind == Kind.CAV
        active = ActivePlan(
            plan,
            vr_commanded=bool(cav[vr]) and bool(np.isfinite(plan.merge_x)) and vr not in ignores,
            vmc_commanded=plan.mode != Mode.NONE and plan.group.vmc not in ignores,
            vnr_commanded=plan.vv2 is not None and plan.group.vnr not in ignores,
        )
        previous = [p for p in self.plans if p.vr == vr]
        self.plans = [p for p in self.plans if p.vr != vr]
        self.plans.append(active)
        now = commanded(self.plans, self.x.size)
        for i in np.flatnonzero(commanded(previous, self.x.size) & ~now).tolist():
            self._release(i)
        for i in np.flatnonzero(commanded([active], self.x.size)).tolist():
            self.sumo.vehicle.setLaneChangeMode(vehicle_id(i), _COMMANDED_LC_MODE)

    def _safe_change(self, i: int, target: int, ids: np.ndarray) -> bool:
        """The co-simulation's check of a commanded change, and for VR's merge the shield's."""
        if not super()._safe_change(i, target, ids):
            return False
        if not self.shield.params.enabled or target != Lane.MAIN_1:
            return True
        bad = self.shield.unsafe_merge(self, i)
        if bad:
            self.shield.overrides.append(Override(self.t, i, bad[0], "hold_change"))
        return not bad
