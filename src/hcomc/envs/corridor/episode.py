"""Corridor runs whose agents drive ramp CAVs: the episodes of ``hcomc/CorridorMerge-v0``
(one agent) and of the corridor's PettingZoo environment (every ramp CAV in a control zone).

:class:`CorridorAgents` is a corridor run on the corridor engine in which some ramp CAVs are
*agents' vehicles*: from its control-zone entry until its merge onto the mainline, a crash or
the episode's end, the engine drives such a vehicle at the acceleration its agent gives and
starts its lane change when told (:mod:`hcomc.sim.corridor.step`, "agents' vehicles");
every other vehicle drives the corridor's models (IDM, MOBIL, the route's mandatory
changes), and no merge controller runs.

Observation and reward are those of ``hcomc/Merge-v0`` (:mod:`hcomc.envs.observation`,
:class:`hcomc.envs.options.RewardWeights`) on the ramp's local view: its acceleration lane
and mainline lanes 0 and 1 as the paper's ramp, lane 1 and lane 2, the key vehicles
identified there as in Section II-A. Two differences, both because a corridor has continuous
demand: the efficiency term E is the agent vehicle's own Eq. 17 gain against its free-road
acceleration (the corridor has no undisturbed run without it to measure the mainline
vehicles' changes against, as its merge events have none), and the lane-change progress is
measured in time, ``(t - start) / duration``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from hcomc.config import ConfigError
from hcomc.config.fuel import FUEL_DEFAULT
from hcomc.corridor import Corridor
from hcomc.envs.observation import N_OBS, SafetyParams, Scene, observe, pair_safety
from hcomc.envs.options import RewardWeights
from hcomc.equations.car_following import follow_accel
from hcomc.equations.fuel import fuel_rate_scalar
from hcomc.road import VMC
from hcomc.sim.corridor.layout import KIND_ON
from hcomc.sim.corridor.motion import advance
from hcomc.sim.corridor.plans import fill_view
from hcomc.sim.corridor.setup import (
    allocate,
    build_fleet,
    build_layout,
    ramp_code,
    vehicles_of,
)
from hcomc.sim.corridor.state import (
    C_AGENTS,
    C_COLLISIONS,
    C_STEP,
    ON_ROAD,
    P_EMERGENCY,
)  # fmt: skip

__all__ = ["CorridorAgents", "CorridorEpisode", "CorridorStep", "PeriodTerms"]

Outcome = Literal["", "merged", "collision", "lane end"]
"""How an agent's drive ended in a step: not yet, its merge complete, a collision it is in,
or past the end of its acceleration lane without changing (the last two are crashes)."""


@dataclass
class PeriodTerms:
    """One agent's reward terms over one action period (or the part of it it drove)."""

    vmc: int  # VMC of its key vehicles at the period's start (-1: none)
    seconds: float = 0.0  # how long it drove [s]
    safety: float = 0.0  # Eq. 15 of its pairs at the end, over a_merg, capped at 1, x seconds
    fuel: float = 0.0  # Eq. 16 of its vehicle [mL]
    fuel_vmc: float = 0.0  # Eq. 16 of VMC [mL]
    gain: float = 0.0  # Eq. 17: its acceleration minus its free-road one, integrated [m/s]
    outcome: Outcome = ""

    @property
    def crashed(self) -> bool:
        return self.outcome in ("collision", "lane end")

    def reward(self, w: RewardWeights, *, with_vmc: bool, timeout: bool) -> float:
        """``- w.safety S - w.fuel F + w.efficiency E - w.time dt - w.collision [crash]
        - w.timeout [timeout]`` (F with VMC's fuel for ``with_vmc``, as ``hcomc/Merge-v0``)."""
        fuel = self.fuel + (self.fuel_vmc if with_vmc else 0.0)
        return (-w.safety * self.safety - w.fuel * fuel + w.efficiency * self.gain
                - w.time * self.seconds - w.collision * self.crashed
                - w.timeout * timeout)  # fmt: skip


class CorridorAgents:
    """Corridor ``c`` run with ``seed`` on the corridor engine, whose agents' vehicles are
    driven by actions (module docstring)."""

    def __init__(self, c: Corridor, seed: int, action_period: float) -> None:
        self.corridor, self.seed = c, int(seed)
        self.dt = c.corridor.step_length
        self.period_steps = round(action_period / self.dt)
        self.steps_total = round(c.corridor.duration / self.dt)
        self.layout = build_layout(c)
        self.fleet = build_fleet(c, self.layout, self.seed, c.corridor.duration)
        self.veh = vehicles_of(self.fleet)
        self.s = allocate(c, self.layout, self.fleet, c.corridor.duration, 0)
        self.agents: set[int] = set()
        n = self.fleet.depart.size
        self._target_view = np.zeros(n, dtype=np.int64)
        self._lc_x0, self._lc_xf = np.zeros(n), np.ones(n)
        ctl = c.control
        self._safety = SafetyParams(
            ctl.safety_delay_cav, ctl.safety_delay_hdv, ctl.safety_min_distance,
            ctl.safety_emergency_decel,
        )  # fmt: skip
        self._fuel = FUEL_DEFAULT.coefficients()

    @property
    def t(self) -> float:
        """The run's time now [s]."""
        return float(self.s.counters[C_STEP] * self.dt)

    @property
    def over(self) -> bool:
        """Whether the run has reached the corridor's duration."""
        return bool(self.s.counters[C_STEP] >= self.steps_total)

    def ramp_cavs(self, ramp: str | None = None) -> np.ndarray:
        """The CAVs of on-ramp ``ramp``'s demand (of every on-ramp for None), by departure."""
        f = self.fleet
        on = [o for o in f.origins if o != "main" and (ramp is None or o == ramp)]
        ids = np.concatenate([np.zeros(0, dtype=np.int64)] + [
            f.queue[f.queue_start[k] : f.queue_start[k + 1]] for k, o in enumerate(f.origins)
            if o in on])  # fmt: skip
        ids = ids[f.cav[ids]]
        return ids[np.argsort(f.depart[ids], kind="stable")]

    def entered(self, ids: np.ndarray) -> np.ndarray:
        """Those of ``ids`` that entered their control zone and have not merged."""
        s = self.s
        return ids[~np.isnan(s.ev_t[ids]) & np.isnan(s.merge_t[ids]) & (s.status[ids] == ON_ROAD)]

    def run_until(self, t: float) -> None:
        """Advance, vehicles on their own models, to time t (or the run's end)."""
        steps = min(round(t / self.dt), self.steps_total) - int(self.s.counters[C_STEP])
        if steps > 0:
            advance(self.layout, self.veh, self.s, steps)

    def step_once(self) -> None:
        """Advance one step."""
        advance(self.layout, self.veh, self.s, 1)

    # ------------------------------------------------------------------ agents
    def take(self, i: int) -> None:
        """Vehicle i becomes an agent's, driving on as it drove until its first action."""
        self.s.agent_acc[i] = self.s.a[i]
        self.agents.add(i)
        self.s.counters[C_AGENTS] = len(self.agents)

    def hand_back(self, i: int) -> None:
        """Vehicle i returns to its own model."""
        self.s.agent_acc[i], self.s.agent_lane[i] = np.nan, -1
        self.agents.discard(i)
        self.s.counters[C_AGENTS] = len(self.agents)

    def observe(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Agent i's observation now (:mod:`hcomc.envs.observation`'s layout on its ramp's
        local view, the key vehicles around it) and those key vehicles (role order)."""
        s, t, code = self.s, self.t, int(self.fleet.start_code[i])
        target = self._view(i, code)
        obs = np.zeros(N_OBS)
        lane_end = float(self.layout.code_x1[code])
        group = observe(obs, self._scene(target), i, i, lane_end)
        changing = s.target[i] != s.code[i]
        obs[4] = min(max((t - s.lc_start[i]) / s.lc_dur[i], 0.0), 1.0) if changing else 0.0
        return obs.astype(np.float32), group

    def _view(self, i: int, code: int) -> np.ndarray:
        """Fill the local view of on-ramp ``code`` now; the view's target lanes, with vehicle
        i's own target (ramp 0, lane 1, lane 2; -1 elsewhere)."""
        s = self.s
        fill_view(s, code, self.t)
        target = self._target_view
        target[:] = s.view_lane
        tgt = int(s.target[i])
        target[i] = 0 if tgt == code else 1 if tgt == 0 else 2 if tgt == 1 else -1
        return target

    def _scene(self, target: np.ndarray) -> Scene:
        """The local view filled by :meth:`_view` (its ``target`` lanes) as the observation's
        kernels read it: every vehicle keeps its view lane (the origin is the view lane)."""
        s = self.s
        return Scene(s.x, s.v, s.view_lane, s.view_active, self.veh.cav, self.veh.length,
                     s.view_lane, target, self._lc_x0, self._lc_xf)  # fmt: skip

    def apply(self, i: int, action: np.ndarray) -> None:
        """Set agent i's command for the next period: ``action[0]`` in [-1, 1] is the
        acceleration as a fraction of its maximum acceleration (> 0) or of the emergency
        deceleration (< 0); ``action[1] > 0`` starts its change onto the lane to its left,
        from its on-ramp lane between the start and the end of the acceleration lane, unless
        a change is under way (as ``hcomc/Merge-v0``)."""
        s, road = self.s, self.layout
        a = min(max(float(action[0]), -1.0), 1.0)
        s.agent_acc[i] = a * (self.veh.a[i] if a >= 0 else s.params[P_EMERGENCY])
        code = int(s.code[i])
        on_lane = road.code_kind[code] == KIND_ON and road.code_x0[code] <= s.x[i]
        if (float(action[1]) > 0 and s.target[i] == code and on_lane
                and s.x[i] <= road.code_x1[code]):  # fmt: skip
            s.agent_lane[i] = road.code_left[code]

    def run_period(self, groups: dict[int, np.ndarray]) -> dict[int, PeriodTerms]:
        """Advance one action period and score it per agent (``groups``: each agent's key
        vehicles at the period's start). An agent whose drive ends within the period (its
        merge, a crash) is handed back to its model at once; the period ends early when no
        agent is left."""
        s = self.s
        terms = {i: PeriodTerms(vmc=int(groups[i][VMC])) for i in sorted(self.agents)}
        driving = set(self.agents)
        for _ in range(self.period_steps):
            if not driving or self.over:
                break
            collisions = int(s.counters[C_COLLISIONS])
            v_before = {i: float(s.v[i]) for i in driving}
            self.step_once()
            for i in sorted(driving):
                term = terms[i]
                term.seconds += self.dt
                term.fuel += self._fuel_rate(i) * self.dt
                if term.vmc >= 0:
                    term.fuel_vmc += self._fuel_rate(term.vmc) * self.dt
                term.gain += (float(s.a[i]) - self._free_accel(i, v_before[i])) * self.dt
                term.outcome = self._outcome(i, collisions)
                if term.outcome:
                    term.safety = term.seconds * self._pair_safety(i)
                    driving.discard(i)
                    self.hand_back(i)
        for i in driving:
            terms[i].safety = terms[i].seconds * self._pair_safety(i)
        return terms

    def _fuel_rate(self, j: int) -> float:
        """Eq. 16 of vehicle j at the end of the step [mL/s] (0 off the road)."""
        if self.s.status[j] != ON_ROAD:
            return 0.0
        rate = fuel_rate_scalar(float(self.s.v[j]), float(self.s.a[j]), *self._fuel)
        return 0.0 if math.isnan(rate) else float(rate)

    def _free_accel(self, i: int, v: float) -> float:
        """Eq. 17's reference of vehicle i: its IDM on a free road at speed v, with the
        step's desired speed (the speed limit applied) [m/s^2]."""
        p = self.veh
        return float(follow_accel(math.inf, v, 0.0, 0.0, self.s.v0e[i], p.T[i], p.s0[i],
                                  p.a[i], p.b[i], p.delta[i], 0.0, False))  # fmt: skip

    def _pair_safety(self, i: int) -> float:
        """Eq. 15 over vehicle i's follower-leader pairs now, a fraction of a_merg."""
        s = self.s
        if s.status[i] != ON_ROAD:
            return 0.0
        target = self._view(i, int(self.fleet.start_code[i]))
        return float(pair_safety(self._scene(target), i, self._safety))

    def _outcome(self, i: int, collisions_before: int) -> Outcome:
        """How agent i's drive ended in the last step (:data:`Outcome`)."""
        s, road = self.s, self.layout
        if not math.isnan(s.merge_t[i]):
            return "merged"
        n = min(int(s.counters[C_COLLISIONS]), s.collisions.shape[0])
        if np.any(s.collisions[collisions_before:n, 1:3] == i):
            return "collision"
        code = int(s.code[i])
        if s.target[i] == code and road.code_kind[code] == KIND_ON and s.x[i] > road.code_x1[code]:
            return "lane end"
        return ""


@dataclass(frozen=True, slots=True)
class CorridorStep:
    """What one step of ``hcomc/CorridorMerge-v0`` returns."""

    obs: np.ndarray
    reward: float
    terminated: bool
    truncated: bool
    info: dict[str, object]


class CorridorEpisode:
    """One episode of ``hcomc/CorridorMerge-v0``: the agent drives the first CAV of on-ramp
    ``ramp`` departing at or after ``start_after`` [s] (so that the corridor has filled),
    from its control-zone entry (:meth:`start`) until its merge, a crash or a timeout."""

    def __init__(self, c: Corridor, ramp: str, seed: int, start_after: float,
                 action_period: float, max_episode_time: float,
                 reward: RewardWeights) -> None:  # fmt: skip
        self.run = CorridorAgents(c, seed, action_period)
        self.seed, self.reward, self.max_time = int(seed), reward, max_episode_time
        self.code = ramp_code(self.run.layout, ramp, c)
        later = self.run.ramp_cavs(ramp)
        later = later[self.run.fleet.depart[later] >= start_after]
        if later.size == 0:
            raise ConfigError(
                f"key 'start_after' = {start_after!r}: no CAV departs from on-ramp {ramp!r} "
                f"at or after it in seed {self.seed}'s demand (its CAV share and flow); "
                "allowed: an earlier time, or a ramp with connected vehicles"
            )
        self.ego = int(later[0])
        self.t0 = math.nan
        self.done = False
        self.group = np.full(6, -1, dtype=np.int64)

    @property
    def t(self) -> float:
        return self.run.t

    def start(self) -> np.ndarray:
        """Advance the run (every vehicle on its own model) until the ego enters its control
        zone; its first observation."""
        run, i = self.run, self.ego
        run.run_until(float(run.fleet.depart[i]))
        while math.isnan(run.s.ev_t[i]) and not run.over:
            run.step_once()
        if math.isnan(run.s.ev_t[i]):
            raise ConfigError(
                f"key 'start_after': the agent's vehicle {i} does not reach its control zone "
                f"within the corridor's duration ({run.corridor.corridor.duration:g} s); "
                "allowed: an earlier start_after or a longer corridor.duration"
            )
        self.t0 = self.t
        run.take(i)
        obs, self.group = run.observe(i)
        return obs

    def step(self, action: np.ndarray) -> CorridorStep:
        """Drive one action period (fewer steps if the episode ends within it)."""
        run, i = self.run, self.ego
        run.apply(i, action)
        term = run.run_period({i: self.group})[i]
        timeout = not term.outcome and (self.t - self.t0 >= self.max_time - 1e-9 or run.over)
        self.done = bool(term.outcome) or timeout
        obs, self.group = run.observe(i)
        info: dict[str, object] = {
            "seed": self.seed, "t": self.t, "ego": i, "merged": term.outcome == "merged",
            "crashed": term.crashed, "outcome": term.outcome or ("timeout" if timeout else ""),
            "safety": term.safety, "fuel_ml": term.fuel + term.fuel_vmc, "gain": term.gain,
        }  # fmt: skip
        reward = term.reward(self.reward, with_vmc=True, timeout=timeout)
        return CorridorStep(obs, reward, bool(term.outcome), timeout, info)
