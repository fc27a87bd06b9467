"""Train PPO (stable-baselines3) on ``hcomc/Merge-v0`` and compare it with FIFO, Game and
HCOMC on the same seeds with the paper's metrics.

    pip install -e ".[rl]"
    python examples/train_ppo.py [--scenario C1] [--timesteps 200000] [--envs 8]
                                 [--eval-seeds 30] [--out results/rl]

The agent drives the ramp CAV VR (continuous acceleration and the moment of its lane
change); training episodes use seeds from 10000 on, so the evaluation seeds 0..N-1 are
traffic the policy has never seen. Observations and rewards are normalised during training
(``VecNormalize``); the evaluation uses the frozen observation statistics and the
deterministic action. Writes to ``--out``: ``ppo_merge.zip`` (the policy),
``vecnormalize.pkl``, ``episodes.csv`` (one row per policy and seed: return, outcome and
every metric), ``comparison.md`` (medians per policy, then PPO against each controller seed
by seed), ``paired.csv`` and ``run.json`` (what ran).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pandas as pd
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.logger import Logger
from stable_baselines3.common.vec_env import VecNormalize

import hcomc
from hcomc import (
    ControllerPolicy,
    MergeEnv,
    compare_policies,
    evaluate_policies,
    git_revision,
    policy_summary,
)

TRAIN_SEEDS = 10_000
COLUMNS = ("episodes", "merged", "collision", "lane_end", "timeout", "episode_return",
           "critical_distance", "average_acceleration", "stabilisation_time", "lsrv", "fuel",
           "min_ttc", "pet")  # fmt: skip


def train(args: argparse.Namespace) -> tuple[PPO, VecNormalize]:
    """PPO with stable-baselines3's defaults but for the rollout length."""
    options = {"scenario": args.scenario, "action_period": args.action_period}
    venv = make_vec_env(MergeEnv, n_envs=args.envs, seed=TRAIN_SEEDS, env_kwargs=options)
    venv = VecNormalize(venv, norm_obs=True, norm_reward=True, clip_obs=10.0)
    model = PPO("MlpPolicy", venv, n_steps=256, batch_size=256, seed=args.seed, device="cpu",
                verbose=0)  # fmt: skip
    # silent, and no folder: stable-baselines3's default logger makes one in the temp folder
    model.set_logger(Logger(folder=None, output_formats=[]))
    model.learn(total_timesteps=args.timesteps)
    venv.training = False
    return model, venv


def markdown(table: pd.DataFrame) -> str:
    """The comparison as a Markdown table (medians; shares for the outcomes)."""
    cols = [c for c in COLUMNS if c in table.columns]
    lines = ["| policy | " + " | ".join(cols) + " |", "|---|" + "---:|" * len(cols)]
    for name, row in table.iterrows():
        cells = [f"{row[c]:.0f}" if c == "episodes" else f"{row[c]:.3g}" for c in cols]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def paired_markdown(pairs: pd.DataFrame) -> str:
    """PPO against each controller, seed by seed (median difference PPO - controller)."""
    lines = ["| PPO vs | metric | median difference [95 % CI] | PPO better in |",
             "|---|---|---|---:|"]  # fmt: skip
    for (versus, metric), row in pairs.iterrows():
        ci = f"{row['median_diff']:.3g} [{row['ci_low']:.3g}, {row['ci_high']:.3g}]"
        lines.append(f"| {versus} | {metric} | {ci} | {int(row['a_better'])} of {int(row['n'])} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> pd.DataFrame:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="C1", help="condition preset or scenario TOML")
    parser.add_argument("--timesteps", type=int, default=200_000, help="training steps")
    parser.add_argument("--envs", type=int, default=8, help="parallel training episodes")
    parser.add_argument("--eval-seeds", type=int, default=30, help="evaluation seeds 0..N-1")
    parser.add_argument("--action-period", type=float, default=0.5, help="seconds per step")
    parser.add_argument("--seed", type=int, default=0, help="PPO's seed")
    parser.add_argument("--out", type=Path, default=Path("results/rl"))
    args = parser.parse_args(argv)
    torch.set_num_threads(1)  # the simulator uses the other core
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    model, venv = train(args)
    trained = time.perf_counter() - start
    model.save(args.out / "ppo_merge.zip")
    venv.save(str(args.out / "vecnormalize.pkl"))

    def ppo(obs: np.ndarray) -> np.ndarray:
        action, _ = model.predict(venv.normalize_obs(obs), deterministic=True)
        return np.asarray(action)

    baselines = {p.name: p for p in map(ControllerPolicy, ["fifo", "game", "hcomc"])}
    results = evaluate_policies(
        {"PPO": ppo, **baselines},
        seeds=range(args.eval_seeds),
        scenario=args.scenario,
        action_period=args.action_period,
    )
    pd.DataFrame([r.row() for r in results]).to_csv(args.out / "episodes.csv", index=False)
    table = policy_summary(results)
    versus = [compare_policies(results, "PPO", name).assign(versus=name) for name in baselines]
    pairs = pd.concat(versus).reset_index().set_index(["versus", "metric"])
    pairs.to_csv(args.out / "paired.csv")
    (args.out / "comparison.md").write_text(markdown(table) + "\n" + paired_markdown(pairs))
    run = {
        "scenario": args.scenario, "timesteps": args.timesteps, "envs": args.envs,
        "eval_seeds": args.eval_seeds, "action_period": args.action_period, "seed": args.seed,
        "train_seeds_from": TRAIN_SEEDS, "training_s": round(trained, 1),
        "hcomc_version": hcomc.__version__, "git_revision": git_revision(),
        "torch": torch.__version__,
    }  # fmt: skip
    (args.out / "run.json").write_text(json.dumps(run, indent=2) + "\n")
    print(markdown(table))
    print(paired_markdown(pairs))
    return table


if __name__ == "__main__":
    main()
