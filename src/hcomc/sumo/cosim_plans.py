"""The co-simulation's live plans and outside commands as its step listeners reach them.

:class:`CosimPlans` is the part of :class:`hcomc.sumo.cosim.SumoSimulation` that puts a
decision into force, names the commanded vehicles, holds or releases a commanded merge, and
drives a vehicle from outside: the methods of :class:`hcomc.interface.listener.ListenedRun`
that our engine offers on its plan table (:class:`hcomc.sim.engine_plans.EnginePlans`), here
acted out through TraCI:

* a vehicle driven from outside (:meth:`~hcomc.sumo.cosim_plans.CosimPlans.command`) gets
  ``setSpeed(v + a dt)`` under speed mode 0 (no SUMO check: the acceleration is clipped to
  the emergency deceleration and the speed to v >= 0, as our engine does) and lane-change
  mode 0 (no change of its own);
* the parameters the engine drives with (``driving``: time headway, jam gap, acceleration)
  are given to SUMO's vehicles (``tau``, ``minGap``, ``accel``) when a listener changes
  them.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.interface import MergePlan, Mode, follow
from hcomc.road import Kind, Lane
from hcomc.sim.plan_execution import ActivePlan, commanded
from hcomc.sumo.cosim_state import CosimState
from hcomc.sumo.routes import vehicle_id

__all__ = ["COMMANDED_SPEED_MODE", "DEFAULT_SPEED_MODE", "CosimPlans"]

DEFAULT_LC_MODE = 1621  # SUMO's default lane-change mode
# no own lane changes; a commanded change (already passed by our MOBIL safety criterion, as in
# our engine) only has to avoid immediate collisions, not SUMO's stricter comfort-gap check
COMMANDED_LC_MODE = 256
_FREE_SPEED_MODE = 0  # a vehicle driven from outside: SUMO checks nothing
DEFAULT_SPEED_MODE = 31  # SUMO's: safe speed, maximum acceleration and deceleration, ...
COMMANDED_SPEED_MODE = 27  # a plan's commanded speed: SUMO's default without bit 2, so it
# brakes beyond its type's comfortable `decel`, down to what the plan asks (at most the
# emergency deceleration, as our engine lets it)
_NO_LANE_CHANGES = 0


class CosimPlans(CosimState):
    """Live plans and outside commands of one co-simulation run."""

    # ---------------------------------------------------------------- plans
    def execute(self, plan: MergePlan, ident: int) -> None:
        """Put decision ``ident``'s ``plan`` into force, replacing its VR's live plan,
        commanding the CAVs it names but those a listener says ignore it."""
        ignores = frozenset().union(*(listener.ignores(plan) for listener in self.listeners))
        vr = plan.group.vr
        cav = self.fleet.kind == Kind.CAV
        active = ActivePlan(
            plan,
            vr_commanded=bool(cav[vr]) and bool(np.isfinite(plan.merge_x)) and vr not in ignores,
            vmc_commanded=plan.mode != Mode.NONE and plan.group.vmc not in ignores,
            vnr_commanded=plan.vv2 is not None and plan.group.vnr not in ignores,
        )
        previous = [p for p in self.plans if p.vr == vr]  # a replan replaces the live plan
        self.plans = [p for p in self.plans if p.vr != vr]
        self.plans.append(active)
        now = commanded(self.plans, self.x.size)
        for i in np.flatnonzero(commanded(previous, self.x.size) & ~now).tolist():
            self._release(i)  # no longer commanded: back to SUMO's own driving
        for i in np.flatnonzero(commanded([active], self.x.size)).tolist():
            self.sumo.vehicle.setLaneChangeMode(vehicle_id(i), COMMANDED_LC_MODE)

    def may_execute(self, vr: int) -> bool:
        """Whether ramp vehicle ``vr`` is in SUMO, on the ramp and not changing lanes."""
        return bool(self.active[vr] and self.lane[vr] == Lane.RAMP and not self.changing()[vr])

    def commanded(self) -> IntArray:
        """Vehicles a live plan commands now: VR until its plan releases it (on the ramp and in
        its commanded change), a commanded cooperating vehicle (VMC) and a commanded VNR."""
        ids = [i for p in self.plans for i, on in ((p.vr, p.vr_commanded and not p.released),
                                                   (p.plan.group.vmc, p.vmc_commanded),
                                                   (p.plan.group.vnr, p.vnr_commanded))
               if on and i >= 0]  # fmt: skip
        return np.unique(np.array(ids, dtype=np.int64))

    def merges_due(self) -> IntArray:
        """Ramp vehicles whose commanded merge may be requested from SUMO in the next step."""
        changing = self.changing()
        due = [p.vr for p in self.plans
               if p.vr_following and not changing[p.vr] and self.lane[p.vr] == Lane.RAMP
               and self.x[p.vr] >= p.plan.merge_x]  # fmt: skip
        return np.array(due, dtype=np.int64)

    def note(self, kind: int, vehicle: int, other: int = -1, value: float = 0.0) -> None:
        """Record a listener's event of ``kind`` now, at the vehicle's position."""
        self.log.add_event(self.t, kind, vehicle, other=other, x=self.x[vehicle], value=value)

    def hold_merge(self, vr: int) -> None:
        """Do not request VR's commanded merge in the next step."""
        self._held.add(vr)

    def release_merge(self, vr: int) -> None:
        """Release VR from its plan to SUMO's own merging."""
        for p in self.plans:
            if p.vr == vr:
                p.released = True
        self._release(vr)

    def _release(self, i: int) -> None:
        """Hand vehicle i back to SUMO: own lane changes, own speed, its type's lateral speed."""
        if not self.active[i]:
            return
        name = vehicle_id(i)
        self.sumo.vehicle.setLaneChangeMode(name, DEFAULT_LC_MODE)
        self.sumo.vehicle.setMaxSpeedLat(
            name, self.config.road.lane_width / float(self.fleet.lc_duration[i])
        )

    # -------------------------------------------------------- from outside
    def command(self, i: int, accel: float) -> None:
        """Drive vehicle ``i`` with ``accel`` [m/s^2] from the next step on; NaN hands it back."""
        if math.isnan(accel):
            self._outside.pop(i, None)
        else:
            self._outside[i] = float(accel)

    def follow(self, ids: IntArray, leader: IntArray) -> FloatArray:
        """Our car following (Eq. 1-3) behind ``leader``, with the nominal parameters."""
        s = self.x[leader] - self.fleet.length[leader] - self.x[ids]
        return follow(self.fleet, ids, s, self.v[ids], self.v[leader], self.a[leader])

    def _drive_outside(self) -> None:
        """Impose the outside accelerations; hand back the vehicles whose outside command
        ended (to their plan's command, or to SUMO)."""
        if not (self._outside or self._driven):
            return
        veh = self.sumo.vehicle
        ended = [i for i in self._driven - self._outside.keys() if self.active[i]]
        by_plan = commanded(self.plans, self.x.size) if ended else np.zeros(0, dtype=bool)
        for i in ended:
            name = vehicle_id(i)
            mode = COMMANDED_SPEED_MODE if i in self._speed_set else DEFAULT_SPEED_MODE
            veh.setSpeedMode(name, mode)
            planned = i in self._speed_set or by_plan[i]
            veh.setLaneChangeMode(name, COMMANDED_LC_MODE if planned else DEFAULT_LC_MODE)
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

    def _sync_parameters(self) -> None:
        """Give SUMO the time headway, jam gap and acceleration the vehicles drive with."""
        changed = self.active & (self._in_sumo != self.driving.matrix).any(axis=0)
        for i in np.flatnonzero(changed).tolist():
            name = vehicle_id(i)
            self.sumo.vehicle.setTau(name, float(self.driving.T[i]))
            self.sumo.vehicle.setMinGap(name, float(self.driving.s0[i]))
            self.sumo.vehicle.setAccel(name, float(self.driving.a[i]))
            self._in_sumo[:, i] = self.driving.matrix[:, i]
