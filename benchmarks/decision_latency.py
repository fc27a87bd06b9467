"""Decision latency of one HCOMC decision, per optimiser, at the default budget, on one core.

Planning instants are captured from Condition 1 runs (the first ramp vehicle entering the
control zone, seeds 0..S-1); each decision is then repeated R times with fresh generators.
The whole ``HCOMCController.plan`` call is timed: lane-change game, problem set-up,
optimisation (360 candidate evaluations by default) and Eq. 19 selection. One warm-up
decision per optimiser loads the compiled kernels first. The optimisers take turns on each
planning instant (same process), so their figures are comparable under the same load. One
core unless ``NUMBA_NUM_THREADS`` says more (a main process then scores a population's rows
side by side on that many threads).

    python benchmarks/decision_latency.py [--json] [--seeds 8] [--repeats 5] [--split]

``--split`` also says where the default optimiser's decisions spend their time: the same
decisions again, with a clock around NSGA-II's compiled search (its generations on the merge
problem: the rows' rollouts, objectives and constraints, and NSGA-II's steps; the rows
counted) and around the lane-change game; the search's rows are scored again on their own,
outside the decisions' clock, for the rollouts' share. Milliseconds per decision of each and
of the rest (problem set-up, selection, the chosen plan's prediction), the rows per decision
and their mean cost.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core, comparable across machines

import argparse  # noqa: E402
import contextlib  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402
from unittest import mock  # noqa: E402

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
    """Where NSGA-II decisions' time goes, timed without a profiler: the same decisions
    again, with a clock around NSGA-II's compiled search on the merge problem (its
    generations, ``MergeProblem.nsga2_generations``, counting the rows it rolls out) and any
    other compiled row scoring (``score_rows`` and ``score_row`` as the problem calls them)
    and around the lane-change game (as the controller calls it). The search's rows are then
    scored again on their own, in one call of ``MergeProblem.evaluate`` outside the decision's
    clock, to tell the rollouts' share of the search from NSGA-II's steps. Milliseconds per
    decision of each, the rest (the problem's set-up, the selection, the chosen plan's
    prediction, in Python and compiled), the rows per decision and their mean cost [us]."""
    import hcomc.control.hierarchical.controller as controller_module
    import hcomc.control.hierarchical.problem as problem_module

    spent = {"search": 0.0, "game": 0.0, "scoring": 0.0}
    rows, counting = [0], [False]  # rows rolled out; whether the calls now are counted

    def timed(part: str, function: Callable[..., Any], count: Callable[..., int]) -> Any:
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            start = time.perf_counter()
            result = function(*args, **kwargs)
            if counting[0]:
                spent[part] += time.perf_counter() - start
                rows[0] += count(*args)
            return result

        return wrapper

    def rescored(problem: Any, archive: Any, *_: Any) -> int:
        """The search's rows rolled out (each distinct canonical row once), scored again
        on their own; their number."""
        first = archive.arrays.first[: archive.size]
        X = archive.X[: archive.size][first == np.arange(archive.size)]
        counting[0] = False  # its own calls of score_rows are not the decision's
        start = time.perf_counter()
        problem.evaluate(X)
        spent["scoring"] += time.perf_counter() - start
        counting[0] = True
        return int(X.shape[0])

    merge_problem = problem_module.MergeProblem
    patches = (
        (merge_problem, "nsga2_generations", "search", rescored),
        (problem_module, "score_rows", "search", lambda *_: 0),  # a replan's kept rows
        (problem_module, "score_row", "search", lambda *_: 0),
        (controller_module, "play_lane_change_game", "game", lambda *_, **__: 0),
    )
    total, decisions = 0.0, 0
    with contextlib.ExitStack() as stack:
        for owner, name, part, count in patches:
            wrapped = timed(part, getattr(owner, name), count)
            stack.enter_context(mock.patch.object(owner, name, wrapped))
        for config, view, group in instants:
            controller = HCOMCController(config)
            counting[0] = False
            controller.plan(view, group, np.random.default_rng(0))  # warm, not counted
            counting[0] = True
            for r in range(repeats):
                outside = spent["scoring"]  # the scoring again is not the decision's
                start = time.perf_counter()
                controller.plan(view, group, np.random.default_rng(r))
                total += time.perf_counter() - start - (spent["scoring"] - outside)
                decisions += 1
    search, game = spent["search"] / decisions, spent["game"] / decisions
    return {"decision_ms": round(1e3 * total / decisions, 2),
            "search_ms": round(1e3 * search, 2),
            "scoring_ms": round(1e3 * spent["scoring"] / decisions, 2),
            "game_ms": round(1e3 * game, 2),
            "rest_ms": round(1e3 * (total / decisions - search - game), 2),
            "rows_per_decision": round(rows[0] / decisions, 1),
            "us_per_row": round(1e6 * spent["scoring"] / max(rows[0], 1), 1)}  # fmt: skip


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
