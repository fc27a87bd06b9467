"""Policies on the learning environments, and their evaluation with the paper's metrics.

A policy is anything that maps an observation to an action: a function, or a trained model
with stable-baselines3's ``predict(obs, deterministic=True)``. The merge controllers FIFO,
Game and HCOMC are available as :class:`ControllerPolicy`: in an environment built for one
(``controller="hcomc"``) the controller drives VR through the engine exactly as
``hcomc run`` executes it (plans, replanning, cooperation of the key vehicles), and the
action is not used. :func:`evaluate_policies` runs any of them on the same seeds and scores each
episode with the environment's reward and with :func:`hcomc.metrics.compute_metrics`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import pandas as pd

from hcomc.config import ConfigError
from hcomc.control.registry import canonical_name
from hcomc.envs.merge_env import MergeEnv
from hcomc.metrics import METRICS, compute_metrics


class Predictor(Protocol):
    """A trained model in stable-baselines3's interface."""

    def predict(self, observation: np.ndarray, deterministic: bool = ...) -> tuple[Any, Any]:
        """Action for an observation (and a recurrent state)."""
        ...


@dataclass(frozen=True, slots=True)
class ControllerPolicy:
    """A merge controller as a policy: ``"fifo"``, ``"game"``, ``"hcomc"`` or any name
    :mod:`hcomc.control.registry` accepts (``"my_pkg.ctg:CTG"``, ``"ctg.py:CTG"``)."""

    controller: str

    def __post_init__(self) -> None:
        try:
            object.__setattr__(self, "controller", canonical_name(self.controller))
        except ConfigError as exc:
            raise ValueError(str(exc)) from None

    @property
    def name(self) -> str:
        """The controller's name as the tables print it."""
        return {"fifo": "FIFO", "game": "Game", "hcomc": "HCOMC"}.get(
            self.controller, self.controller
        )

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """The (unused) action: the controller drives VR through the engine."""
        return np.zeros(2, dtype=np.float32)


FIFO, GAME, HCOMC = ControllerPolicy("fifo"), ControllerPolicy("game"), ControllerPolicy("hcomc")
"""The paper's controllers as policies."""

Policy = Callable[[np.ndarray], np.ndarray] | Predictor | ControllerPolicy


def as_function(policy: Policy) -> Callable[[np.ndarray], np.ndarray]:
    """The policy as ``obs -> action`` (a model's deterministic prediction)."""
    if isinstance(policy, ControllerPolicy) or not hasattr(policy, "predict"):
        return policy
    model = policy

    def act(obs: np.ndarray) -> np.ndarray:
        action, _ = model.predict(obs, deterministic=True)
        return np.asarray(action)

    return act


@dataclass(frozen=True, slots=True)
class EpisodeResult:
    """One evaluated episode: the environment's outcome and the paper's metrics."""

    policy: str
    seed: int
    episode_return: float
    steps: int
    merged: bool
    collision: bool
    lane_end: bool
    timeout: bool
    metrics: dict[str, float | bool | str] = field(default_factory=dict)

    def row(self) -> dict[str, Any]:
        """Flat record for a table."""
        head = {name: getattr(self, name) for name in self.__slots__ if name != "metrics"}
        return {**head, **self.metrics}


def run_episode(
    env: MergeEnv, policy: Callable[[np.ndarray], np.ndarray], seed: int, name: str
) -> EpisodeResult:
    """One episode of ``policy`` on ``env`` with ``seed``, scored with the metrics on the
    whole run's log against its undisturbed reference."""
    obs, _ = env.reset(seed=seed)
    total, steps, done = 0.0, 0, False
    info: dict[str, Any] = {}
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        total, steps, done = total + reward, steps + 1, terminated or truncated
    log, reference = env.episode_logs()
    return EpisodeResult(
        policy=name, seed=seed, episode_return=total, steps=steps,
        merged=bool(info["merged"]), collision=bool(info["collision"]),
        lane_end=bool(info["lane_end"]), timeout=bool(info["timeout"]),
        metrics=compute_metrics(log, reference=reference),
    )  # fmt: skip


def evaluate_policies(
    policies: dict[str, Policy], seeds: Iterable[int], **env_kwargs: Any
) -> list[EpisodeResult]:
    """Run every policy on every seed (the same traffic for all) and score the episodes.

    ``env_kwargs`` are the options of :class:`MergeEnv` (``scenario``, ``action_period``,
    ``reward`` ...); a :class:`ControllerPolicy` gets an environment with its controller.
    """
    seeds = list(seeds)
    results = []
    for name, policy in policies.items():
        kwargs = dict(env_kwargs)
        if isinstance(policy, ControllerPolicy):
            kwargs["controller"] = policy.controller
        env = MergeEnv(**kwargs)
        act = as_function(policy)
        results += [run_episode(env, act, seed, name) for seed in seeds]
    return results


def policy_summary(results: Sequence[EpisodeResult]) -> pd.DataFrame:
    """Per policy: episodes, merge/collision/timeout shares, and the median of the return
    and of every metric."""
    frame = pd.DataFrame([r.row() for r in results])
    numeric = frame.drop(columns=["seed"]).select_dtypes("number").columns.tolist()
    rates = ["merged", "collision", "lane_end", "timeout"]
    grouped = frame.groupby("policy", sort=False)
    table = grouped[numeric].median()
    for col in rates:
        table[col] = grouped[col].mean()
    table.insert(0, "episodes", grouped.size())
    return table


PAIRED = ("episode_return", "critical_distance", "average_acceleration", "stabilisation_time",
          "lsrv", "fuel", "min_ttc", "pet")  # fmt: skip
"""The quantities :func:`compare_policies` compares by default."""


def compare_policies(results: Sequence[EpisodeResult], a: str, b: str,
                     metrics: Sequence[str] = PAIRED) -> pd.DataFrame:  # fmt: skip
    """Paired comparison of policies ``a`` and ``b`` seed by seed: per metric the median of
    the differences a - b over the seeds where both are finite, its 95 % bootstrap interval
    (the experiments' :func:`~hcomc.experiments.tables.median_ci`), n, and in how many of
    them ``a`` is better (larger return, critical distance, TTC and PET; smaller for the
    rest)."""
    from hcomc.experiments.tables import median_ci

    frame = pd.DataFrame([r.row() for r in results])
    left = frame[frame["policy"] == a].set_index("seed")
    right = frame[frame["policy"] == b].set_index("seed")
    seeds = left.index.intersection(right.index)
    rows = []
    for name in metrics:
        diff = (left.loc[seeds, name] - right.loc[seeds, name]).to_numpy(dtype=float)
        diff = diff[np.isfinite(diff)]
        median, low, high = median_ci(diff)
        larger = name == "episode_return" or METRICS[name].better == "larger"
        better = int((diff > 0).sum() if larger else (diff < 0).sum())
        rows.append({"metric": name, "median_diff": median, "ci_low": low, "ci_high": high,
                     "n": int(diff.size), "a_better": better})  # fmt: skip
    return pd.DataFrame(rows).set_index("metric")


__all__ = [
    "FIFO", "GAME", "HCOMC", "ControllerPolicy", "EpisodeResult", "Predictor", "as_function",
    "compare_policies", "evaluate_policies", "policy_summary", "run_episode",
]  # fmt: skip
