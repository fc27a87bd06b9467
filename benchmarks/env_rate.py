"""Environment steps per second: ``hcomc/Merge-v0`` (one environment, and the native vector
environment) against highway-env's ``merge-v0``, side by side in one process run.

Both take uniformly random actions from their action spaces (seeded) and restart episodes as
they end; each configuration runs ``--seconds`` of wall time per repetition after a warm-up
(numba's kernels load from its cache, highway-env imports), configurations alternate within
each repetition and the median is reported. hcomc runs with a 1 s action period, the policy
period of highway-env's merge-v0 (``policy_frequency = 1``, 15 simulation frames per step),
so one environment step is one simulated second in both. Also reported: simulated seconds
per second, the mean number of vehicles in the scene and simulated vehicle-seconds per second
(independent of each engine's own time step: 0.1 s here, 1/15 s in highway-env). The vector
environment is measured on one thread and on all the threads numba may use (``--threads``
picks others): on a machine whose cores do not add throughput, one thread is faster.

    pip install -e ".[envs,bench]"
    python benchmarks/env_rate.py [--json] [--vector 64] [--seconds 10] [--repeats 3]
        [--threads 1 2]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
import warnings
from collections.abc import Callable

import gymnasium as gym
import numba
import numpy as np
from throughput import machine

import hcomc.envs  # noqa: F401 (registers hcomc/Merge-v0)
from hcomc.envs import MergeEnv
from hcomc.envs.vector import MergeVectorEnv

PERIOD = 1.0  # [s] simulated per environment step, as highway-env's merge-v0


Runner = tuple[Callable[[], int], Callable[[], float], float]
"""``(step, vehicles, period)``: one step (returns environment steps taken), the current scene
size, and the simulated seconds per environment step."""


def one_env(env: gym.Env, vehicles: Callable[[], float], period: float) -> Runner:
    """A single environment stepped with random actions, restarted when an episode ends."""
    env.action_space.seed(0)
    env.reset(seed=0)

    def step() -> int:
        _, _, term, trunc, _ = env.step(env.action_space.sample())
        if term or trunc:
            env.reset()
        return 1

    return step, vehicles, period


def highway_env() -> Runner:
    """highway-env's merge-v0."""
    import highway_env  # noqa: F401 (registers merge-v0)

    env = gym.make("merge-v0")
    period = 1.0 / env.unwrapped.config["policy_frequency"]
    return one_env(env, lambda: float(len(env.unwrapped.road.vehicles)), period)


def hcomc_single() -> Runner:
    """``hcomc/Merge-v0``, one environment."""
    env = MergeEnv("C1", action_period=PERIOD)
    return one_env(env, lambda: float(env.episode.sim.active.sum()), PERIOD)  # type: ignore[union-attr]


def hcomc_vector(n: int, threads: int | None) -> Runner:
    envs = MergeVectorEnv(n, threads=threads, scenario="C1", action_period=PERIOD)
    envs.action_space.seed(0)
    envs.reset(seed=0)

    def step() -> int:
        envs.step(envs.action_space.sample())
        return n

    def vehicles() -> float:
        return float(np.mean([e.sim.active.sum() for e in envs.episodes if e is not None]))

    return step, vehicles, PERIOD


def measure(step: Callable[[], int], vehicles: Callable[[], float], seconds: float) -> dict:
    """Steps per second over ``seconds`` of wall time (the steps' own time: the scene size,
    sampled every 10th step, is not counted), and the mean scene size."""
    steps, sizes, busy = 0, [], 0.0
    start = time.perf_counter()
    while time.perf_counter() - start < seconds:
        before = time.perf_counter()
        steps += step()
        busy += time.perf_counter() - before
        if len(sizes) * 10 <= steps:
            sizes.append(vehicles())
    return {"steps_per_s": steps / busy, "vehicles": float(np.mean(sizes))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--vector", type=int, default=64, help="environments in the vector")
    parser.add_argument("--threads", type=int, nargs="+", default=None,
                        help="cores for the vector env, one configuration each "
                             "(default: 1 and all numba may use)")  # fmt: skip
    parser.add_argument("--seconds", type=float, default=10.0, help="wall time per run [s]")
    parser.add_argument("--repeats", type=int, default=3, help="repetitions (median)")
    args = parser.parse_args()
    warnings.filterwarnings("ignore")
    most = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    threads = args.threads or sorted({1, most})
    makers: dict[str, Callable[[], Runner]] = {
        "highway-env merge-v0": highway_env,
        "hcomc/Merge-v0": hcomc_single,
    }
    for n in threads:
        name = f"hcomc/Merge-v0 vector of {args.vector}, {n} thread{'s' if n > 1 else ''}"
        makers[name] = lambda n=n: hcomc_vector(args.vector, n)
    built = {name: make() for name, make in makers.items()}
    for step, _, _ in built.values():  # warm-up: kernels, imports
        for _ in range(3):
            step()
    runs: dict[str, list[dict]] = {name: [] for name in built}
    for _ in range(args.repeats):
        for name, (step, vehicles, _) in built.items():
            runs[name].append(measure(step, vehicles, args.seconds))
    base = statistics.median(r["steps_per_s"] for r in runs["highway-env merge-v0"])
    results = []
    for name, (_, _, period) in built.items():
        rate = statistics.median(r["steps_per_s"] for r in runs[name])
        size = statistics.median(r["vehicles"] for r in runs[name])
        results.append({
            "configuration": name, "steps_per_s": round(rate, 1),
            "ratio_vs_highway_env": round(rate / base, 2),
            "simulated_s_per_s": round(rate * period, 1), "vehicles": round(size, 1),
            "vehicle_seconds_per_s": round(rate * period * size),
        })  # fmt: skip
    report = {"machine": machine(), "seconds": args.seconds, "repeats": args.repeats,
              "action_period_s": PERIOD, "results": results}  # fmt: skip
    if args.json:
        print(json.dumps(report, indent=2))
        return
    print(f"{'configuration':44s} {'steps/s':>10s} {'x highway-env':>14s} {'sim s/s':>9s} "
          f"{'vehicles':>9s}")  # fmt: skip
    for r in results:
        print(f"{r['configuration']:44s} {r['steps_per_s']:10.1f} "
              f"{r['ratio_vs_highway_env']:14.2f} {r['simulated_s_per_s']:9.1f} "
              f"{r['vehicles']:9.1f}")  # fmt: skip


if __name__ == "__main__":
    main()
