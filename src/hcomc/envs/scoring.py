"""What the compiled kernels of :mod:`hcomc.envs.batch` are given and what their terms make
of a step: the parameter vector of a scenario (from its configuration), how each episode's
step ended and its reward (with the environment's reward weights).

Python, as the configuration and the options are: one episode
(:class:`~hcomc.envs.episode.MergeEpisode`) and the vector environment both call these.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from hcomc.config.fuel import FUEL_DEFAULT
from hcomc.envs.batch import (
    T_COLLISIONS,
    T_EFFICIENCY,
    T_FUEL,
    T_LANE_END,
    T_MERGED,
    T_SAFETY,
    T_TIME,
    T_VR_ON_ROAD,
)

if TYPE_CHECKING:
    from hcomc.config import ScenarioConfig
    from hcomc.envs.options import RewardWeights

__all__ = ["Outcomes", "outcomes", "parameters", "rewards"]


def parameters(config: ScenarioConfig, action_period: float) -> np.ndarray:
    """The parameter vector of a scenario for the kernels (the config's values)."""
    road, ctl = config.road, config.control
    head = [road.accel_lane_start, road.accel_lane_end, config.lane_change.emergency_decel,
            ctl.safety_delay_cav, ctl.safety_delay_hdv, ctl.safety_min_distance,
            ctl.safety_emergency_decel, action_period, config.log_interval,
            config.lane_change.politeness]  # fmt: skip
    return np.array([*head, *FUEL_DEFAULT.coefficients()], dtype=np.float64)


class Outcomes(NamedTuple):
    """How a step ended, per episode (arrays, or scalars for one episode's terms)."""

    terminated: Any
    timeout: Any
    crashed: Any
    collision: Any
    merged: Any
    lane_end: Any


def outcomes(
    terms: np.ndarray, collisions_before: Any, t_start: Any, finished: Any, *,
    lane_end_ends: bool, max_time: float,
) -> Outcomes:  # fmt: skip
    """How each episode's step ended, from its terms (the last axis of ``terms``) and its
    state before the step: a new collision or (with ``lane_end_ends``: the agent drives VR)
    VR stuck at the lane end is a crash; a crash, the merge or VR leaving the road ends the
    episode; otherwise ``max_time`` [s] since ``t_start`` or the run's end is a timeout."""
    collision = terms[..., T_COLLISIONS] > collisions_before
    merged = terms[..., T_MERGED] > 0
    lane_end = (terms[..., T_LANE_END] > 0) & lane_end_ends
    crashed = collision | lane_end
    terminated = crashed | merged | (terms[..., T_VR_ON_ROAD] == 0)
    late = terms[..., T_TIME] - t_start >= max_time - 1e-9
    timeout = ~terminated & (late | finished)
    return Outcomes(terminated, timeout, crashed, collision, merged, lane_end)


def rewards(
    terms: np.ndarray, crashed: np.ndarray, timeout: np.ndarray, w: RewardWeights, period: float
) -> np.ndarray:
    """The reward of each episode's period from its terms (rows of ``terms``) and outcome:
    ``- safety S - fuel F + efficiency E - time dt - collision [crash] - timeout [timeout]``
    (:class:`~hcomc.envs.options.RewardWeights`)."""
    return (
        -w.safety * terms[:, T_SAFETY]
        - w.fuel * terms[:, T_FUEL]
        + w.efficiency * terms[:, T_EFFICIENCY]
        - w.time * period
        - w.collision * crashed
        - w.timeout * timeout
    )
