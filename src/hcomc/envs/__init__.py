"""Learning environments on the hcomc engine (extra ``envs``: gymnasium, pettingzoo).

* ``hcomc/Merge-v0`` (:class:`~hcomc.envs.merge_env.MergeEnv`): the agent drives the ramp CAV
  VR (or the cooperating mainline vehicle) through one merge;
* :class:`~hcomc.envs.vector.MergeVectorEnv`: many such environments advanced together on
  the ensemble engine (a native ``gymnasium.vector.VectorEnv``);
* :class:`~hcomc.envs.multi_agent.MergeParallelEnv`: every CAV in the control zone is an
  agent (PettingZoo ``ParallelEnv``);
* :mod:`hcomc.envs.policies`: the FIFO, Game and HCOMC controllers on the same
  environment, and :func:`~hcomc.envs.policies.evaluate`.

Importing this package registers ``hcomc/Merge-v0`` with gymnasium.
"""

from __future__ import annotations

import gymnasium as gym

from hcomc.envs.merge_env import MergeEnv
from hcomc.envs.options import EnvOptions, RewardWeights

ENV_ID = "hcomc/Merge-v0"

if ENV_ID not in gym.registry:
    gym.register(
        id=ENV_ID,
        entry_point="hcomc.envs.merge_env:MergeEnv",
        vector_entry_point="hcomc.envs.vector:MergeVectorEnv",
    )

__all__ = ["ENV_ID", "EnvOptions", "MergeEnv", "RewardWeights"]
