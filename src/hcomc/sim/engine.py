"""Simulation engine: release -> perceive -> decide -> check -> integrate -> log.

State is struct-of-arrays over every vehicle of the run (``active`` marks those on the road).
All vehicles decide from the same snapshot, then all integrate, so update order cannot bias
results. Only this module writes state.

Lane changes follow the quintic path of Eq. 4-6 parametrised in x: the end point is predicted
as ``x_f = x_0 + max(v T_lc, 3 L)`` when the change starts and the true x(t) is mapped through
the fixed polynomial. The vehicle's ``lane`` switches when its centre crosses the lane line
(xi = 1/2); during the whole manoeuvre its acceleration is the Eq. 14 tanh blend of the
accelerations behind its origin-lane and target-lane leaders, and it is visible to followers
in both lanes. The acceleration lane ends at ``accel_lane_end``: ramp vehicles that have not
started merging stop there (a static obstacle seen exactly), a merge already begun is
completed.

Integration is ballistic: ``x += v dt + a dt^2 / 2``, ``v += a dt``, stopping exactly at v = 0.
Every vehicle's deceleration is limited to ``lane_change.emergency_decel``; a collision that
still happens is logged as an event, never hidden.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.config import ConfigError, ScenarioConfig
from hcomc.control.base import (
    MergeController,
    MergeGroup,
    MergePlan,
    Mode,
    TrafficView,
    find_key_vehicles,
)
from hcomc.models.quintic import lateral_offset
from hcomc.models.transition import blend_acceleration, transition_weight
from hcomc.rng import make_rng
from hcomc.road import Kind, Lane, lane_centre
from hcomc.safety.collision import vehicles_collide
from hcomc.sim.demand import generate_demand
from hcomc.sim.execution import ActivePlan, holding_lane, plan_record, virtual_leaders
from hcomc.sim.fleet import Fleet, follow
from hcomc.sim.log import EventKind, SimulationLog
from hcomc.sim.manifest import build_manifest
from hcomc.sim.mobil import Snapshot, decide
from hcomc.sim.neighbours import LaneIndex, build_lane_index
from hcomc.sim.perception import Perception

_WAIT_SPEED = 0.1  # [m/s] below this a ramp vehicle near the lane end counts as waiting
_WAIT_ZONE = 20.0  # [m] distance to the lane end within which waiting is logged


class Simulation:
    """One run of a scenario with one seed.

    Parameters
    ----------
    config : validated scenario.
    seed : run seed; defaults to ``config.seed``. All randomness (demand, vehicle kinds,
        estimation errors) comes from one generator derived from it.
    """

    def __init__(  # noqa: PLR0915 (allocates the state arrays one by one)
        self,
        config: ScenarioConfig,
        seed: int | None = None,
        controller: MergeController | None = None,
        *,
        counterfactual: bool = False,
    ) -> None:
        self.config = config
        self.counterfactual = counterfactual
        self.seed = config.seed if seed is None else seed
        self.rng = make_rng(self.seed)
        self.dt = config.dt
        demand = generate_demand(config, self.rng)
        self.demand = demand
        n = demand.n
        self.fleet = Fleet.build(config, demand.kind, demand.scripted)
        width = config.road.lane_width
        self.x = np.zeros(n)
        self.y = lane_centre(demand.lane, width)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.heading = np.zeros(n)
        self.lane = demand.lane.copy()
        self.origin = demand.lane.copy()  # lane a change started from (= lane when keeping)
        self.target = demand.lane.copy()  # lane a change goes to (= lane when keeping)
        self.lc_t0 = np.zeros(n)
        self.lc_x0 = np.zeros(n)
        self.lc_xf = np.ones(n)
        self.active = np.zeros(n, dtype=bool)
        self.waited = np.zeros(n, dtype=bool)
        self._profile = np.asarray(config.platoon.profile, dtype=np.float64)  # scripted leader
        self.lc_dur = self.fleet.lc_duration.copy()  # a merge plan may set VR's duration
        if controller is None:
            from hcomc.control.registry import make_controller

            controller = make_controller(config)
        self.controller = controller
        self.planned = np.zeros(n, dtype=bool)
        self.key_groups: dict[int, MergeGroup] = {}  # per VR, found at control-zone entry
        self.plans: list[ActivePlan] = []
        self.decisions: list[MergePlan] = []
        self.requests: list[tuple[TrafficView, MergeGroup]] = []  # what each plan was asked
        self.is_hdv = demand.kind == Kind.HDV
        self.perception = Perception(config.hdv, self.is_hdv, self.dt, self.rng)
        hdv = config.hdv
        self._perceive_hdv = (
            self.perception.errors
            or max(hdv.reaction_time_gap, hdv.reaction_time_speed, hdv.reaction_time_approach) > 0
        )
        # the undisturbed counterfactual: the same demand and random streams, but ramp
        # vehicles are never released (nothing merges)
        self._queues = [
            np.flatnonzero(demand.lane == lane)
            if not (counterfactual and lane == Lane.RAMP)
            else np.empty(0, dtype=np.int64)
            for lane in Lane
        ]
        self._queue_pos = [0] * len(Lane)
        self._colliding: set[tuple[int, int]] = set()
        self.n_warmup = round(config.warmup / self.dt)
        self.n_steps = round(config.duration / self.dt)
        self._log_every = round(config.log_interval / self.dt)
        self._decide_every = max(1, round(config.lane_change.decision_interval / self.dt))
        self.step_index = 0
        self.vehicle_steps = 0
        meta = build_manifest(
            seed=self.seed,
            config=config.model_dump(mode="json"),
            extra={"dt": self.dt, "log_interval": config.log_interval},
        )
        rows = self.n_steps // self._log_every + 1
        need = SimulationLog.bytes_needed(rows, n) / 2**30
        if need > config.log_memory_limit:
            raise ConfigError(
                f"key 'log_memory_limit' = {config.log_memory_limit} GiB: this run's log needs "
                f"{need:.2f} GiB ({rows} rows x {n} vehicles); allowed: a larger "
                "log_memory_limit, a coarser log_interval or a shorter duration"
            )
        self.log = SimulationLog.allocate(
            rows,
            n,
            dt=config.log_interval,
            kind=demand.kind,
            length=self.fleet.length,
            width=self.fleet.width,
            meta=meta,
        )
        self._rows = 0

    @property
    def t(self) -> float:
        """Current simulation time [s]; logging starts at t = 0 after the warm-up."""
        return -self.config.warmup + self.step_index * self.dt

    # ------------------------------------------------------------------ run
    def run(self, progress: Callable[[int, int], None] | None = None) -> SimulationLog:
        """Warm up, then simulate ``duration`` seconds, logging every ``log_interval``."""
        total = self.n_warmup + self.n_steps
        for _ in range(self.n_warmup):
            self.step()
            if progress is not None and self.step_index % 100 == 0:
                progress(self.step_index, total)
        self._release(self.t)  # vehicles due at t = 0 are on the road in the first row
        self._record()
        for k in range(1, self.n_steps + 1):
            self.step()
            if k % self._log_every == 0:
                self._record()
            if progress is not None and self.step_index % 100 == 0:
                progress(self.step_index, total)
        self.log.finish(self._rows)
        self.log.meta["vehicle_steps"] = self.vehicle_steps
        if progress is not None:
            progress(total, total)
        return self.log

    def run_until_plan(self) -> MergePlan | None:
        """Step (without logging rows) until the first plan; None if the run ends first."""
        while not self.decisions and self.step_index < self.n_warmup + self.n_steps:
            self.step()
        return self.decisions[0] if self.decisions else None

    def _record(self) -> None:
        self.log.record(
            self._rows,
            self.t,
            self.x,
            self.y,
            self.v,
            self.a,
            self.heading,
            self.lane,
            self.active,
        )
        self._rows += 1

    # ----------------------------------------------------------------- step
    def step(self) -> None:
        """Advance the whole traffic state by one step ``dt``."""
        t = self.t
        self._release(t)
        ids = np.flatnonzero(self.active)
        if ids.size:
            self.vehicle_steps += ids.size
            self._advance(ids, t)
        self.step_index += 1
        self.perception.push(self.step_index, self.x, self.v)

    def _advance(self, ids: IntArray, t: float) -> None:
        changing = self.origin[ids] != self.target[ids]
        ch = ids[changing]
        width = self.config.road.lane_width
        # followers in the target lane see a changer from its start; in the origin lane while
        # its body still overlaps that lane (its current lane always qualifies)
        reach = 0.5 * (width + self.fleet.width[ch])
        in_ori = np.abs(self.y[ch] - lane_centre(self.origin[ch], width)) < reach
        in_tgt = np.abs(self.y[ch] - lane_centre(self.target[ch], width)) < reach
        crossed = self.lane[ch] == self.target[ch]
        also = np.where(crossed, in_ori, True)
        other = np.where(crossed, self.origin[ch], self.target[ch])[also]
        entries = np.concatenate([ids, ch[also]])
        index = build_lane_index(entries, np.concatenate([self.lane[ids], other]), self.x[entries])
        self._identify_key_vehicles(ids, changing, t)
        if self.controller is not None:
            self._plan_new(ids, changing, t)
        lead = index.leader_of(np.arange(ids.size))
        if ch.size:
            # Eq. 14 blends the accelerations behind the origin- and target-lane leaders; on
            # top, the leader of every lane the body still overlaps must be respected
            lead[changing], _ = index.lookup(self.origin[ch], self.x[ch])
            lead_new, _ = index.lookup(self.target[ch], self.x[ch])
        acc = self._follow(ids, lead)
        if ch.size:
            a_ori, a_new = acc[changing], self._follow(ch, lead_new)
            psi = transition_weight(
                t - self.lc_t0[ch], self.lc_dur[ch], self.config.lane_change.transition_tolerance
            )
            blend = blend_acceleration(a_ori, a_new, psi)
            blend = np.where(in_ori, np.minimum(blend, a_ori), blend)
            acc[changing] = np.where(in_tgt, np.minimum(blend, a_new), blend)
        acc = self._stop_line(ids, changing, acc)
        if self.plans:
            acc = self._virtual_leaders(ids, acc, t)
        acc = np.maximum(acc, -self.config.lane_change.emergency_decel)
        acc = self._scripted(ids, acc, t)  # a scripted profile is followed exactly
        if self.plans:
            self._execute_plans(ids, changing, index, lead, t)
        if self.step_index % self._decide_every == 0:
            self._lane_changes(ids, changing, index, lead, t)
        self._check_collisions(index, t)
        self._integrate(ids, acc)
        self._lateral(t)
        self._bookkeeping(ids, t)
        if self.plans:
            self._finish_plans()
        self.perception.advance_errors(ids[self.is_hdv[ids]], self.rng)

    # ------------------------------------------------------------ perceive
    def _follow(self, ids: IntArray, leader: IntArray) -> FloatArray:
        """Car-following acceleration behind ``leader`` (-1: none), HDVs perceiving Eq. 2."""
        has = leader >= 0
        lead = np.where(has, leader, ids)
        lead_len = self.fleet.length[lead]
        s = np.where(has, self.x[lead] - lead_len - self.x[ids], np.inf)
        v = self.v[ids]
        vl = np.where(has, self.v[lead], v)
        al = np.where(has, self.a[lead], 0.0)
        if self._perceive_hdv:
            hdv = self.is_hdv[ids]
            if hdv.any():
                s[hdv], v[hdv], vl[hdv] = self.perception.perceive(
                    self.step_index, ids[hdv], leader[hdv], lead_len[hdv]
                )
        return follow(self.fleet, ids, s, v, vl, al)

    def _stop_line(self, ids: IntArray, changing: np.ndarray, acc: FloatArray) -> FloatArray:
        """Ramp vehicles that have not started merging stop at the acceleration-lane end,
        unless they follow a live merge plan (they brake for the end only if it fails)."""
        on_ramp = (self.lane[ids] == Lane.RAMP) & ~changing
        if self.plans:
            following = [p.vr for p in self.plans if p.vr_following]
            on_ramp &= ~np.isin(ids, following)
        if on_ramp.any():
            r = ids[on_ramp]
            s = self.config.road.accel_lane_end - self.x[r]
            a_stop = follow(self.fleet, r, s, self.v[r], np.zeros(r.size), np.zeros(r.size))
            acc[on_ramp] = np.minimum(acc[on_ramp], a_stop)
        return acc

    def _scripted(self, ids: IntArray, acc: FloatArray, t: float) -> FloatArray:
        """Scripted leaders reach the profile speed at t + dt exactly."""
        scripted = self.fleet.scripted[ids]
        if scripted.any():
            target = np.interp(t + self.dt, self._profile[:, 0], self._profile[:, 1])
            acc[scripted] = (target - self.v[ids[scripted]]) / self.dt
        return acc

    # ---------------------------------------------------------------- plans
    def _view(self, t: float) -> TrafficView:
        """Read-only copy of the state for a controller."""
        state = {"x": self.x, "v": self.v, "a": self.a, "lane": self.lane,
                 "active": self.active, "changing": self.origin != self.target}  # fmt: skip
        plans = tuple(p.plan for p in self.plans)
        return TrafficView.snapshot(t, state, self.fleet, self.config, plans)

    def _identify_key_vehicles(self, ids: IntArray, changing: np.ndarray, t: float) -> None:
        """Record each ramp vehicle's key vehicles when it enters the control zone.

        This happens for every run, with or without a controller and before any control
        acts, so metrics compare the same physical vehicles across controllers.
        """
        new = ids[
            (self.lane[ids] == Lane.RAMP)
            & ~changing
            & (self.x[ids] >= self.config.road.control_zone_start)
        ]
        for vr in new.tolist():
            if vr in self.key_groups:
                continue
            group = find_key_vehicles(self._view(t), vr)
            self.key_groups[vr] = group
            self.log.meta.setdefault("key_groups", []).append({"t": float(t), **group.as_dict()})

    @property
    def key_group(self) -> MergeGroup | None:
        """Key vehicles of the first ramp vehicle that entered the control zone (or None)."""
        return next(iter(self.key_groups.values()), None)

    def _plan_new(self, ids: IntArray, changing: np.ndarray, t: float) -> None:
        """Ask the controller for a plan when a ramp vehicle enters the control zone, and again
        every ``control.replan_period`` seconds while its plan may still change (receding
        horizon, key vehicles re-identified)."""
        assert self.controller is not None
        new = ids[
            (self.lane[ids] == Lane.RAMP)
            & ~changing
            & ~self.planned[ids]
            & (self.x[ids] >= self.config.road.control_zone_start)
        ]
        period = self.config.control.replan_period
        on_ramp = (self.lane == Lane.RAMP) & (self.origin == self.target) & self.active
        due = [
            p.vr
            for p in self.plans
            if on_ramp[p.vr] and p.may_replan(t, period, self.x[p.vr], self.v[p.vr])
        ]
        for vr in [*new.tolist(), *due]:
            self.planned[vr] = True
            view = self._view(t)
            group = find_key_vehicles(view, vr)
            plan = self.controller.plan(view, group, self.rng.spawn(1)[0])
            self.requests.append((view, group))
            self.decisions.append(plan)
            self.log.meta.setdefault("plans", []).append(plan_record(plan))
            self.log.add_event(t, EventKind.PLAN, vr, other=group.vmc, x=self.x[vr],
                               value=int(plan.mode))  # fmt: skip
            if plan.fallback:
                self.log.add_event(t, EventKind.FALLBACK, vr, other=group.vmc, x=self.x[vr])
            cav = self.fleet.kind == Kind.CAV
            self.plans = [p for p in self.plans if p.vr != vr]
            self.plans.append(
                ActivePlan(
                    plan,
                    vr_commanded=bool(cav[vr]) and bool(np.isfinite(plan.merge_x)),
                    vmc_commanded=plan.mode != Mode.NONE,
                    vnr_commanded=plan.vv2 is not None,
                )
            )

    def _virtual_leaders(self, ids: IntArray, acc: FloatArray, t: float) -> FloatArray:
        """Commanded vehicles also follow their virtual vehicle when it is ahead of them."""
        fol, xv, vv, av, lv = virtual_leaders(
            self.plans, t, self.x, self.v, self.a, self.fleet.length
        )
        ahead = xv > self.x[fol]
        if ahead.any():
            fol, xv, vv, av, lv = fol[ahead], xv[ahead], vv[ahead], av[ahead], lv[ahead]
            pos = np.searchsorted(ids, fol)
            a_v = follow(self.fleet, fol, xv - lv - self.x[fol], self.v[fol], vv, av)
            acc[pos] = np.minimum(acc[pos], a_v)
        return acc

    def _safe_change(
        self, i: int, target: int, ids: IntArray, index: LaneIndex, lead: IntArray
    ) -> bool:
        """MOBIL safety criterion for a commanded change of vehicle i to ``target``."""
        pos = np.searchsorted(ids, [i])
        chosen, _ = decide(
            self.fleet, Snapshot(x=self.x, v=self.v, a=self.a), index, np.array([i]),
            self.lane[[i]], lead[pos], index.follower_of(pos), self.config.lane_change,
            target=np.array([target]), force=np.array([True]),
        )  # fmt: skip
        return bool(chosen.size)

    def _execute_plans(
        self, ids: IntArray, changing: np.ndarray, index: LaneIndex, lead: IntArray, t: float
    ) -> None:
        """Start the lane changes the live plans command (see :mod:`hcomc.sim.execution`)."""
        road = self.config.road
        for p in self.plans:
            g = p.plan.group
            if p.plan.mode == Mode.LATERAL and p.vmc_commanded and not p.vmc_started:
                if self._safe_change(g.vmc, Lane.MAIN_2, ids, index, lead):
                    self._start_lane_changes(np.array([g.vmc]), np.array([Lane.MAIN_2]), t)
                    p.vmc_started = True
                else:
                    p.vmc_commanded = p.vnr_commanded = False
                    p.released = True
                    self.log.add_event(t, EventKind.FALLBACK, g.vr, other=g.vmc, x=self.x[g.vr])
            vr = g.vr
            if (
                not p.vr_commanded
                or p.vr_started
                or p.released
                or self.origin[vr] != self.target[vr]
            ):
                continue
            if self.x[vr] >= p.plan.merge_x:
                if self._safe_change(vr, Lane.MAIN_1, ids, index, lead):
                    self._start_lane_changes(
                        np.array([vr]), np.array([Lane.MAIN_1]), t, np.array([p.plan.vr_duration])
                    )
                    p.vr_started = True
                elif self.x[vr] >= road.accel_lane_end - self._stopping_distance(vr):
                    p.released = True
                    self.log.add_event(t, EventKind.FALLBACK, vr, other=g.vmc, x=self.x[vr])

    def _stopping_distance(self, i: int) -> float:
        """Distance vehicle i needs to stop at the MOBIL safe deceleration, plus s0 [m]."""
        b_safe = self.config.lane_change.safe_decel
        return float(self.v[i] ** 2 / (2.0 * b_safe) + self.fleet.s0[i])

    def _finish_plans(self) -> None:
        """Drop plans whose merge is complete or whose key vehicles left."""
        for p in self.plans:
            g = p.plan.group
            merged = self.lane[g.vr] == Lane.MAIN_1 and self.origin[g.vr] == self.target[g.vr]
            gone = not self.active[g.vr] or (g.vmc >= 0 and not self.active[g.vmc])
            p.done = merged or gone
        self.plans = [p for p in self.plans if not p.done]

    # --------------------------------------------------------------- decide
    def _lane_changes(
        self, ids: IntArray, changing: np.ndarray, index: LaneIndex, lead: IntArray, t: float
    ) -> None:
        if self.config.scenario == "platoon":
            return
        road = self.config.road
        lane, x = self.lane[ids], self.x[ids]
        on_accel_lane = (
            (lane == Lane.RAMP) & (x >= road.accel_lane_start) & (x <= road.accel_lane_end)
        )
        sel = ~changing & ~self.fleet.scripted[ids] & ((lane != Lane.RAMP) | on_accel_lane)
        if self.plans:
            sel &= ~holding_lane(self.plans, self.fleet.kind == Kind.CAV)[ids]
        pos = np.flatnonzero(sel)
        if pos.size == 0:
            return
        cand = ids[pos]
        snap = Snapshot(x=self.x, v=self.v, a=self.a)
        chosen, target = decide(
            self.fleet, snap, index, cand, lane[pos], lead[pos], index.follower_of(pos),
            self.config.lane_change,
        )  # fmt: skip
        if self.config.lane_change.cav_game and chosen.size:
            keep = self._game_confirms(chosen, target, ids, lead, index)
            chosen, target = chosen[keep], target[keep]
        self._start_lane_changes(chosen, target, t)

    def _game_confirms(
        self, chosen: IntArray, target: IntArray, ids: IntArray, lead: IntArray, index: LaneIndex
    ) -> np.ndarray:
        """Section III-B: a CAV's discretionary change must be its game equilibrium action
        (SV = the CAV, FV = its new follower); ramp merges and HDV changes are unaffected."""
        from hcomc.control.lane_change_game import game_params, game_vehicle, lane_change_game

        def vehicle(i: int):
            return game_vehicle(self.x, self.v, self.fleet, i)

        keep = np.ones(chosen.size, dtype=bool)
        new_lead, new_fol = index.lookup(target, self.x[chosen])
        old_lead = lead[np.searchsorted(ids, chosen)]
        cfg = self.config
        for k, i in enumerate(chosen.tolist()):
            if self.fleet.kind[i] != Kind.CAV or self.lane[i] == Lane.RAMP:
                continue
            fol = int(new_fol[k])
            fv_idm = cfg.cav if fol >= 0 and self.fleet.kind[fol] == Kind.CAV else cfg.hdv
            decision = lane_change_game(
                vehicle(i), vehicle(fol), vehicle(int(old_lead[k])), vehicle(int(new_lead[k])),
                params=game_params(cfg), sv_idm=cfg.cav, fv_idm=fv_idm,
            )  # fmt: skip
            keep[k] = decision.change
        return keep

    def _start_lane_changes(
        self, chosen: IntArray, target: IntArray, t: float, duration: FloatArray | None = None
    ) -> None:
        """Begin quintic lane changes (Eq. 4-6); x_f is predicted from the current speed."""
        if chosen.size == 0:
            return
        if duration is not None:
            self.lc_dur[chosen] = duration
        self.origin[chosen] = self.lane[chosen]
        self.target[chosen] = target
        self.lc_t0[chosen] = t
        self.lc_x0[chosen] = self.x[chosen]
        self.lc_xf[chosen] = self.x[chosen] + np.maximum(
            self.v[chosen] * self.lc_dur[chosen], 3.0 * self.fleet.length[chosen]
        )
        for i, tgt in zip(
            chosen.tolist(), np.broadcast_to(target, chosen.shape).tolist(), strict=True
        ):
            self.log.add_event(t, EventKind.LANE_CHANGE_START, i, x=self.x[i], value=tgt)

    # ---------------------------------------------------------------- check
    def _check_collisions(self, index: LaneIndex, t: float) -> None:
        """Oriented-rectangle test (Eq. 7) of each entry against its next two leaders per lane.

        A 1-D prefilter skips pairs whose x-extents cannot overlap: a rectangle whose front
        bumper centre is at x lies within ``[x - L - W/2, x + W/2]`` for any heading.
        """
        veh, lane = index.vehicle, index.lane
        f = self.fleet
        x = self.x[veh]
        front = x + 0.5 * f.width[veh]
        rear = x - f.length[veh] - 0.5 * f.width[veh]
        rows, cols = [], []
        for k in (1, 2):
            if veh.size > k:
                near = (lane[:-k] == lane[k:]) & (front[:-k] >= rear[k:]) & (veh[:-k] != veh[k:])
                rows.append(veh[:-k][near])
                cols.append(veh[k:][near])
        a = np.concatenate(rows) if rows else np.empty(0, dtype=np.int64)
        b = np.concatenate(cols) if cols else np.empty(0, dtype=np.int64)
        now: set[tuple[int, int]] = set()
        if a.size:
            hit = vehicles_collide(
                self.x[a],
                self.y[a],
                self.heading[a],
                f.length[a],
                f.width[a],
                self.x[b],
                self.y[b],
                self.heading[b],
                f.length[b],
                f.width[b],
            )
            now = {
                (min(i, j), max(i, j))
                for i, j in zip(a[hit].tolist(), b[hit].tolist(), strict=True)
            }
        for i, j in sorted(now - self._colliding):
            self.log.add_event(t, EventKind.COLLISION, i, other=j, x=self.x[i])
        self._colliding = now

    # ------------------------------------------------------------ integrate
    def _integrate(self, ids: IntArray, acc: FloatArray) -> None:
        """Ballistic update; a vehicle that would reverse stops exactly at v = 0."""
        dt = self.dt
        v0 = self.v[ids]
        v1 = v0 + acc * dt
        stops = v1 < 0.0
        safe_acc = np.where(stops, acc, 1.0)
        dx = np.where(stops, -(v0 * v0) / (2.0 * safe_acc), v0 * dt + 0.5 * acc * dt * dt)
        self.x[ids] += dx
        self.v[ids] = np.maximum(v1, 0.0)
        self.a[ids] = np.where(stops, -v0 / dt, acc)

    def _lateral(self, t: float) -> None:
        """Move changing vehicles along their quintic path; switch lane at the lane line."""
        ch = np.flatnonzero(self.active & (self.origin != self.target))
        if ch.size == 0:
            return
        width = self.config.road.lane_width
        x0, xf = self.lc_x0[ch], self.lc_xf[ch]
        y0, y1 = lane_centre(self.origin[ch], width), lane_centre(self.target[ch], width)
        y, dy_dx, _ = lateral_offset(self.x[ch], x0, xf, y0, y1)
        self.y[ch] = y
        self.heading[ch] = np.arctan(dy_dx)
        xi = (self.x[ch] - x0) / (xf - x0)
        self.lane[ch] = np.where(xi >= 0.5, self.target[ch], self.origin[ch])
        done = xi >= 1.0
        for i in ch[done].tolist():
            self.log.add_event(t, EventKind.LANE_CHANGE_END, i, x=self.x[i], value=self.target[i])
            if self.origin[i] == Lane.RAMP:
                self.log.add_event(t, EventKind.MERGE, i, x=self.x[i])
        fin = ch[done]
        self.lc_dur[fin] = self.fleet.lc_duration[fin]
        self.origin[fin] = self.target[fin]
        self.y[fin] = lane_centre(self.target[fin], width)
        self.heading[fin] = 0.0

    def _bookkeeping(self, ids: IntArray, t: float) -> None:
        """Exits past the road end; ramp vehicles waiting at the acceleration-lane end."""
        road = self.config.road
        gone = ids[self.x[ids] - self.fleet.length[ids] > road.length]
        if gone.size:
            self.active[gone] = False
            for i in gone.tolist():
                self.log.add_event(t, EventKind.EXIT, i, x=self.x[i])
        waiting = ids[
            (self.lane[ids] == Lane.RAMP)
            & (self.origin[ids] == self.target[ids])
            & (self.v[ids] < _WAIT_SPEED)
            & (self.x[ids] > road.accel_lane_end - _WAIT_ZONE)
            & ~self.waited[ids]
        ]
        for i in waiting.tolist():
            self.waited[i] = True
            self.log.add_event(t, EventKind.RAMP_WAIT, i, x=self.x[i])

    # -------------------------------------------------------------- release
    def _release(self, t: float) -> None:
        """Insert due vehicles lane by lane; a blocked entry waits (and blocks its queue)."""
        for lane, queue in enumerate(self._queues):
            pos = self._queue_pos[lane]
            while pos < queue.size and self.demand.t[queue[pos]] <= t + 1e-9:
                if not self._insert(int(queue[pos]), t):
                    break
                pos += 1
            self._queue_pos[lane] = pos

    def _insert(self, i: int, t: float) -> bool:
        """Place vehicle i at its release point if the gap to the vehicle ahead allows it.

        The release speed is kept if the gap exceeds ``s0 + v T``; otherwise the vehicle is
        released at the speed of the vehicle ahead if that gap suffices, else it waits.
        """
        d, f = self.demand, self.fleet
        x, v = d.x[i], d.v[i]
        if d.t[i] > -self.config.warmup + 1e-9:  # arrivals check the gap; the initial fill does not
            in_lane = self.active & ((self.lane == d.lane[i]) | (self.target == d.lane[i]))
            ahead = np.flatnonzero(in_lane & (self.x >= x))
            if ahead.size:
                j = ahead[np.argmin(self.x[ahead])]
                gap = self.x[j] - f.length[j] - x
                if gap < f.s0[i] + v * f.T[i]:
                    v = min(v, self.v[j])
                    if gap < f.s0[i] + v * f.T[i]:
                        return False
        self.x[i], self.v[i], self.active[i] = x, v, True
        self.perception.fill(np.array([i]), self.x, self.v)
        self.log.add_event(t, EventKind.INSERTION, i, x=x, value=t - d.t[i])
        return True


def simulate(
    config: ScenarioConfig,
    seed: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SimulationLog:
    """Run ``config`` with ``seed`` and return its :class:`SimulationLog`."""
    return Simulation(config, seed).run(progress)


__all__ = ["Simulation", "simulate"]
