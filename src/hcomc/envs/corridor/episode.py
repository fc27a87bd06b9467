"""Corridor runs whose agents drive ramp CAVs: the episodes of ``hcomc/CorridorMerge-v0``
(one agent) and of the corridor's PettingZoo environment (every ramp CAV in a control zone).

:class:`CorridorAgents` is a corridor run on the engine (the corridor as a scene,
:mod:`hcomc.sim.corridor_scene`) in which some ramp CAVs are *agents' vehicles*: from its
control-zone entry until its merge onto the mainline, a crash or the episode's end, the
engine drives such a vehicle at the acceleration its agent gives and starts its lane change
when told (:meth:`hcomc.sim.engine.Simulation.command`,
:meth:`~hcomc.sim.engine.Simulation.start_lane_change`); every other vehicle drives the
models of every run (Eq. 2 perception, IDM, MOBIL, the route's mandatory changes), and no
merge controller runs.

Observation and reward are those of ``hcomc/Merge-v0`` (:mod:`hcomc.envs.observation`,
:class:`hcomc.envs.options.RewardWeights`) on the ramp's local view: its acceleration lane
and mainline lanes 0 and 1 as the paper's ramp, lane 1 and lane 2, the key vehicles
identified there as in Section II-A. One difference, because a corridor has continuous
demand: the efficiency term E is the agent vehicle's own Eq. 17 gain against its free-road
acceleration (the corridor has no undisturbed run without it to measure the mainline
vehicles' changes against, as its merge events have none).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from hcomc.config import ConfigError
from hcomc.config.fuel import FUEL_DEFAULT
from hcomc.corridor import Corridor
from hcomc.corridor.layout import ramp_codes
from hcomc.envs.observation import N_OBS, SafetyParams, Scene, observe, pair_safety
from hcomc.envs.options import RewardWeights
from hcomc.equations.fuel import fuel_rate_scalar
from hcomc.road import VMC, Kind
from hcomc.sim.corridor_scene import corridor_config, corridor_scene
from hcomc.sim.lane_table import KIND_ON, L_END, L_KIND, L_LEFT, L_OPENS
from hcomc.sim.log import EventKind
from hcomc.sim.roads import ramp_of

__all__ = ["CorridorAgents", "CorridorEpisode", "CorridorStep", "PeriodTerms"]

_LOG_EVERY = 60.0
"""The log's interval in an environment's run [s]: it reads the engine's state, not the log."""

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
    """Corridor ``c`` run with ``seed`` on the engine, whose agents' vehicles are driven by
    actions (module docstring)."""

    def __init__(self, c: Corridor, seed: int, action_period: float) -> None:
        from hcomc.sim.engine import Simulation

        self.corridor, self.seed = c, int(seed)
        self.dt = c.corridor.step_length
        self.period_steps = round(action_period / self.dt)
        self.steps_total = round(c.corridor.duration / self.dt)
        # no controller; a row of the log a minute (the environment reads the state)
        config = corridor_config(c, control={"controller": "none"}, log_interval=_LOG_EVERY)
        self.sim = Simulation(config, self.seed, scene=corridor_scene(c))
        self.lanes = self.sim.lanes
        self.agents: set[int] = set()
        self.is_cav = self.sim.fleet.kind == int(Kind.CAV)
        ctl = c.control
        self._safety = SafetyParams(
            ctl.safety_delay_cav, ctl.safety_delay_hdv, ctl.safety_min_distance,
            ctl.safety_emergency_decel,
        )  # fmt: skip
        self._fuel = FUEL_DEFAULT.coefficients()

    @property
    def t(self) -> float:
        """The run's time now [s]."""
        return self.sim.step_index * self.dt

    @property
    def over(self) -> bool:
        """Whether the run has reached the corridor's duration."""
        return self.sim.step_index >= self.steps_total

    def depart(self, i: int) -> float:
        """Vehicle i's departure time [s]."""
        return float(self.sim.demand.t[i]) + self.sim.config.warmup

    def ramp_cavs(self, ramp: str | None = None) -> np.ndarray:
        """The CAVs of on-ramp ``ramp``'s demand (of every on-ramp for None), by departure."""
        codes = ramp_codes(self.corridor.road)
        ramps = [r.id for r in self.corridor.road.on_ramps if ramp is None or r.id == ramp]
        lanes = [codes[r] for r in ramps]
        return np.flatnonzero(np.isin(self.sim.demand.lane, lanes) & self.is_cav)

    def entered(self, ids: np.ndarray) -> np.ndarray:
        """Those of ``ids`` that entered their control zone and have not merged (on the
        road, in their ramp lane)."""
        sim = self.sim
        zoned = np.array([int(i) in sim.key_groups for i in ids], dtype=bool)
        on_ramp = self.lanes.ints[L_KIND, sim.lane[ids]] == KIND_ON
        return ids[zoned & sim.active[ids] & on_ramp]

    def run_until(self, t: float) -> None:
        """Advance, vehicles on their own models, to time t (or the run's end)."""
        self.sim.run_to(min(round(t / self.dt), self.steps_total))

    def step_once(self) -> None:
        """Advance one step."""
        self.sim.run_to(self.sim.step_index + 1)

    # ------------------------------------------------------------------ agents
    def take(self, i: int) -> None:
        """Vehicle i becomes an agent's, driving on as it drove until its first action."""
        self.sim.command(i, float(self.sim.a[i]))
        self.agents.add(i)

    def own_model(self, i: int) -> None:
        """Agent i drives its own model until its next action."""
        self.sim.command(i, math.nan)

    def hand_back(self, i: int) -> None:
        """Vehicle i returns to its own model for good."""
        self.own_model(i)
        self.agents.discard(i)

    def ramp_lane(self, i: int) -> int:
        """The code of the ramp lane vehicle i departed into."""
        return int(self.sim.demand.lane[i])

    def lane_end(self, i: int) -> float:
        """Where vehicle i's acceleration lane ends [m]."""
        return float(self.lanes.floats[L_END, self.ramp_lane(i)])

    def observe(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Agent i's observation now (:mod:`hcomc.envs.observation`'s layout on its ramp's
        local view, the key vehicles around it) and those key vehicles (role order)."""
        obs = np.zeros(N_OBS)
        group = observe(obs, self._scene(i), i, i, self.lane_end(i))
        return obs.astype(np.float32), group

    def _scene(self, i: int) -> Scene:
        """The engine's vehicles in the local view of vehicle i's on-ramp: its ramp lane as
        lane 0, the lane it joins as 1 and the one beyond as 2 (-1: every other lane)."""
        sim, ramp = self.sim, ramp_of(self.lanes, self.ramp_lane(i))
        local = np.full(self.lanes.n_lanes, -1, dtype=np.int64)
        for k, code in enumerate((ramp.lane, ramp.target, ramp.beyond)):
            if code >= 0:
                local[code] = k
        lane = local[sim.lane]
        return Scene(sim.x, sim.v, lane, sim.active & (lane >= 0), self.is_cav,
                     sim.fleet.length, local[sim.origin], local[sim.target], sim.lc_x0,
                     sim.lc_xf)  # fmt: skip

    def apply(self, i: int, action: np.ndarray) -> None:
        """Set agent i's command for the next period: ``action[0]`` in [-1, 1] is the
        acceleration as a fraction of its maximum acceleration (> 0) or of the emergency
        deceleration (< 0); ``action[1] > 0`` starts its change onto the lane to its left,
        from its on-ramp lane between the start and the end of the acceleration lane, unless
        a change is under way (as ``hcomc/Merge-v0``)."""
        sim, f = self.sim, self.lanes.floats
        a = min(max(float(action[0]), -1.0), 1.0)
        emergency = sim.config.lane_change.emergency_decel
        sim.command(i, a * (float(sim.fleet.matrix[3, i]) if a >= 0 else emergency))
        code = int(sim.lane[i])
        on_lane = code == self.ramp_lane(i) and f[L_OPENS, code] <= sim.x[i] <= f[L_END, code]
        if float(action[1]) > 0 and sim.origin[i] == sim.target[i] and on_lane:
            sim.start_lane_change(i, int(self.lanes.ints[L_LEFT, code]))

    def run_period(self, groups: dict[int, np.ndarray]) -> dict[int, PeriodTerms]:
        """Advance one action period and score it per agent (``groups``: each agent's key
        vehicles at the period's start). An agent whose drive ends within the period (its
        merge, a crash) is handed back to its model at once; the period ends early when no
        agent is left."""
        sim = self.sim
        terms = {i: PeriodTerms(vmc=int(groups[i][VMC])) for i in sorted(self.agents)}
        driving = set(self.agents)
        for _ in range(self.period_steps):
            if not driving or self.over:
                break
            events = sim.log.n_events
            ids = np.array(sorted(driving), dtype=np.int64)
            free = dict(zip(ids.tolist(), sim.follow(ids, np.full(ids.size, -1)).tolist(),
                            strict=True))  # fmt: skip
            self.step_once()
            for i in ids.tolist():
                term = terms[i]
                term.seconds += self.dt
                term.fuel += self._fuel_rate(i) * self.dt
                if term.vmc >= 0:
                    term.fuel_vmc += self._fuel_rate(term.vmc) * self.dt
                term.gain += (float(sim.a[i]) - free[i]) * self.dt
                term.outcome = self._outcome(i, events)
                if term.outcome:
                    term.safety = term.seconds * self._pair_safety(i)
                    driving.discard(i)
                    self.hand_back(i)
        for i in driving:
            terms[i].safety = terms[i].seconds * self._pair_safety(i)
        return terms

    def _fuel_rate(self, j: int) -> float:
        """Eq. 16 of vehicle j at the end of the step [mL/s] (0 off the road)."""
        if not self.sim.active[j]:
            return 0.0
        rate = fuel_rate_scalar(float(self.sim.v[j]), float(self.sim.a[j]), *self._fuel)
        return 0.0 if math.isnan(rate) else float(rate)

    def _pair_safety(self, i: int) -> float:
        """Eq. 15 over vehicle i's follower-leader pairs now, a fraction of a_merg."""
        if not self.sim.active[i]:
            return 0.0
        return float(pair_safety(self._scene(i), i, self._safety))

    def _outcome(self, i: int, events_before: int) -> Outcome:
        """How agent i's drive ended in the last step (:data:`Outcome`)."""
        sim, code = self.sim, int(self.sim.lane[i])
        new = sim.log.events_since(events_before)
        if np.any((new["kind"] == EventKind.MERGE) & (new["vehicle"] == i)):
            return "merged"
        hit = (new["kind"] == EventKind.COLLISION) & ((new["vehicle"] == i) | (new["other"] == i))
        if hit.any():
            return "collision"
        keeping = sim.origin[i] == sim.target[i]
        if keeping and code == self.ramp_lane(i) and sim.x[i] > self.lanes.floats[L_END, code]:
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
        later = self.run.ramp_cavs(ramp)
        later = later[self.run.sim.demand.t[later] + c.corridor.warmup >= start_after]
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
        run.run_until(run.depart(i))
        while i not in run.sim.key_groups and not run.over:
            run.step_once()
        if i not in run.sim.key_groups:
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
