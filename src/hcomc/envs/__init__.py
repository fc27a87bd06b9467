"""Learning environments on the hcomc engine (extra ``envs``: gymnasium, pettingzoo).

* ``hcomc/Merge-v0`` (:class:`~hcomc.envs.merge_env.MergeEnv`): the agent drives the ramp CAV
  VR (or the cooperating mainline vehicle) through one merge;
* :class:`~hcomc.envs.vector.MergeVectorEnv`: many such environments advanced together on
  the ensemble engine (a native ``gymnasium.vector.VectorEnv``);
* :class:`~hcomc.envs.multi_agent.MergeParallelEnv`: every CAV in the control zone is an
  agent (PettingZoo ``ParallelEnv``), also made by :func:`parallel_env`, PettingZoo's
  factory convention;
* :mod:`hcomc.envs.policies`: the FIFO, Game and HCOMC controllers on the same
  environment, and :func:`~hcomc.envs.policies.evaluate_policies`;
* ``hcomc/CorridorMerge-v0`` (:class:`~hcomc.envs.corridor.env.CorridorMergeEnv`): the agent
  drives a ramp CAV through its merge at one on-ramp of any corridor (N lanes, several
  ramps, continuous demand), on the engine.

Importing this package registers ``hcomc/Merge-v0`` and ``hcomc/CorridorMerge-v0`` with
gymnasium.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import gymnasium as gym

from hcomc.envs.merge_env import MergeEnv
from hcomc.envs.options import EnvOptions, RewardWeights

if TYPE_CHECKING:
    from hcomc.envs.multi_agent import MergeParallelEnv

ENV_ID = "hcomc/Merge-v0"
CORRIDOR_ENV_ID = "hcomc/CorridorMerge-v0"

if ENV_ID not in gym.registry:
    gym.register(
        id=ENV_ID,
        entry_point="hcomc.envs.merge_env:MergeEnv",
        vector_entry_point="hcomc.envs.vector:MergeVectorEnv",
    )
if CORRIDOR_ENV_ID not in gym.registry:
    gym.register(id=CORRIDOR_ENV_ID, entry_point="hcomc.envs.corridor.env:CorridorMergeEnv")


def parallel_env(
    scenario: str = "C1",
    *,
    overrides: dict[str, Any] | None = None,
    action_period: float = 0.5,
    max_episode_time: float = 60.0,
    reward: RewardWeights | dict[str, float] | None = None,
    render_mode: str | None = None,
) -> MergeParallelEnv:
    """The multi-agent environment (:class:`~hcomc.envs.multi_agent.MergeParallelEnv`, a
    PettingZoo ``ParallelEnv``) with the class's arguments: PettingZoo's module-level factory
    (``parallel_env(**kwargs)``). PettingZoo is imported only here, so that the Gymnasium
    environments need only Gymnasium."""
    from hcomc.envs.multi_agent import MergeParallelEnv

    return MergeParallelEnv(
        scenario, overrides=overrides, action_period=action_period,
        max_episode_time=max_episode_time, reward=reward, render_mode=render_mode,
    )  # fmt: skip


__all__ = ["CORRIDOR_ENV_ID", "ENV_ID", "EnvOptions", "MergeEnv", "RewardWeights", "parallel_env"]
