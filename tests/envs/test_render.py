"""``render_mode="rgb_array"`` of the learning environments: frames drawn where the state is."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import hcomc.envs  # noqa: F401 (registers hcomc/Merge-v0)
from hcomc.envs import MergeEnv
from hcomc.envs.multi_agent import MergeParallelEnv
from hcomc.envs.render import BEHIND, FRAME_SIZE, SCALE
from hcomc.envs.vector import MergeVectorEnv
from hcomc.road import Kind

COLOURS = {Kind.HDV: (217, 95, 2), Kind.CAV: (27, 158, 119)}
FOCUS = (31, 95, 214)


def centre_pixel(sim, focus: int, i: int) -> tuple[int, int]:
    """(row, column) of vehicle i's rectangle centre in a frame centred on ``focus``."""
    height, width = FRAME_SIZE
    left = float(sim.x[focus]) - BEHIND * width / SCALE
    heading = float(sim.heading[i])
    cx = float(sim.x[i]) - 0.5 * float(sim.fleet.length[i]) * np.cos(heading)
    cy = float(sim.y[i]) - 0.5 * float(sim.fleet.length[i]) * np.sin(heading)
    return int(0.5 * height - cy * SCALE), int((cx - left) * SCALE)


def test_frames_show_the_vehicles_where_they_are() -> None:
    env = MergeEnv("C1", render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(3):
        frame = env.render()
        assert frame is not None
        assert frame.shape == (*FRAME_SIZE, 3)
        assert frame.dtype == np.uint8
        sim, ego = env.episode.sim, env.episode.ego  # type: ignore[union-attr]
        assert tuple(frame[centre_pixel(sim, ego, ego)]) == FOCUS
        right = float(sim.x[ego]) + (1 - BEHIND) * FRAME_SIZE[1] / SCALE
        others = [
            i for i in np.flatnonzero(sim.active).tolist()
            if i != ego and float(sim.x[ego]) - 40 < float(sim.x[i]) - 5 and float(sim.x[i]) < right
        ]  # fmt: skip
        assert others, "some vehicle should be in view"
        for i in others:
            r, c = centre_pixel(sim, ego, i)
            assert tuple(frame[r, c]) == COLOURS[Kind(int(sim.fleet.kind[i]))], f"vehicle {i}"
        before = frame.copy()
        env.step(np.array([0.3, -1.0], dtype=np.float32))
        assert (env.render() != before).any()


def test_the_environments_accept_the_render_mode() -> None:
    env = gym.make("hcomc/Merge-v0", render_mode="rgb_array")
    check_env(env.unwrapped)
    assert env.unwrapped.metadata["render_fps"] == 2.0  # one frame per action period (0.5 s)
    parallel = MergeParallelEnv("C1", render_mode="rgb_array")
    parallel.reset(seed=1)
    frame = parallel.render()
    assert frame is not None
    assert frame.shape == (*FRAME_SIZE, 3)
    vector = MergeVectorEnv(2, render_mode="rgb_array")
    vector.reset(seed=3)
    frames = vector.render()
    assert frames is not None
    assert len(frames) == 2
    single = MergeEnv("C1", render_mode="rgb_array")
    single.reset(seed=4)
    np.testing.assert_array_equal(frames[1], single.render())


def test_render_mode_errors() -> None:
    with pytest.raises(ValueError, match=r"key 'render_mode' = 'human': allowed: 'rgb_array'"):
        MergeEnv("C1", render_mode="human")
    with pytest.raises(RuntimeError, match="call reset"):
        MergeEnv("C1", render_mode="rgb_array").render()
    assert MergeEnv("C1").render() is None
