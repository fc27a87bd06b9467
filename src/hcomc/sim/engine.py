"""Simulation engine: release -> perceive -> decide -> check -> integrate -> log.

State is struct-of-arrays over every vehicle of the run (``active`` marks those on the road).
All vehicles decide from the same snapshot, then all integrate, so update order cannot bias
results. Only this module writes state; its set-up (demand, fleet, compiled state arrays,
log) is :class:`hcomc.sim.engine_setup.EngineSetup`.

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

The per-step work runs in compiled kernels (:mod:`hcomc.sim.step.loop`); this class builds their
state and drives every step through one compiled driver
(:func:`~hcomc.sim.step.loop.run_steps`), many steps per call, live merge plans included
(executed from the plan table of the compiled state, :mod:`hcomc.sim.step.plans`). The
driver hands a step to Python only for its decisions: a ramp vehicle entering the control
zone (key vehicles, a first plan), a live plan due for a replan, and on every step of a run
whose CAVs confirm their lane changes by the game (Section III-B). Python then runs the
controller and finishes the step with the driver's own kernels, so where a step's decisions
are taken does not change the run. A run without a controller or listeners has no decisions
to take: the driver records its key groups itself and never hands a step to Python.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.config import ScenarioConfig
from hcomc.control.key_group import find_key_vehicles
from hcomc.interface import MergeGroup, MergePlan, TrafficView
from hcomc.interface.ramp import ramp_in
from hcomc.sim.decision import decide, undecided
from hcomc.sim.engine_plans import EnginePlans
from hcomc.sim.lane_table import L_LEFT, L_RIGHT, L_ZONE
from hcomc.sim.log import SimulationLog
from hcomc.sim.plan_execution import game_confirms
from hcomc.sim.step import loop as step_loop
from hcomc.sim.step import state as layout
from hcomc.sim.step.build import adopt_log_columns, widen_log

_NO_FLOAT = np.empty(0)


class Simulation(EnginePlans):
    """One run of a scenario with one seed.

    Parameters
    ----------
    config : validated scenario.
    seed : run seed; defaults to ``config.seed``. All randomness (demand, vehicle kinds,
        estimation errors) comes from one generator derived from it.
    controller : merge controller; defaults to the one ``config.control`` names.
    counterfactual : the undisturbed run: the same demand and random streams, but ramp
        vehicles are never released (nothing merges).
    listeners : step listeners (:class:`hcomc.interface.listener.StepListener`).
    scene : draws the road, demand and fleet of the run
        (:data:`hcomc.sim.scene.SceneMaker`); by default the paper's road with the
        scenario's demand and fleet (:func:`hcomc.sim.scene.paper_scene`).
    """

    # ------------------------------------------------------------------ run
    @classmethod
    def run_together(cls, sims: Sequence[Simulation], *, threads: int | None = None) -> None:
        """Run ``sims`` to their ends as one ensemble (:func:`hcomc.sim.ensemble.run_ensemble`,
        on ``threads`` cores): the batching capability of :func:`hcomc.interface.run_all`.
        Each run's log is bit-identical to running it alone. A run with step listeners runs
        alone (they act between its steps, in Python)."""
        from hcomc.sim.ensemble import run_ensemble

        for sim in sims:
            if sim.listeners:
                sim.run()
        run_ensemble([sim for sim in sims if not sim.listeners], threads=threads)

    def run(self, progress: Callable[[int, int], None] | None = None) -> SimulationLog:
        """Warm up, then simulate ``duration`` seconds, logging every ``log_interval``
        (with listeners, from the warm-up's end one step at a time: :meth:`_listened_step`)."""
        total = self.n_warmup + self.n_steps
        if self.listeners:
            self.run_to(self.n_warmup)
        while not self.finished:
            if self.listeners and self.step_index >= self.n_warmup:
                self._listened_step()
                if progress is not None and self.step_index % 100 == 0:
                    progress(self.step_index, total)
                continue
            stop = self.stop_step
            if progress is not None:  # report every 100 steps
                stop = min(stop, (self.step_index // 100 + 1) * 100)
            self.resume(step_loop.run_steps(self.core, stop, self.logging, self.rng))
            if progress is not None and self.step_index % 100 == 0:
                progress(self.step_index, total)
        if progress is not None:
            progress(total, total)
        return self.log

    # The run as a sequence of compiled stretches (also driven by hcomc.sim.ensemble):
    # stage 0 warms up to ``n_warmup``, stage 1 logs to the end, stage 2 is done.
    @property
    def finished(self) -> bool:
        """Whether the run has reached its end (its log is complete)."""
        return self._stage == 2

    @property
    def stop_step(self) -> int:
        """Last step of the current stage."""
        return self.n_warmup if self._stage == 0 else self.n_warmup + self.n_steps

    @property
    def logging(self) -> bool:
        """Whether steps of the current stage write log rows."""
        return self._stage == 1

    def resume(self, reason: int) -> None:
        """Do what the compiled stretch that returned ``reason`` left to Python: empty the
        event buffer, write a row into a log that must grow first, take a step's decisions
        and the rest of that step (:meth:`_decision_step`, then its log row), or begin the
        next stage."""
        if reason == layout.FLUSH:
            self.flush_events()
        elif reason == layout.GROW_LOG:
            self._record()  # the row the compiled loop could not write
        elif reason == layout.NEED_PYTHON:
            self._decision_step()
            if not step_loop.record_due_row(self.core, self.logging):
                self._record()
        elif self.step_index >= self.stop_step:
            self._next_stage()

    def _next_stage(self) -> None:
        if self._stage == 0:
            # vehicles due at t = 0 are on the road in the first row; their events are moved
            # into the log with the stage's (every driver flushes before it returns)
            step_loop.release(self.core, self.t)
            self._record()
        else:
            self.flush_events()
            rows = int(self.arrays.counters[layout.ROWS])
            self.log.mark_recorded(rows)
            self.log.finish(rows)
            self.log.meta["vehicle_steps"] = self.vehicle_steps
        self._stage += 1

    def run_to(self, step: int, *, until_key_vehicles: bool = False) -> None:
        """Advance until step ``step`` (warm-up included; see :attr:`step_index`) or the end
        of the run, whichever comes first; with ``until_key_vehicles`` also stop after the
        step in which the first ramp vehicle's key vehicles were identified (it entered the
        control zone). Python is entered only at decision events."""
        flags = self.arrays.flags
        flags[layout.STOP_AT_KEYS] = until_key_vehicles  # for key groups found compiled
        try:
            while not self.reached(step, until_key_vehicles=until_key_vehicles):
                stop = min(self.stop_step, step)
                self.resume(step_loop.run_steps(self.core, stop, self.logging, self.rng))
        finally:
            flags[layout.STOP_AT_KEYS] = False
        self.flush_events()

    def reached(self, step: int, *, until_key_vehicles: bool = False) -> bool:
        """Whether :meth:`run_to` with these arguments has nothing left to do."""
        return (
            self.finished
            or self.step_index >= step
            or (until_key_vehicles and bool(self.key_groups))
        )

    # ----------------------------------------------------- driven from outside (agents)
    def command(self, i: int, accel: float) -> None:
        """Drive vehicle ``i`` from outside: from the next step on, its acceleration is
        ``accel`` [m/s^2] instead of its model's (still limited to the emergency
        deceleration and to v >= 0), and it makes no lane change of its own (no MOBIL, no gap
        acceptance, no braking for the lane end); NaN hands it back to its model."""
        layout.command(self.core, i, float(accel))

    def start_lane_change(self, i: int, target: int, duration: float = math.nan) -> None:
        """Start vehicle ``i``'s quintic lane change (Eq. 4-6) to lane ``target`` now, with
        ``duration`` [s] (NaN: the vehicle's own); no safety check: a driving agent decides,
        and a collision it causes is logged like any other."""
        if self.origin[i] != self.target[i] or not self.active[i]:
            raise ValueError(f"vehicle {i} is not on the road or already changing lanes")
        beside = self.lanes.ints[[L_LEFT, L_RIGHT], int(self.lane[i])]
        if int(target) < 0 or int(target) not in beside.tolist():
            raise ValueError(f"lane change of vehicle {i}: target lane {target} is not adjacent "
                             f"to its lane {int(self.lane[i])}")  # fmt: skip
        step_loop.start_lane_changes(
            self.core, np.array([i]), np.array([int(target)]), self.t, np.array([duration])
        )
        self.flush_events()

    def run_until_plan(self) -> MergePlan | None:
        """Step (without logging rows) until the first plan; None if the run ends first."""
        while not self.decisions and self.step_index < self.n_warmup + self.n_steps:
            self.step()
        return self.decisions[0] if self.decisions else None

    def _record(self) -> None:
        rows = int(self.arrays.counters[layout.ROWS])
        if rows >= self.log.n_steps:
            raise IndexError(f"row {rows} outside the log's {self.log.n_steps} rows")
        while not step_loop.record_row(self.core, rows, self.t):  # more vehicles than columns
            widen_log(self.config, self.log, int(np.count_nonzero(self.arrays.active)))
            self.arrays = adopt_log_columns(self.arrays, self.core, self.log)
        self.arrays.counters[layout.ROWS] = rows + 1

    def flush_events(self) -> None:
        """Move the compiled step's buffered events into the log, in order (the compiled
        stretches buffer them; :meth:`run_to` flushes when it returns), and the key groups it
        found (:meth:`take_key_groups`)."""
        self.take_key_groups()
        c = self.arrays
        n = int(c.counters[layout.N_EVENTS])
        if n == 0:
            return
        self.log.add_event_columns(c.ev_t[:n], c.ev_kind[:n], c.ev_vehicle[:n],
                                   c.ev_other[:n], c.ev_x[:n], c.ev_value[:n])  # fmt: skip
        c.counters[layout.N_EVENTS] = 0

    def _listened_step(self) -> None:
        """One step of a run with listeners: they act before it (:meth:`StepListener.before_step
        <hcomc.interface.listener.StepListener.before_step>`), then the step is taken compiled,
        or in Python when a listener asks for a decision the compiled loop does not know of; a
        stage that ended on a Python step is closed."""
        if self.step_index >= self.stop_step:
            self.resume(layout.DONE)
        elif self._listeners_act():
            self.resume(layout.NEED_PYTHON)
        else:
            self.run_to(self.step_index + 1)

    def _listeners_act(self) -> bool:
        """The listeners act before the step about to be taken; whether one of them wants a
        decision in it."""
        t = self.t
        for listener in self.listeners:
            listener.before_step(self, t)
        return any(listener.decisions_due(self, t) for listener in self.listeners)

    # ----------------------------------------------------------------- step
    def step(self) -> None:
        """Advance the whole traffic state by one step ``dt`` (no log row), through the same
        driver as :meth:`run` (:func:`hcomc.sim.step.loop.run_steps`): compiled, with Python
        only for a decision; listeners act before it from the warm-up's end on."""
        if self.listeners and self.step_index >= self.n_warmup and self._listeners_act():
            self._decision_step()
            return
        target = self.step_index + 1
        while self.step_index < target:
            reason = step_loop.run_steps(self.core, target, False, self.rng)
            if reason == layout.FLUSH:
                self.flush_events()
            elif reason == layout.NEED_PYTHON:
                self._decision_step()
        self.flush_events()

    def _begin_step(self) -> None:
        """The step's start (:func:`hcomc.sim.step.loop.begin_step`; a no-op when the compiled
        driver has done it), its events moved into the log before the decisions add theirs."""
        while not step_loop.begin_step(self.core, self.rng):
            self.flush_events()
        self.flush_events()

    def _decision_step(self) -> None:
        """One step with decisions: its start, the key vehicles and the controller's plans
        (Python), then the compiled loop's step (:func:`hcomc.sim.step.loop.step_alone`, or
        its parts around the lane-change game when CAVs confirm their changes by it), so a
        step taken here equals one taken there."""
        self.python_steps += 1
        self._begin_step()
        t = self.t
        ids = np.flatnonzero(self.active)
        if ids.size:
            changing = self.origin[ids] != self.target[ids]
            self._identify_key_vehicles(ids, changing, t)
            if self.controller is not None:
                self._plan_new(ids, changing, t)
        if self.config.lane_change.cav_game:
            self._game_step(t)
        else:
            step_loop.step_alone(self.core, t)
        self.flush_events()

    def _game_step(self, t: float) -> None:
        """The compiled step with the CAVs' discretionary changes confirmed by the lane-change
        game (Section III-B) between its front and its back."""
        ids = step_loop.on_road(self.core)
        if ids.size == 0:
            return
        acc, changing, index, lead = step_loop.step_front(self.core, ids, t)
        if self.step_index % self._decide_every == 0 and self.config.scenario != "platoon":
            chosen, target = step_loop.discretionary_changes(
                self.core, ids, changing, step_loop.holding(self.core), lead, index
            )
            if chosen.size:
                keep = game_confirms(
                    self.x, self.v, self.lane, self.fleet, self.config, chosen, target, ids,
                    lead, index,
                )  # fmt: skip
                chosen, target = chosen[keep], target[keep]
            step_loop.start_lane_changes(self.core, chosen, target, t, _NO_FLOAT)
        step_loop.step_back(self.core, ids, t, acc, index)

    def follow(self, ids: IntArray, leader: IntArray) -> FloatArray:
        """Car-following acceleration behind ``leader`` (-1: none), HDVs perceiving Eq. 2."""
        ids = np.ascontiguousarray(ids, dtype=np.int64)
        return step_loop.follow_many(self.core, ids, np.ascontiguousarray(leader, dtype=np.int64))

    # ---------------------------------------------------------------- plans
    def view(self, t: float, vr: int = -1) -> TrafficView:
        """Read-only copy of the state for a controller deciding for ramp vehicle ``vr``,
        with the on-ramp of its lane (:func:`hcomc.interface.ramp.ramp_in`: the road's first
        on-ramp when ``vr`` is -1 or has left its ramp lane)."""
        state = {"x": self.x, "v": self.v, "a": self.a, "lane": self.lane,
                 "active": self.active, "changing": self.origin != self.target}  # fmt: skip
        plans = tuple(p.plan for p in self.plans)
        ramp = ramp_in(self.ramps, int(self.lane[vr]) if vr >= 0 else -1)
        return TrafficView.snapshot(t, state, self.fleet, self.config, plans, ramp)

    def _in_control_zone(self, ids: IntArray, changing: np.ndarray) -> IntArray:
        """The vehicles of ``ids`` in a ramp lane's control zone, keeping their lane
        (``changing`` per vehicle of ``ids``), stalled vehicles aside."""
        zone = self.arrays.road_f[L_ZONE, self.lane[ids]]
        inside = ids[~changing & (self.x[ids] >= zone)]
        return inside[~np.isin(inside, self.stalled)] if self.stalled.size else inside

    def _identify_key_vehicles(self, ids: IntArray, changing: np.ndarray, t: float) -> None:
        """Record each ramp vehicle's key vehicles when it enters the control zone.

        This happens for every run, with or without a controller and before any control
        acts, so metrics compare the same physical vehicles across controllers.
        """
        for vr in self._in_control_zone(ids, changing).tolist():
            self.arrays.identified[vr] = True
            if vr in self.key_groups:
                continue
            group = find_key_vehicles(self.view(t, vr), vr)
            self.key_groups[vr] = group
            self.log.meta.setdefault("key_groups", []).append({"t": float(t), **group.as_dict()})
            for listener in self.listeners:
                listener.on_key_vehicles(self, group, t)

    @property
    def key_group(self) -> MergeGroup | None:
        """Key vehicles of the first ramp vehicle that entered the control zone (or None)."""
        return next(iter(self.key_groups.values()), None)

    def _plan_new(self, ids: IntArray, changing: np.ndarray, t: float) -> None:
        """Ask the controller for a plan when a ramp vehicle enters the control zone, and again
        every ``control.replan_period`` seconds while its plan may still change (receding
        horizon, key vehicles re-identified: :func:`hcomc.sim.step.plans.due_plans`) or when a
        listener asks; one decision each (:func:`hcomc.sim.decision.decide`: the plan is
        checked, recorded and put into force by :meth:`execute`)."""
        new = self._in_control_zone(ids, changing)
        new = new[~self.planned[new]]
        due = step_loop.due_plans(self.core, t).tolist()
        for listener in self.listeners:
            due += listener.decisions_due(self, t)
        where = f"{self.config.name}, seed {self.seed}"
        for vr in undecided(self, [*new.tolist(), *due]):  # type: ignore[arg-type]
            decide(self, vr, t, where)  # type: ignore[arg-type]


def simulate(
    config: ScenarioConfig,
    seed: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SimulationLog:
    """Run ``config`` with ``seed`` and return its :class:`SimulationLog`."""
    return Simulation(config, seed).run(progress)


__all__ = ["Simulation", "simulate"]
