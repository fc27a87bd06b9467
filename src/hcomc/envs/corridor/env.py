"""``hcomc/CorridorMerge-v0``: the Gymnasium environment of one merge at an on-ramp of any
corridor (N mainline lanes, several on- and off-ramps, continuous time-varying demand), on
the engine that runs every road.

The agent drives a ramp CAV from its entry into the ramp's cooperative control zone until
its merge is complete (:mod:`hcomc.envs.corridor.episode`); the spaces are those of
``hcomc/Merge-v0``. See docs/rl.md, "Corridors".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from hcomc.config import ConfigError
from hcomc.corridor import Corridor, load_corridor
from hcomc.corridor.engine import scenario_only
from hcomc.envs.corridor.episode import CorridorEpisode
from hcomc.envs.merge_env import action_space
from hcomc.envs.observation import observation_bounds
from hcomc.envs.options import RewardWeights, refuse_impairments
from hcomc.rng import draw_seed
from hcomc.sim.stages import ensure_kernels

__all__ = ["CorridorEnvSettings", "CorridorMergeEnv", "load_env_corridor"]


def load_env_corridor(source: str, overrides: dict[str, Any] | None = None) -> Corridor:
    """The corridor ``source`` (a preset or a TOML file) with dotted-key ``overrides``; one of
    the paper's conditions as a preset (a warm-up, lane flows, a single release: an episode
    of ``hcomc/Merge-v0``) is refused by the key that makes it so."""
    c = load_corridor(source, overrides)
    refuse_impairments(c)
    found = scenario_only(c)
    if found is not None:
        key, value = found
        raise ConfigError(
            f"key '{key}' = {value!r}: a corridor episode does not take it; allowed: it unset "
            f"(for {source!r} use hcomc/Merge-v0 with scenario={source!r})"
        )
    return c


def _positive(key: str, value: object) -> float:
    if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
        raise ConfigError(f"key '{key}' = {value!r}: allowed: a number > 0")
    return float(value)


@dataclass(frozen=True)
class CorridorEnvSettings:
    """The checked options of the corridor environments (:class:`CorridorMergeEnv`'s
    parameters; :meth:`of` names the first bad one)."""

    corridor: Corridor
    start_after: float
    action_period: float
    max_episode_time: float
    reward: RewardWeights

    @classmethod
    def of(cls, corridor: str, overrides: dict[str, Any] | None, start_after: float,
           action_period: float, max_episode_time: float,
           reward: RewardWeights | dict[str, float] | None,
           render_mode: str | None) -> CorridorEnvSettings:  # fmt: skip
        if render_mode is not None:
            raise ConfigError(
                f"key 'render_mode' = {render_mode!r}: allowed: None (the corridor "
                "environments do not render; `hcomc plot` draws corridor runs)"
            )
        c = load_env_corridor(corridor, overrides)
        if not c.road.on_ramps:
            raise ConfigError(f"key 'corridor' = {corridor!r}: allowed: a corridor with an on-ramp")
        duration = c.corridor.duration
        if not (isinstance(start_after, int | float) and 0 <= start_after < duration):
            raise ConfigError(
                f"key 'start_after' = {start_after!r}: allowed: 0 <= start_after < the "
                f"corridor's duration, {duration:g} s"
            )
        period = _positive("action_period", action_period)
        dt = c.corridor.step_length
        if abs(period / dt - round(period / dt)) > 1e-9:
            raise ConfigError(
                f"key 'action_period' = {action_period}: allowed: a multiple of the step, {dt} s"
            )
        weights = RewardWeights(**reward) if isinstance(reward, dict) else reward
        return cls(c, float(start_after), period, _positive("max_episode_time", max_episode_time),
                   weights or RewardWeights())  # fmt: skip

    def observation_space(self) -> gym.spaces.Box:
        """The observation space of ``hcomc/Merge-v0`` for this corridor's length."""
        low, high = observation_bounds(self.corridor.road.length)
        return gym.spaces.Box(low, high, dtype=np.float32)


class CorridorMergeEnv(gym.Env[np.ndarray, np.ndarray]):
    """One merge at one on-ramp of a corridor per episode
    (``gymnasium.make("hcomc/CorridorMerge-v0", corridor=..., ramp=...)``).

    Parameters
    ----------
    corridor : a corridor preset (``hcomc corridors`` lists them) or a corridor TOML file.
    overrides : dotted corridor keys and their values (``{"road.lanes": 4}``), as
        ``hcomc simulate CORRIDOR --set`` takes them.
    ramp : the on-ramp whose CAV the agent drives (default: the corridor's first).
    start_after : the agent's vehicle is the ramp's first CAV departing at or after this
        time [s], so that the corridor has filled with traffic.
    action_period : simulated time per environment step [s], a multiple of the step.
    max_episode_time : the episode is truncated (a timeout) after this long [s].
    reward : the :class:`RewardWeights` (or a dict of its fields).

    ``reset(seed=s)`` runs the corridor with seed ``s`` (the traffic of ``hcomc simulate
    CORRIDOR --seed s``) until the agent's vehicle enters its control zone; without a seed the
    next seed comes from the environment's generator. Episodes are bit-reproducible: the same
    seed and actions give the same observations and rewards. The corridor's ``[control]``
    table is not used: no merge controller runs beside the agent.
    """

    metadata: dict[str, Any] = {"render_modes": [], "render_fps": 2}  # noqa: RUF012

    def __init__(
        self,
        corridor: str = "corridor",
        *,
        overrides: dict[str, Any] | None = None,
        ramp: str | None = None,
        start_after: float = 300.0,
        action_period: float = 0.5,
        max_episode_time: float = 60.0,
        reward: RewardWeights | dict[str, float] | None = None,
        render_mode: str | None = None,
    ) -> None:
        self.settings = CorridorEnvSettings.of(corridor, overrides, start_after, action_period,
                                               max_episode_time, reward, render_mode)  # fmt: skip
        self.corridor = self.settings.corridor
        ramps = [r.id for r in self.corridor.road.on_ramps]
        self.ramp = ramps[0] if ramp is None else ramp
        if self.ramp not in ramps:
            raise ConfigError(f"key 'ramp' = {ramp!r}: allowed: {', '.join(ramps)}")
        ensure_kernels(("corridor",))
        self.render_mode = None
        self.action_space = action_space()
        self.observation_space = self.settings.observation_space()
        self.episode: CorridorEpisode | None = None
        self.metadata = {**self.metadata, "render_fps": 1.0 / self.settings.action_period}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Run the corridor of ``seed`` to the agent's control-zone entry."""
        super().reset(seed=seed)
        run_seed = draw_seed(self.np_random) if seed is None else int(seed)
        s = self.settings
        self.episode = CorridorEpisode(
            s.corridor, self.ramp, run_seed, s.start_after, s.action_period,
            s.max_episode_time, s.reward,
        )  # fmt: skip
        obs = self.episode.start()
        e = self.episode
        return obs, {"seed": e.seed, "t": e.t, "ego": e.ego, "ramp": self.ramp}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Drive one action period."""
        episode = self.episode
        if episode is None or episode.done:
            raise RuntimeError("call reset() before step() (the episode has ended)")
        result = episode.step(np.asarray(action, dtype=np.float64))
        return result.obs, result.reward, result.terminated, result.truncated, result.info
