"""Cooperative multi-agent merging: every CAV in the control zone is an agent (a PettingZoo
``ParallelEnv``), with the scenario's human drivers and their reaction delays and errors.

An agent ``"cav_<i>"`` is CAV i while it is in the cooperative control zone (from
``road.control_zone_start`` to the end of the acceleration lane, on any lane). It joins when
it enters (its first observation comes with the step in which it entered) and terminates when
it leaves; it is then handed back to its car-following model. The episode runs from the ramp
vehicle VR's entry into the zone until its merge is complete, a collision, VR at the lane end
(when VR is an agent), or ``max_episode_time`` (all agents truncated).

Each agent has the action and observation spaces of ``hcomc/Merge-v0`` (the observation is
its own state and the six key vehicles around VR, relative to it); its lane-change action
takes a ramp vehicle into lane 1 and a mainline vehicle to the other main lane. Its reward
over a period is its own share of the same terms: Eq. 15 over its follower-leader pairs, its
Eq. 16 fuel, its Eq. 17 acceleration change against the undisturbed run, the time weight per
second, the collision weight when it is in a collision (or is VR at the lane end), the
timeout weight on truncation.
"""

from __future__ import annotations

import functools
from typing import Any

import gymnasium as gym
import numpy as np
from pettingzoo import ParallelEnv

from hcomc.envs.episode import MergeEpisode, apply_action
from hcomc.envs.merge_env import action_space, observation_space
from hcomc.envs.observation import N_OBS
from hcomc.envs.options import EnvOptions, RewardWeights
from hcomc.envs.render import RENDER_MODES, check_render_mode, render_frame
from hcomc.rng import draw_seed
from hcomc.road import Kind
from hcomc.sim.stages import SCENARIO, ensure_kernels


def agent_name(i: int) -> str:
    """Agent id of vehicle i."""
    return f"cav_{i}"


class AgentSpaces:
    """Every agent's spaces are those of ``hcomc/Merge-v0``, one object each as PettingZoo
    asks (the multi-agent environments of the paper's road and of a corridor)."""

    _obs_space: gym.spaces.Box
    _act_space: gym.spaces.Box

    @functools.cache  # noqa: B019 (one space object per agent, as required)
    def observation_space(self, agent: str) -> gym.spaces.Box:
        """The observation space of every agent (that of ``hcomc/Merge-v0``)."""
        return self._obs_space

    @functools.cache  # noqa: B019
    def action_space(self, agent: str) -> gym.spaces.Box:
        """``[acceleration, lane change]`` in [-1, 1], as in ``hcomc/Merge-v0``."""
        return self._act_space


class MergeParallelEnv(AgentSpaces, ParallelEnv[str, np.ndarray, np.ndarray]):
    """Every CAV in the control zone is an agent. Options as ``hcomc/Merge-v0``
    (:class:`~hcomc.envs.merge_env.MergeEnv`) except ``agent`` and ``controller``."""

    metadata: dict[str, Any] = {"name": "hcomc_merge_v0", "render_modes": list(RENDER_MODES)}  # noqa: RUF012

    def __init__(
        self,
        scenario: str = "C1",
        *,
        overrides: dict[str, Any] | None = None,
        action_period: float = 0.5,
        max_episode_time: float = 60.0,
        reward: RewardWeights | dict[str, float] | None = None,
        render_mode: str | None = None,
    ) -> None:
        self.render_mode = check_render_mode(render_mode)
        self.options = EnvOptions.of(
            scenario, overrides=overrides, reward=reward, action_period=action_period,
            max_episode_time=max_episode_time,
        )  # fmt: skip
        self.config = self.options.config()
        ensure_kernels(SCENARIO if self.options.controller else ("step",))
        self._obs_space = observation_space(self.options)
        self._act_space = action_space()
        self.agents: list[str] = []
        self.possible_agents: list[str] = []
        self.episode: MergeEpisode | None = None
        self._rng = np.random.default_rng()
        self._members: set[int] = set()
        self._left: set[int] = set()

    # -------------------------------------------------------------------- reset
    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict[str, Any]]]:
        """Start the run of ``seed`` at VR's control-zone entry (no seed: the next one)."""
        if seed is not None:
            self._rng = np.random.default_rng(seed)
            run_seed = int(seed)
        else:
            run_seed = draw_seed(self._rng)
        # the agents drive mainline CAVs: the twin differs from the run from the first step
        episode = MergeEpisode(self.options, self.config, run_seed, defer_twin=False)
        episode.start()
        episode.sim.log.meta["agent"] = {"role": "CAVs in the control zone", "vehicle": -1,
                                         "t_start": float(episode.t_start)}  # fmt: skip
        self.episode = episode
        cav = np.flatnonzero(episode.sim.fleet.kind == Kind.CAV)
        self.possible_agents = [agent_name(int(i)) for i in cav]
        self._members, self._left = set(), set()
        joined = self._update_members()
        self.agents = [agent_name(i) for i in sorted(self._members)]
        obs = {agent_name(i): self._observe(i) for i in joined}
        infos = {agent_name(i): {"seed": run_seed, "vehicle": i} for i in joined}
        return obs, infos

    def _in_zone(self) -> set[int]:
        s, road = self.episode.sim, self.config.road  # type: ignore[union-attr]
        cav = s.fleet.kind == Kind.CAV
        inside = s.active & cav & (s.x >= road.control_zone_start) & (s.x <= road.accel_lane_end)
        return set(np.flatnonzero(inside).tolist())

    def _update_members(self) -> list[int]:
        """Add CAVs that entered the zone; returns them (sorted)."""
        joined = sorted(self._in_zone() - self._members - self._left)
        self._members |= set(joined)
        return joined

    def _observe(self, i: int) -> np.ndarray:
        assert self.episode is not None
        out = np.zeros(N_OBS, dtype=np.float32)
        self.episode.observe_into(out, i)
        return out

    # --------------------------------------------------------------------- step
    def step(self, actions: dict[str, np.ndarray]) -> tuple[
        dict[str, np.ndarray], dict[str, float], dict[str, bool], dict[str, bool],
        dict[str, dict[str, Any]],
    ]:  # fmt: skip
        """One action period for every agent; agents without an action keep their model."""
        e = self.episode
        if e is None or not self.agents:
            raise RuntimeError("call reset() before step() (the episode has ended)")
        s = e.sim
        for i in sorted(self._members):
            action = actions.get(agent_name(i))
            if action is None:
                s.command(i, float("nan"))
                continue
            apply_action(s, e.kernel_params, i, np.asarray(action, dtype=np.float64))
        target = s.step_index + e.period_steps
        s.run_to(target)
        e.twin.run_to(target)
        return self._evaluate()

    def _evaluate(self) -> tuple[
        dict[str, np.ndarray], dict[str, float], dict[str, bool], dict[str, bool],
        dict[str, dict[str, Any]],
    ]:  # fmt: skip
        e, w = self.episode, self.options.reward
        assert e is not None
        s = e.sim
        collided = set(e.collided().tolist())
        r0, r1 = e.new_rows()
        vr_agent = bool(e.is_cav[e.vr])
        lane_end = vr_agent and e.at_lane_end()
        over = bool(collided) or lane_end or e.merged() or not s.active[e.vr]
        timeout = not over and e.out_of_time()
        before = sorted(self._members)
        inside = self._in_zone()
        joined = [] if over or timeout else self._update_members()
        obs, rew, term, trunc, info = {}, {}, {}, {}, {}
        for i in before:
            name = agent_name(i)
            crashed = i in collided or (lane_end and i == e.vr)
            reward = (
                -w.safety * e.safety_of(i)
                - w.fuel * e.fuel_of(i, r0, r1)
                + w.efficiency * e.gain_of(i, r0, r1)
                - w.time * self.options.action_period
                - w.collision * crashed
                - w.timeout * timeout
            )
            left = i not in inside or not s.active[i]
            obs[name], rew[name] = self._observe(i), float(reward)
            term[name], trunc[name] = over or left, timeout
            info[name] = {"vehicle": i, "collision": crashed, "merged": e.merged(), "t": s.t}
        for i in joined:
            name = agent_name(i)
            obs[name], rew[name], term[name], trunc[name] = self._observe(i), 0.0, False, False
            info[name] = {"vehicle": i, "joined": True, "t": s.t}
        done = {i for i in self._members if term[agent_name(i)] or trunc[agent_name(i)]}
        for i in done:
            s.command(i, float("nan"))  # back to its model
        self._left |= done
        self._members -= done
        self.agents = [agent_name(i) for i in sorted(self._members)]
        if not self.agents:
            e.done = True
        return obs, rew, term, trunc, info

    def render(self) -> np.ndarray | None:
        """The RGB frame of the road around VR now (``render_mode="rgb_array"``, see
        :func:`hcomc.envs.render.render_frame`); None without a render mode."""
        if self.render_mode is None:
            return None
        if self.episode is None:
            raise RuntimeError("call reset() before render()")
        return render_frame(self.episode.sim, self.config, self.episode.vr)

    def episode_logs(self) -> tuple[Any, Any]:
        """The episode's log and undisturbed reference, run to the scenario's end."""
        if self.episode is None:
            raise RuntimeError("no episode: call reset() first")
        for i in sorted(self._members):
            self.episode.sim.command(i, float("nan"))
        return self.episode.finish()


__all__ = ["AgentSpaces", "MergeParallelEnv", "agent_name"]
