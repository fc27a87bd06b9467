"""Decision latency of one HCOMC decision, per optimiser, at the default budget, on one core.

Planning instants are captured from Condition 1 runs (the first ramp vehicle entering the
control zone, seeds 0..S-1); each decision is then repeated R times with fresh generators.
The whole ``HCOMCController.plan`` call is timed: lane-change game, problem set-up,
optimisation (360 candidate evaluations by default) and Eq. 19 selection. One warm-up
decision per optimiser loads the compiled kernels first. The optimisers take turns on each
planning instant (same process), so their figures are comparable under the same load.

    python benchmarks/decision_latency.py [--json] [--seeds 8] [--repeats 5] [--split]

``--split`` also says where the default optimiser's decisions spend their time: the same
decisions again under cProfile, the share of the compiled scoring of candidate rows
(``score_rows``: rollout, objectives, constraints) and of the lane-change game, and the rest
(the optimiser's own steps, problem set-up and selection in Python). cProfile's own cost
inflates the Python part a little; the shares, not the times, are the figures.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core, comparable across machines

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from throughput import machine  # noqa: E402

from hcomc.config import load_config  # noqa: E402
from hcomc.control.hierarchical.controller import HCOMCController  # noqa: E402
from hcomc.sim.engine import Simulation  # noqa: E402

OPTIMIZERS = ("nsga2", "nsga2-pymoo", "pso", "pso-pymoo", "sa", "sa-scipy")
"""Measured side by side: the compiled NSGA-II (the default), pymoo's, the lean PSO, pymoo's, SA
on arrays, SciPy's."""


def planning_instants(n_seeds: int) -> list:
    """(config, view, group) of the first decision in C1 for seeds 0..n_seeds-1."""
    found = []
    for seed in range(n_seeds):
        config = load_config("C1", control={"controller": "hcomc"})
        sim = Simulation(config, seed)
        if sim.run_until_plan() is not None:
            found.append((config, *sim.requests[0]))
    return found


def measure(optimizers: tuple[str, ...], instants: list, repeats: int) -> list[dict[str, float]]:
    """Median, p95 and max wall time [ms] of the decisions, per optimiser.

    The optimisers take turns instant by instant, so that machine load affects them alike.
    """
    times: dict[str, list[float]] = {name: [] for name in optimizers}
    for i, (config, view, group) in enumerate(instants):
        for optimizer in optimizers:
            cfg = config.model_copy(update={"control": config.control.model_copy(
                update={"optimizer": optimizer})})  # fmt: skip
            controller = HCOMCController(cfg)
            if i == 0:
                controller.plan(view, group, np.random.default_rng(0))  # warm-up
            for r in range(repeats):
                start = time.perf_counter()
                controller.plan(view, group, np.random.default_rng(r))
                times[optimizer].append((time.perf_counter() - start) * 1e3)
    rows = []
    for optimizer in optimizers:
        ms = np.array(times[optimizer])
        rows.append(
            {
                "optimizer": optimizer,
                "decisions": int(ms.size),
                "median_ms": round(float(np.median(ms)), 1),
                "p95_ms": round(float(np.percentile(ms, 95)), 1),
                "max_ms": round(float(ms.max()), 1),
                "budget": instants[0][0].control.budget,
            }
        )
    return rows


def split(instants: list, repeats: int) -> dict[str, float]:
    """Shares [%] of NSGA-II decisions' time under cProfile: the compiled row scoring, the
    lane-change game, and everything else."""
    import cProfile
    import pstats

    profile = cProfile.Profile()
    for config, view, group in instants:
        controller = HCOMCController(config)
        controller.plan(view, group, np.random.default_rng(0))  # warm, unprofiled
        profile.enable()
        for r in range(repeats):
            controller.plan(view, group, np.random.default_rng(r))
        profile.disable()
    stats = pstats.Stats(profile).stats  # type: ignore[attr-defined]
    total = sum(tt for _, _, tt, _, _ in stats.values())

    def own(name: str, cumulative: bool) -> float:
        return sum((ct if cumulative else tt) for (_, _, fn), (_, _, tt, ct, _) in stats.items()
                   if fn == name)  # fmt: skip

    scoring = own("score_rows", False) + own("score_row", False)
    game = own("lane_change_game", True)
    return {"row_scoring_pct": round(100 * scoring / total, 1),
            "game_pct": round(100 * game / total, 1),
            "rest_pct": round(100 * (total - scoring - game) / total, 1)}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--split", action="store_true", help="where NSGA-II's time goes")
    args = parser.parse_args()
    instants = planning_instants(args.seeds)
    rows = measure(OPTIMIZERS, instants, args.repeats)
    shares = split(instants, args.repeats) if args.split else None
    if args.json:
        print(json.dumps({"machine": machine(), "results": rows, "split": shares}))
        return
    print("machine:", ", ".join(f"{k} {v}" for k, v in machine().items()))
    print(
        f"{'optimiser':>11} {'decisions':>9} {'budget':>6} {'median ms':>10} {'p95 ms':>8}"
        f" {'max ms':>8}"
    )
    for r in rows:
        print(
            f"{r['optimizer']:>11} {r['decisions']:>9} {r['budget']:>6} {r['median_ms']:>10}"
            f" {r['p95_ms']:>8} {r['max_ms']:>8}"
        )
    if shares:
        print("nsga2 decisions:", ", ".join(f"{k} {v}" for k, v in shares.items()))


if __name__ == "__main__":
    main()
