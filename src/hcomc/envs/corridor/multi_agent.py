"""Cooperative multi-agent merging on a corridor: every ramp CAV in its on-ramp's control zone
is an agent, at every on-ramp at once (a PettingZoo ``ParallelEnv`` on the engine).

An agent ``"cav_<i>"`` is ramp CAV i from its control-zone entry until its merge onto the
mainline (or a crash: a collision it is in, or past the end of its acceleration lane); it is
then handed back to its own model. It joins in the step in which it entered (its first
observation comes with that step). The episode is a window of the corridor's traffic: from
``start_after`` seconds (or the first entry after it) for ``max_episode_time`` seconds, when
every agent still driving is truncated. When no agent is left before then, the run goes on
(every vehicle on its model) to the next entry.

Each agent has the spaces of ``hcomc/Merge-v0``, its observation the key vehicles of its own
merge on its ramp's local view (:mod:`hcomc.envs.corridor.episode`), and its reward its own
terms: Eq. 15 of its pairs, its Eq. 16 fuel, its Eq. 17 gain against its free road, the time
weight per second, the collision weight at its crash, the timeout weight on truncation. An
agent without an action in a step drives its own model for that period.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pettingzoo import ParallelEnv

from hcomc.config import ConfigError
from hcomc.envs.corridor.env import CorridorEnvSettings
from hcomc.envs.corridor.episode import CorridorAgents, PeriodTerms
from hcomc.envs.merge_env import action_space
from hcomc.envs.multi_agent import AgentSpaces, agent_name
from hcomc.envs.options import RewardWeights
from hcomc.rng import draw_seed

__all__ = ["CorridorParallelEnv"]

Returns = tuple[
    dict[str, np.ndarray], dict[str, float], dict[str, bool], dict[str, bool],
    dict[str, dict[str, Any]],
]  # fmt: skip


class CorridorParallelEnv(AgentSpaces, ParallelEnv[str, np.ndarray, np.ndarray]):
    """Every ramp CAV in a control zone of the corridor is an agent (module docstring).
    Options as ``hcomc/CorridorMerge-v0`` (:class:`~hcomc.envs.corridor.env.
    CorridorMergeEnv`) except ``ramp``: every on-ramp has agents."""

    metadata: dict[str, Any] = {"name": "hcomc_corridor_merge_v0", "render_modes": []}  # noqa: RUF012

    def __init__(
        self,
        corridor: str = "corridor",
        *,
        overrides: dict[str, Any] | None = None,
        start_after: float = 300.0,
        action_period: float = 0.5,
        max_episode_time: float = 60.0,
        reward: RewardWeights | dict[str, float] | None = None,
        render_mode: str | None = None,
    ) -> None:
        self.settings = CorridorEnvSettings.of(corridor, overrides, start_after, action_period,
                                               max_episode_time, reward, render_mode)  # fmt: skip
        self.render_mode = None
        self._obs_space = self.settings.observation_space()
        self._act_space = action_space()
        self.agents: list[str] = []
        self.possible_agents: list[str] = []
        self.run: CorridorAgents | None = None
        self._rng = np.random.default_rng()
        self._groups: dict[int, np.ndarray] = {}
        self._left: set[int] = set()
        self._ramp_cavs = np.zeros(0, dtype=np.int64)
        self.t_end = 0.0

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict[str, Any]]]:
        """Run the corridor of ``seed`` to ``start_after`` and on to the first control-zone
        entry of a ramp CAV (no seed: the next one of the environment's generator)."""
        if seed is not None:
            self._rng = np.random.default_rng(seed)
            run_seed = int(seed)
        else:
            run_seed = draw_seed(self._rng)
        s = self.settings
        run = self.run = CorridorAgents(s.corridor, run_seed, s.action_period)
        self._ramp_cavs = run.ramp_cavs()
        self.possible_agents = [agent_name(int(i)) for i in self._ramp_cavs]
        run.run_until(s.start_after)
        while run.entered(self._ramp_cavs).size == 0 and not run.over:
            run.step_once()
        if run.over:
            raise ConfigError(
                f"key 'start_after' = {s.start_after!r}: no ramp CAV enters a control zone "
                "after it within the corridor's duration; allowed: an earlier time"
            )
        self.t_end = run.t + s.max_episode_time
        self._groups, self._left = {}, set()
        joined = self._join()  # at least one: the entry found above
        obs = {agent_name(i): self._observe(i) for i in joined}
        infos = {agent_name(i): {"seed": run_seed, "vehicle": i, "t": run.t} for i in joined}
        return obs, infos

    def _fresh(self) -> list[int]:
        """Ramp CAVs in their zones that are not (or were not yet) agents."""
        run = self.run
        assert run is not None
        return [int(i) for i in run.entered(self._ramp_cavs)
                if int(i) not in run.agents and int(i) not in self._left]  # fmt: skip

    def _join(self) -> list[int]:
        """Take the ramp CAVs that entered their zones since; returns them (sorted). With no
        agent left before the window's end, the run advances to the next entry first."""
        run = self.run
        assert run is not None
        fresh = self._fresh()
        while not fresh and not run.agents and not run.over and run.t < self.t_end - 1e-9:
            run.step_once()
            fresh = self._fresh()
        for i in fresh:
            run.take(i)
        self.agents = [agent_name(i) for i in sorted(run.agents)]
        return fresh

    def _observe(self, i: int) -> np.ndarray:
        assert self.run is not None
        obs, self._groups[i] = self.run.observe(i)
        return obs

    def step(self, actions: dict[str, np.ndarray]) -> Returns:
        """One action period for every agent; agents without an action drive their model."""
        run = self.run
        if run is None or not self.agents:
            raise RuntimeError("call reset() before step() (the episode has ended)")
        for i in sorted(run.agents):
            action = actions.get(agent_name(i))
            if action is None:
                run.own_model(i)
            else:
                run.apply(i, np.asarray(action, dtype=np.float64))
        terms = run.run_period(self._groups)
        timeout = run.t >= self.t_end - 1e-9 or run.over
        return self._returns(terms, timeout)

    def _returns(self, terms: dict[int, PeriodTerms], timeout: bool) -> Returns:
        run, w = self.run, self.settings.reward
        assert run is not None
        obs, rew, term, trunc, info = {}, {}, {}, {}, {}
        for i, t in terms.items():
            name = agent_name(i)
            ended = bool(t.outcome)
            obs[name] = self._observe(i)
            rew[name] = t.reward(w, with_vmc=False, timeout=timeout and not ended)
            term[name], trunc[name] = ended, timeout and not ended
            info[name] = {"vehicle": i, "outcome": t.outcome or ("timeout" if trunc[name] else ""),
                          "crashed": t.crashed, "safety": t.safety, "fuel_ml": t.fuel,
                          "gain": t.gain, "t": run.t}  # fmt: skip
            if ended or timeout:
                run.hand_back(i)
                self._left.add(i)
                self._groups.pop(i, None)
        joined = [] if timeout else self._join()
        for i in joined:
            name = agent_name(i)
            obs[name], rew[name], term[name], trunc[name] = self._observe(i), 0.0, False, False
            info[name] = {"vehicle": i, "joined": True, "t": run.t}
        self.agents = [agent_name(i) for i in sorted(run.agents)]
        return obs, rew, term, trunc, info
