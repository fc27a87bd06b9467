"""Options of the learning environments: the scenario, who the agent drives, the action
period, the episode limit and the reward weights (their one home)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any, Literal

from hcomc.config import ConfigError, ScenarioConfig
from hcomc.config.impairment_tables import impairing_key
from hcomc.control.registry import canonical_name
from hcomc.corridor import Corridor
from hcomc.corridor.engine import scenario_config

AGENTS = ("vr", "vmc")
"""Who the agent of ``hcomc/Merge-v0`` drives: the ramp CAV VR (default) or the mainline
vehicle VMC that VR merges in front of (the cooperating vehicle of Section II-A)."""

CONTROLLERS = ("fifo", "game", "hcomc")
"""hcomc's merge controllers that can drive VR in an environment instead of the agent
(:mod:`hcomc.envs.policies`); any other controller name works too (``package.module:Class``,
``path/to/file.py:Class`` or a registered name: :mod:`hcomc.control.registry`)."""


@dataclass(frozen=True, slots=True)
class RewardWeights:
    """Weights of the reward terms (all >= 0); the reward of one action period is

    ``- safety * S - fuel * F + efficiency * E - time * dt - collision * [crash]
    - timeout * [timeout]``

    with S the Eq. 15 critical acceleration of the agent's follower-leader pairs divided by
    a_merg and capped at 1, integrated over the period [s]; F the Eq. 16 fuel of VR and VMC
    over the period [mL]; E the Eq. 17 gain over the period [m/s] (VR's acceleration minus
    its free-road acceleration, plus eta times the acceleration changes of VMC, VMR and VNR
    against the undisturbed run); dt the period [s] (``time`` prices the merge's duration, so
    that waiting is not free: without it a discounted timeout at the end of a long episode
    costs less than a risky merge now). A crash (a collision, or VR driven past the end of
    the acceleration lane) and a timeout each cost about as much as a minute at the safety
    limit. The defaults are a starting point, the same for every scenario, not tuned.
    """

    safety: float = 1.0
    fuel: float = 0.05
    efficiency: float = 0.1
    time: float = 1.0
    collision: float = 50.0
    timeout: float = 50.0

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ConfigError(
                    f"key 'reward.{f.name}' = {value!r}: allowed: a finite number >= 0"
                )


@dataclass(frozen=True, slots=True)
class EnvOptions:
    """Everything an environment episode depends on besides its seed.

    Attributes
    ----------
    scenario : a condition preset (``"C1"`` ... ``"C5"``), a scenario TOML path, or a
        corridor of the paper's layout (``"paper"``, ``"paper-C3"``, a file based on them:
        :func:`hcomc.corridor.engine.scenario_config`).
    overrides : config values changed for this environment (``{"cav_penetration": 0.5}``),
        as :func:`hcomc.config.load_config` takes them.
    agent : ``"vr"`` or ``"vmc"`` (:data:`AGENTS`).
    controller : ``None`` (the agent drives) or a controller name (:data:`CONTROLLERS`, or any
        name :mod:`hcomc.control.registry` accepts) that drives VR through the engine, exactly
        as ``hcomc run`` executes it.
    action_period : simulated time per environment step [s], a multiple of ``dt``.
    max_episode_time : the episode is truncated (a timeout) after this long [s].
    reward : the :class:`RewardWeights`.
    """

    scenario: str = "C1"
    overrides: dict[str, Any] = field(default_factory=dict)
    agent: Literal["vr", "vmc"] = "vr"
    controller: str | None = None
    action_period: float = 0.5
    max_episode_time: float = 60.0
    reward: RewardWeights = field(default_factory=RewardWeights)

    def __post_init__(self) -> None:
        if self.agent not in AGENTS:
            raise ConfigError(f"key 'agent' = {self.agent!r}: allowed: {', '.join(AGENTS)}")
        if self.controller is not None:
            object.__setattr__(self, "controller", canonical_name(self.controller))
        if self.controller is not None and self.agent != "vr":
            raise ConfigError(
                f"key 'controller' = {self.controller!r} drives VR: allowed only with agent 'vr'"
            )
        for key in ("action_period", "max_episode_time"):
            value = getattr(self, key)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ConfigError(f"key '{key}' = {value!r}: allowed: a number > 0")
        if isinstance(self.reward, Mapping):  # a plain mapping, as gymnasium.make passes it
            object.__setattr__(self, "reward", RewardWeights(**self.reward))

    @classmethod
    def of(
        cls, scenario: str, *, overrides: Mapping[str, Any] | None = None,
        reward: RewardWeights | Mapping[str, float] | None = None, **rest: Any,
    ) -> EnvOptions:  # fmt: skip
        """The options an environment's constructor was given (``rest``: the other fields):
        ``None`` for the default overrides and weights; ``reward`` may be a mapping of
        :class:`RewardWeights` fields."""
        weights: Any = RewardWeights() if reward is None else reward  # a mapping: see below
        return cls(scenario=scenario, overrides=dict(overrides or {}), reward=weights, **rest)

    def config(self) -> ScenarioConfig:
        """The scenario as the environment runs it (its controller set by ``controller``)."""
        control = {"controller": self.controller or "none"}
        control = {**dict(self.overrides.get("control", {})), **control}
        config = scenario_config(self.scenario, **{**self.overrides, "control": control})
        steps = self.action_period / config.dt
        if abs(steps - round(steps)) > 1e-9:
            raise ConfigError(
                f"key 'action_period' = {self.action_period}: allowed: a multiple of "
                f"dt = {config.dt} s"
            )
        refuse_impairments(config)
        if config.scenario != "merge":
            raise ConfigError(
                f"key 'scenario' = {config.scenario!r} ({self.scenario}): allowed: a merge "
                "scenario (an on-ramp with a ramp vehicle)"
            )
        return config


def refuse_impairments(config: ScenarioConfig | Corridor) -> None:
    """A :class:`ConfigError` naming the ``[v2x]``, ``[[faults]]`` or ``[shield]`` table set
    in ``config``: an episode runs the nominal traffic (the commands and ``hcomc faults`` run
    them)."""
    key = impairing_key(config.v2x, config.faults, config.shield)
    if key is not None:
        raise ConfigError(
            f"key '{key}': a learning environment runs the nominal traffic; allowed: the "
            "defaults of [v2x], [[faults]] and [shield] (hcomc simulate, run, compare and "
            "faults run them)"
        )
