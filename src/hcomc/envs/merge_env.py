"""``hcomc/Merge-v0``: the Gymnasium environment of one on-ramp merge.

The agent drives the ramp CAV VR (or, with ``agent="vmc"``, the mainline vehicle VR merges in
front of) on the paper's road, among the scenario's human-driven and connected vehicles,
from VR's entry into the cooperative control zone until its merge is complete. See
docs/rl.md for the spaces, the reward and the options.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from hcomc.envs.episode import MergeEpisode, start_drawn
from hcomc.envs.observation import observation_bounds
from hcomc.envs.options import EnvOptions, RewardWeights
from hcomc.envs.render import RENDER_MODES, check_render_mode, render_frame
from hcomc.rng import draw_seed
from hcomc.sim.log import SimulationLog
from hcomc.sim.stages import SCENARIO, ensure_kernels


def action_space() -> gym.spaces.Box:
    """``[acceleration, lane change]``, both in [-1, 1] (see :meth:`MergeEpisode.apply`)."""
    return gym.spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)


def observation_space(options: EnvOptions) -> gym.spaces.Box:
    """The observation vector of :mod:`hcomc.envs.observation`."""
    low, high = observation_bounds(options.config().road.length)
    return gym.spaces.Box(low, high, dtype=np.float32)


class MergeEnv(gym.Env[np.ndarray, np.ndarray]):
    """One on-ramp merge per episode (``gymnasium.make("hcomc/Merge-v0", ...)``).

    Parameters are those of :class:`hcomc.envs.options.EnvOptions`: ``scenario``,
    ``overrides``, ``agent``, ``controller``, ``action_period``, ``max_episode_time`` and
    ``reward`` (a :class:`RewardWeights` or a dict of its fields).

    ``reset(seed=s)`` starts the scenario's run with seed ``s`` (the same traffic as
    ``hcomc simulate CONDITION --seed s``); without a seed the next seed comes from the
    environment's generator, itself seeded by the first ``reset(seed=...)`` (with
    ``agent="vmc"``, a drawn seed whose VR has no VMC is skipped for the next one; a given one
    raises :class:`~hcomc.envs.episode.NoVMCError`). Episodes are bit-reproducible: the same
    seed and actions give the same observations and rewards.

    ``render_mode="rgb_array"``: :meth:`render` returns the frame of the road around the
    agent's vehicle (:func:`hcomc.envs.render.render_frame`).
    """

    # gymnasium's API; render_fps is set per environment from its action period
    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 2}  # noqa: RUF012

    def __init__(
        self,
        scenario: str = "C1",
        *,
        overrides: dict[str, Any] | None = None,
        agent: str = "vr",
        controller: str | None = None,
        action_period: float = 0.5,
        max_episode_time: float = 60.0,
        reward: RewardWeights | dict[str, float] | None = None,
        render_mode: str | None = None,
    ) -> None:
        self.render_mode = check_render_mode(render_mode)
        self.options = EnvOptions.of(
            scenario, overrides=overrides, reward=reward, agent=agent, controller=controller,
            action_period=action_period, max_episode_time=max_episode_time,
        )  # fmt: skip
        self.config = self.options.config()
        ensure_kernels(SCENARIO if self.options.controller else ("step",))
        self.action_space = action_space()
        self.observation_space = observation_space(self.options)
        self.episode: MergeEpisode | None = None
        self.metadata = {**self.metadata, "render_fps": 1.0 / self.options.action_period}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start the run of ``seed`` and advance it to VR's control-zone entry."""
        super().reset(seed=seed)
        if seed is not None:  # this seed's run, or its clear error
            self.episode = MergeEpisode(self.options, self.config, seed)
            obs = self.episode.start()
        else:
            self.episode, obs = start_drawn(self.options, self.config,
                                            lambda: draw_seed(self.np_random))  # fmt: skip
        e = self.episode
        return obs, {"seed": e.seed, "t": e.sim.t, "ego": e.ego}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Drive one action period."""
        episode = self.episode
        if episode is None or episode.done:
            raise RuntimeError("call reset() before step() (the episode has ended)")
        episode.run_period(episode.apply(np.asarray(action, dtype=np.float64)))
        result = episode.evaluate()
        return result.obs, result.reward, result.terminated, result.truncated, result.info

    def render(self) -> np.ndarray | None:
        """The (160, 640, 3) RGB frame of the road around the agent's vehicle now, to scale
        (``render_mode="rgb_array"``; None without a render mode)."""
        if self.render_mode is None:
            return None
        if self.episode is None:
            raise RuntimeError("call reset() before render()")
        return render_frame(self.episode.sim, self.config, self.episode.ego)

    def episode_logs(self) -> tuple[SimulationLog, SimulationLog]:
        """The episode's log and its undisturbed reference, each run to the scenario's end
        (the agent's vehicle back on its model after the episode), for
        :func:`hcomc.metrics.compute_metrics` and the report's figures."""
        if self.episode is None:
            raise RuntimeError("no episode: call reset() first")
        return self.episode.finish()
