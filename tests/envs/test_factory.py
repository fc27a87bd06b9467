"""PettingZoo's factory convention: ``hcomc.envs.parallel_env(**kwargs)`` beside the class."""

from __future__ import annotations

import inspect

import numpy as np
from pettingzoo.test import parallel_api_test

import hcomc.envs
from hcomc.envs import RewardWeights, parallel_env
from hcomc.envs.multi_agent import MergeParallelEnv


def test_the_factory_returns_the_parallel_env() -> None:
    env = parallel_env()
    assert type(env) is MergeParallelEnv
    assert env.options == MergeParallelEnv().options  # the class's defaults
    assert "parallel_env" in hcomc.envs.__all__


def test_the_factory_takes_the_arguments_of_the_class() -> None:
    """Same names, kinds and defaults: the factory cannot drift from the class."""
    ours = inspect.signature(parallel_env).parameters
    theirs = inspect.signature(MergeParallelEnv).parameters
    assert [(p.name, p.kind, p.default) for p in ours.values()] == [
        (p.name, p.kind, p.default) for p in theirs.values()
    ]


def test_keyword_arguments_are_forwarded() -> None:
    env = parallel_env(
        scenario="C4",
        overrides={"demand": {"cav_penetration": 0.5}},
        action_period=1.0,
        max_episode_time=30.0,
        reward={"time": 0.5},
        render_mode="rgb_array",
    )
    twin = MergeParallelEnv(
        "C4",
        overrides={"demand": {"cav_penetration": 0.5}},
        action_period=1.0,
        max_episode_time=30.0,
        reward={"time": 0.5},
        render_mode="rgb_array",
    )
    assert env.options == twin.options
    assert env.options.action_period == 1.0
    assert env.options.max_episode_time == 30.0
    assert env.options.reward == RewardWeights(time=0.5)
    assert env.config.demand.cav_penetration == 0.5
    assert env.render_mode == "rgb_array"


def test_the_factory_made_env_passes_pettingzoos_parallel_api_test() -> None:
    parallel_api_test(parallel_env(scenario="C1"), num_cycles=300)


def test_the_factory_and_the_class_run_the_same_episode() -> None:
    a, b = parallel_env(scenario="C4"), MergeParallelEnv("C4")
    obs_a, _ = a.reset(seed=3)
    obs_b, _ = b.reset(seed=3)
    assert obs_a.keys() == obs_b.keys()
    for agent in obs_a:
        np.testing.assert_array_equal(obs_a[agent], obs_b[agent])
