"""Co-simulation: SUMO moves every vehicle, our controllers command the key CAVs.

:class:`SumoSimulation` has the surface of :class:`hcomc.sim.engine.Simulation` (``run() ->
SimulationLog``, ``decisions``, ``key_group``, ``key_groups``, ``fleet``, ``config``,
``seed``), so the runner, metrics, figures and reports work unchanged.

The scenario is the one ``hcomc export sumo`` writes (same road, vTypes, seeded demand, SUMO
options), run in process through libsumo. Every step:

1. SUMO advances one ``dt``; HDVs and uncommanded CAVs drive SUMO's IDM and LC2013.
2. The state is read back in our frame (the network's x, y are ours; the lane is the one the
   vehicle's centre is in, so it switches mid-manoeuvre as in our engine): the run's state
   and its reading are :class:`hcomc.sumo.cosim_state.CosimState`.
3. As in our engine, a ramp vehicle entering the control zone gets its key vehicles
   (:func:`hcomc.control.key_group.find_key_vehicles`) and the controller is asked for a
   plan on a read-only :class:`~hcomc.interface.TrafficView`.
4. Plans are executed with the engine's helpers (:mod:`hcomc.sim.plan_execution`): a commanded CAV
   whose virtual vehicle is ahead follows min(real leader, virtual leader) with our model
   (:func:`hcomc.interface.follow`), imposed on SUMO with ``setSpeed``; commanded lane changes
   pass our MOBIL safety criterion (b_safe, as in our engine) and are executed by
   ``changeLane`` with the plan's duration (lateral speed = lane width / duration); SUMO only
   rules out immediate collisions (lane-change mode 256), since its own check, built on the
   comfortable deceleration b, is stricter than the model the plans are made with.
   Commanded vehicles make no lane changes of their own while their plan lasts; a VR whose
   change has not begun three vehicle lengths before the acceleration-lane end is handed back
   to SUMO's own merging (logged as a fallback).

Collisions are found with our oriented-rectangle test (Eq. 7) on every logged row, as for any
external trajectory; SUMO's own collision count is kept in the log's metadata.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from hcomc.control.key_group import find_key_vehicles
from hcomc.interface import Mode, TrafficView, follow
from hcomc.road import Kind, Lane
from hcomc.sim import decision
from hcomc.sim.lane_change_decisions import Snapshot, decide
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.neighbours import build_lane_index
from hcomc.sim.plan_execution import ActivePlan, virtual_leaders
from hcomc.sim.step.motion import WAIT_SPEED, WAIT_ZONE
from hcomc.sumo.cosim_plans import COMMANDED_SPEED_MODE, DEFAULT_SPEED_MODE, CosimPlans
from hcomc.sumo.export import export_scenario
from hcomc.sumo.external import collision_events
from hcomc.sumo.network import edge_at, sumo_lane_of
from hcomc.sumo.routes import TYPE_IDS, route_id, vehicle_id

__all__ = ["SumoSimulation"]


class SumoSimulation(CosimPlans):
    """One run of a merge scenario in SUMO (libsumo), controlled by our merge controller."""

    # ------------------------------------------------------------------ run
    def run(self, progress: Callable[[int, int], None] | None = None) -> SimulationLog:
        """Warm up, then simulate ``duration`` seconds in SUMO, logging every interval."""
        total = self.n_warmup + self.n_steps
        with tempfile.TemporaryDirectory(prefix="hcomc-sumo-") as tmp:
            scenario = export_scenario(self.config, self.seed, Path(tmp))
            quiet = ["--no-step-log", "true", "--no-warnings", "true",
                     "--duration-log.disable", "true"]  # fmt: skip
            self.sumo.start(["sumo", "-c", str(scenario.sumocfg), *quiet])
            try:
                self._add_stalled()
                for _ in range(self.n_warmup):
                    self.step()
                self._record()
                for k in range(1, self.n_steps + 1):
                    self.step()
                    if k % self._log_every == 0:
                        self._record()
                    if progress is not None and self.step_index % 100 == 0:
                        progress(self.step_index, total)
                self._decide_and_execute()  # on the last state, as on every other
            finally:
                self.sumo.close()
        self.log.finish(self._rows)
        for t, kind, i, j, x in collision_events(self.log):
            self.log.add_event(t, kind, i, other=j, x=x)
        self.log.meta["vehicle_steps"] = self.vehicle_steps
        self.log.meta["sumo_collisions"] = self.sumo_collisions
        self.log.meta["sumo_teleports"] = self.sumo_teleports
        if progress is not None:
            progress(total, total)
        return self.log

    def _add_stalled(self) -> None:
        """The run's stalled vehicles (:mod:`hcomc.sim.stalled`) into SUMO before its first
        step, standing where our engine puts them: added on the acceleration lane at speed 0,
        kept at 0 and making no lane change. The undisturbed run has none."""
        if self.counterfactual:
            return
        veh = self.sumo.vehicle
        for i in self.stalled.tolist():
            x, lane = float(self.demand.x[i]), int(self.demand.lane[i])
            edge = edge_at(self.config, x, lane)  # its front at least a length into the edge
            name = vehicle_id(i)
            veh.add(name, route_id(edge.id), typeID=TYPE_IDS[Kind.HDV], depart="now",
                    departLane=str(sumo_lane_of(edge, lane)), departPos=f"{x - edge.x0:.6g}",
                    departSpeed="0")  # fmt: skip
            veh.setLaneChangeMode(name, 0)
            veh.setSpeed(name, 0.0)

    # ----------------------------------------------------------------- step
    def step(self) -> None:
        """Between the last step and this one: the listeners act (from the warm-up's end on),
        then the decisions and the plans' lane changes on the state SUMO last reported
        (:meth:`_decide_and_execute`); then the key CAVs are commanded and the outside
        commands imposed, SUMO advances by ``dt`` and the new state is read back."""
        if self.listeners and self.step_index >= self.n_warmup:
            t = self.t
            for listener in self.listeners:
                listener.before_step(self, t)
            self._sync_parameters()
        if self.step_index > 0:
            self._decide_and_execute()
        self._held.clear()
        if self.plans or self._speed_set:
            self._command_speeds()
        self._drive_outside()  # replaces a plan's command of the same vehicle
        self.sumo.simulationStep()
        self.step_index += 1
        t = self.t
        self._read_state(t)
        ids = np.flatnonzero(self.active)
        self.vehicle_steps += ids.size
        self.sumo_collisions += len(self.sumo.simulation.getCollisions())

    def _decide_and_execute(self) -> None:
        """Key vehicles and decisions (:meth:`_key_vehicles`), then the lane changes the live
        plans command, on the state SUMO last reported; after the listeners, as in our engine,
        so that a listener's hold of a merge applies to that merge's request."""
        t = self.t
        ids = np.flatnonzero(self.active)
        self._key_vehicles(ids, t)
        if self.plans:
            self._execute_plans(ids, t)
            self._finish_plans()

    # ---------------------------------------------------------------- plans
    def view(self, t: float, vr: int = -1) -> TrafficView:
        """Read-only copy of the state for a controller (as our engine builds it; the
        paper's road has one on-ramp, whoever ``vr`` is)."""
        state = {"x": self.x, "v": self.v, "a": self.a, "lane": self.lane,
                 "active": self.active, "changing": self.changing()}  # fmt: skip
        plans = tuple(p.plan for p in self.plans)
        return TrafficView.snapshot(t, state, self.fleet, self.config, plans)

    def _key_vehicles(self, ids: np.ndarray, t: float) -> None:
        """Key vehicles and (with a controller) a plan when a ramp vehicle enters the zone."""
        changing = self.changing()
        new = ids[
            (self.lane[ids] == Lane.RAMP)
            & ~changing[ids]
            & (self.x[ids] >= self.config.road.control_zone_start)
            & ~np.isin(ids, self.stalled)  # no ramp vehicle: nobody plans for it
        ]
        where = f"{self.config.name}, seed {self.seed}, SUMO"
        for vr in new.tolist():
            if vr not in self.key_groups:
                group = find_key_vehicles(self.view(t), vr)
                self.key_groups[vr] = group
                self.log.meta.setdefault("key_groups", []).append({"t": float(t),
                                                                   **group.as_dict()})  # fmt: skip
                for listener in self.listeners:
                    listener.on_key_vehicles(self, group, t)
            if self.controller is not None and not self.planned[vr]:
                for first in decision.undecided(self, [vr]):  # type: ignore[arg-type]
                    decision.decide(self, first, t, where)  # type: ignore[arg-type]
        if self.controller is None:
            return
        # receding horizon, as in the engine: replan until VR starts its lane change; and
        # whenever a listener asks
        period = self.config.control.replan_period
        on_ramp = (self.lane == Lane.RAMP) & ~changing & self.active
        due = [
            p.vr
            for p in self.plans
            if on_ramp[p.vr] and p.may_replan(t, period, self.x[p.vr], self.v[p.vr])
        ]
        for listener in self.listeners:
            due += listener.decisions_due(self, t)
        for vr in decision.undecided(self, due):  # type: ignore[arg-type]
            decision.decide(self, vr, t, where)  # type: ignore[arg-type]

    def _command_speeds(self) -> None:
        """Commanded CAVs follow min(real leader, virtual leader) with our model (Eq. 1-3)."""
        t = self.t
        fol, xv, vv, av, lv = virtual_leaders(self.plans, t, self.x, self.v, self.a,
                                              self.fleet.length)  # fmt: skip
        ahead = (xv > self.x[fol]) & self.active[fol]
        constrained: set[int] = set()
        if ahead.any():
            fol, xv, vv, av, lv = fol[ahead], xv[ahead], vv[ahead], av[ahead], lv[ahead]
            a_virtual = follow(self.fleet, fol, xv - lv - self.x[fol], self.v[fol], vv, av)
            a_real = self._follow_real(fol)
            acc = np.maximum(np.minimum(a_virtual, a_real),
                             -self.config.lane_change.emergency_decel)  # fmt: skip
            for i, a in zip(fol.tolist(), acc.tolist(), strict=True):
                target = max(0.0, float(self.v[i]) + a * self.dt)
                if i not in self._speed_set:  # braking beyond its type's decel, as ours
                    self.sumo.vehicle.setSpeedMode(vehicle_id(i), COMMANDED_SPEED_MODE)
                self.sumo.vehicle.setSpeed(vehicle_id(i), target)
                constrained.add(i)
        for i in self._speed_set - constrained:  # hand back to SUMO's IDM
            if self.active[i]:
                self.sumo.vehicle.setSpeedMode(vehicle_id(i), DEFAULT_SPEED_MODE)
                self.sumo.vehicle.setSpeed(vehicle_id(i), -1.0)
        self._speed_set = constrained

    def _follow_real(self, ids: np.ndarray) -> np.ndarray:
        """Our model's acceleration behind each vehicle's real leader in its lane."""
        act = np.flatnonzero(self.active)
        index = build_lane_index(act, self.lane[act], self.x[act])
        lead = index.leader_of(np.searchsorted(act, ids))
        has = lead >= 0
        safe = np.where(has, lead, ids)
        s = np.where(has, self.x[safe] - self.fleet.length[safe] - self.x[ids], np.inf)
        vl = np.where(has, self.v[safe], self.v[ids])
        al = np.where(has, self.a[safe], 0.0)
        return follow(self.fleet, ids, s, self.v[ids], vl, al)

    def _safe_change(self, i: int, target: int, ids: np.ndarray) -> bool:
        """Our MOBIL safety criterion for a commanded change of vehicle i to ``target``."""
        index = build_lane_index(ids, self.lane[ids], self.x[ids])
        pos = np.searchsorted(ids, [i])
        chosen, _ = decide(
            self.fleet, Snapshot(x=self.x, v=self.v, a=self.a), index, np.array([i]),
            self.lane[[i]], index.leader_of(pos), index.follower_of(pos),
            self.config.lane_change, self.lanes, np.array([target]), np.array([True]),
        )  # fmt: skip
        return bool(chosen.size)

    def _change_lane(self, i: int, target: int, duration: float) -> None:
        edge = edge_at(self.config, float(self.x[i]), int(self.lane[i]))
        name = vehicle_id(i)
        self.sumo.vehicle.setMaxSpeedLat(name, self.config.road.lane_width / duration)
        self.sumo.vehicle.changeLane(name, sumo_lane_of(edge, target), duration)

    def _execute_plans(self, ids: np.ndarray, t: float) -> None:
        """Start the lane changes the live plans command (as :mod:`hcomc.sim.plan_execution`)."""
        changing = self.changing()
        for p in self.plans:
            g = p.plan.group
            if p.plan.mode == Mode.LATERAL and p.vmc_commanded and not p.vmc_started:
                if self._safe_change(g.vmc, Lane.MAIN_2, ids):
                    self._change_lane(g.vmc, Lane.MAIN_2, float(self.fleet.lc_duration[g.vmc]))
                    p.vmc_started = True
                else:
                    self._fail(p, t)
            vr = g.vr
            if not p.released and not p.vr_started and self._waiting(vr, changing):
                self._fail(p, t)  # VR waits at the lane end, as our engine's plans fail
                continue
            if not p.vr_commanded or p.vr_started or p.released:
                continue
            if changing[vr]:  # SUMO is executing the commanded change
                p.vr_started = True
            elif self.x[vr] >= self.accel_end - 3.0 * self.fleet.length[vr]:
                # not begun 3 lengths before the lane end (our safety criterion or SUMO's
                # refused it): VR falls back to SUMO's own merging, as to gap acceptance
                self._fail(p, t)
                self._release(vr)
            elif (
                self.x[vr] >= p.plan.merge_x
                and vr not in self._held
                and self._safe_change(vr, Lane.MAIN_1, ids)
            ):
                # requested again every step until SUMO, whose own safety check also
                # applies, starts it
                self._change_lane(vr, Lane.MAIN_1, float(p.plan.vr_duration))

    def _fail(self, p: ActivePlan, t: float) -> None:
        """A failed plan (FALLBACK): VR on gap acceptance, VMC and VNR no longer commanded
        (:func:`hcomc.sim.step.plans.execute_plans`)."""
        g = p.plan.group
        p.released, p.vmc_commanded, p.vnr_commanded = True, False, False
        self.log.add_event(t, EventKind.FALLBACK, g.vr, other=g.vmc, x=self.x[g.vr])

    def _waiting(self, vr: int, changing: np.ndarray) -> bool:
        """Whether ramp vehicle ``vr`` waits at its lane's end (our engine's RAMP_WAIT; the
        end before a stalled vehicle where there is one)."""
        end = self.accel_end
        return bool(self.lane[vr] == Lane.RAMP and not changing[vr]
                    and self.v[vr] < WAIT_SPEED and self.x[vr] > end - WAIT_ZONE)  # fmt: skip

    def _finish_plans(self) -> None:
        for p in self.plans:
            g = p.plan.group
            merged = self.lane[g.vr] == Lane.MAIN_1 and self.origin[g.vr] == Lane.MAIN_1
            gone = not self.active[g.vr] or (g.vmc >= 0 and not self.active[g.vmc])
            p.done = merged or gone
            if p.done:
                for i in (g.vr, g.vmc, g.vnr):
                    if i >= 0:
                        self._release(i)
        self.plans = [p for p in self.plans if not p.done]
