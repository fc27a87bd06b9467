"""Recorded HCOMC decision problems: Pareto-front hypervolume and decision time per optimiser.

Recording (``--record``, once): the first planning instant (``TrafficView`` + ``MergeGroup``)
of seeded runs of Conditions C1-C5 with the HCOMC controller, cycling through the conditions
and seeds 0, 1, ... until ``--count`` problems are found (instants without a lane-1 vehicle
behind VR are skipped: no optimisation happens there). Each problem is stored as plain data
(arrays, the resolved config as JSON, the key-vehicle ids) in ``benchmarks/data/decisions.pkl``,
so the file does not depend on the engine's classes. With it go one fixed reference point per
problem for the hypervolume: the per-objective worst feasible value over 2,000 uniform random
candidates and the NSGA-II fronts of three seeds, plus 10 % of that objective's range.

Evaluation: every recorded problem is decided ``--repeats`` times (generators seeded 0..R-1) by
a full ``HCOMCController.plan`` call with the given optimiser at the config's budget (or at
``--budget`` candidate evaluations, to see what a smaller budget costs in quality); the
hypervolume (pymoo ``HV``) of the returned feasible front against the problem's reference
point is averaged over the repeats, and all decision times give the median and p95. With
``--save-baseline`` the per-problem hypervolumes are stored as the baseline; later
evaluations (e.g. of a faster optimiser: :func:`evaluate` takes any ``Optimizer``) report
the ratio to it per problem.

With several ``--optimizer`` options the optimisers take each decision in turn, in one process
(:func:`evaluate_side_by_side`), and ``identical_to_first`` counts the decisions whose Pareto set
equals the first optimiser's bit for bit. One core unless ``NUMBA_NUM_THREADS`` says more (a
main process then scores a population's rows side by side on that many threads).

    python benchmarks/record_decisions.py [--record] [--count 60] [--optimizer nsga2 ...]
                                          [--repeats 3] [--budget N] [--save-baseline] [--json]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core, as decision_latency.py

import argparse  # noqa: E402
import json  # noqa: E402
import pickle  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass, fields  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any, NoReturn  # noqa: E402

import numpy as np  # noqa: E402
from pymoo.indicators.hv import HV  # noqa: E402
from throughput import machine  # noqa: E402

from hcomc.config import ConfigError, ScenarioConfig, load_config, validate_config  # noqa: E402
from hcomc.control.hierarchical.controller import HCOMCController, HCOMCDetails  # noqa: E402
from hcomc.interface import (  # noqa: E402
    Fleet,
    MergeGroup,
    Ramp,
    TrafficView,
)
from hcomc.optim.base import Optimizer  # noqa: E402
from hcomc.optim.registry import OPTIMIZERS, optimizer_from_config  # noqa: E402
from hcomc.sim.engine import Simulation  # noqa: E402

DATA = Path(__file__).with_name("data")
PROBLEMS_FILE = DATA / "decisions.pkl"
CONDITIONS = ("C1", "C2", "C3", "C4", "C5")
REFERENCE_SAMPLES = 2000
REFERENCE_SEEDS = 3
REFERENCE_MARGIN = 0.1  # of each objective's range


@dataclass(frozen=True, slots=True)
class Decision:
    """One recorded decision problem, rebuilt into the engine's types."""

    name: str  # "C1-seed0"
    config: ScenarioConfig
    view: TrafficView
    group: MergeGroup
    reference: np.ndarray  # (n_obj,) hypervolume reference point


def fail(message: str) -> NoReturn:
    """One-line error on stderr, exit status 2."""
    print(f"error: {message}", file=sys.stderr)
    sys.exit(2)


# --------------------------------------------------------------------------- recording
def _plain(name: str, view: TrafficView, group: MergeGroup) -> dict[str, Any]:
    """A planning instant as plain data (numpy arrays, builtins)."""
    if view.plans:
        raise ValueError(f"{name}: a first planning instant should have no live plans")
    return {
        "name": name,
        "config": view.config.model_dump(mode="json"),
        "t": float(view.t),
        **{k: np.array(getattr(view, k)) for k in ("x", "v", "a", "lane", "active", "changing")},
        "kind": np.array(view.fleet.kind),
        "scripted": np.array(view.fleet.scripted),
        "group": {f.name: int(getattr(group, f.name)) for f in fields(group)},
    }


def _rebuild(record: dict[str, Any]) -> tuple[ScenarioConfig, TrafficView, MergeGroup]:
    """The engine's view and group of a plain record."""
    config = validate_config(record["config"], record["name"])
    fleet = Fleet.build(config, record["kind"], record["scripted"])
    arrays = {k: record[k] for k in ("x", "v", "a", "lane", "active", "changing")}
    view = TrafficView(
        t=record["t"], fleet=fleet, config=config, ramp=Ramp.of(config.road), **arrays
    )
    return config, view, MergeGroup(**record["group"])


def capture(count: int) -> list[dict[str, Any]]:
    """First planning instants of C1-C5 runs (seeds 0, 1, ...) with a lane-1 vehicle behind VR."""
    records: list[dict[str, Any]] = []
    seed = 0
    while len(records) < count:
        for condition in CONDITIONS:
            config = load_config(condition, control={"controller": "hcomc"})
            sim = Simulation(config, seed)
            if sim.run_until_plan() is None:
                continue
            view, group = sim.requests[0]
            if group.vmc < 0:
                continue
            record = _plain(f"{condition}-seed{seed}", view, group)
            _check_rebuild(record, view)
            records.append(record)
            if len(records) == count:
                break
        seed += 1
    return records


def _check_rebuild(record: dict[str, Any], view: TrafficView) -> None:
    """The rebuilt fleet must equal the engine's (the problem is stored faithfully)."""
    fleet = _rebuild(record)[1].fleet
    for field in ("kind", "matrix", "iidm", "lc_duration", "length", "width", "scripted"):
        if not np.array_equal(getattr(fleet, field), getattr(view.fleet, field)):
            raise ValueError(f"{record['name']}: rebuilt fleet differs in '{field}'")


def reference_point(config: ScenarioConfig, view: TrafficView, group: MergeGroup) -> np.ndarray:
    """Worst feasible objectives of random candidates and NSGA-II fronts, plus a margin."""
    controller = HCOMCController(config)
    problem, _ = controller.problem(view, group)
    rng = np.random.default_rng(12345)
    xl, xu = np.asarray(problem.xl, float), np.asarray(problem.xu, float)
    X = xl + rng.random((REFERENCE_SAMPLES, xl.size)) * (xu - xl)
    F, G = problem.evaluate(X)
    fronts = [F[np.all(G <= 0, axis=1)]]
    for seed in range(REFERENCE_SEEDS):
        plan = controller.plan(view, group, np.random.default_rng(seed))
        if isinstance(plan.details, HCOMCDetails):
            pareto = plan.details.pareto
            fronts.append(pareto.F[pareto.feasible])
    feasible = np.vstack(fronts)
    if feasible.size == 0:
        return np.full(problem.n_obj, np.nan)  # nothing feasible found: hypervolume is 0
    worst, best = feasible.max(axis=0), feasible.min(axis=0)
    span = np.maximum(worst - best, 1e-9 * np.maximum(1.0, np.abs(worst)))
    return worst + REFERENCE_MARGIN * span


def record(count: int, path: Path = PROBLEMS_FILE) -> None:
    """Capture ``count`` problems with their reference points into ``path``."""
    if path.exists():
        fail(f"{path} exists; remove it to record new problems (nothing was overwritten)")
    records = capture(count)
    for rec in records:
        rec["reference"] = reference_point(*_rebuild(rec))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    with tmp.open("wb") as fh:
        pickle.dump({"version": 1, "problems": records}, fh, protocol=pickle.HIGHEST_PROTOCOL)
    tmp.replace(path)


def load_decisions(path: Path = PROBLEMS_FILE) -> list[Decision]:
    """The recorded problems, rebuilt."""
    with path.open("rb") as fh:
        data = pickle.load(fh)  # our own file of plain data
    return [Decision(r["name"], *_rebuild(r), np.asarray(r["reference"])) for r in data["problems"]]


def with_budget(decisions: list[Decision], budget: int) -> list[Decision]:
    """The same problems decided with ``budget`` candidate evaluations (``control.budget``,
    validated as a config value is)."""
    out = []
    for d in decisions:
        raw = d.config.model_dump(mode="json")
        raw["control"]["budget"] = budget
        out.append(Decision(d.name, validate_config(raw, d.name), d.view, d.group, d.reference))
    return out


# --------------------------------------------------------------------------- evaluation
def hypervolume(front: np.ndarray, reference: np.ndarray) -> float:
    """Hypervolume of the (feasible) front against ``reference``; 0 for an empty front."""
    if front.size == 0 or np.isnan(reference).any():
        return 0.0
    inside = front[np.all(front < reference, axis=1)]
    return float(HV(ref_point=reference)(inside)) if inside.size else 0.0


def evaluate(
    decisions: list[Decision], optimizer: Optimizer | None = None, repeats: int = 3
) -> dict[str, Any]:
    """Decide every problem ``repeats`` times with ``optimizer`` (None: the config's own).

    Returns the per-problem mean hypervolume, the number of problems with a feasible plan,
    and the decision time median / p95 / max [ms] over all decisions.
    """
    return evaluate_side_by_side(decisions, [optimizer], repeats)[0]


def evaluate_side_by_side(
    decisions: list[Decision], optimizers: list[Optimizer | None], repeats: int = 3
) -> list[dict[str, Any]]:
    """:func:`evaluate` for several optimisers in one pass: each decision is taken by every
    optimiser in turn (same problem, same generator seed), so that machine load affects their
    times alike. ``identical_to_first`` counts decisions whose Pareto set equals the first
    optimiser's bit for bit."""
    times: list[list[float]] = [[] for _ in optimizers]
    rows: list[list[dict[str, Any]]] = [[] for _ in optimizers]
    identical = [0 for _ in optimizers]
    for k, d in enumerate(decisions):
        chosen = [opt or optimizer_from_config(d.config.control) for opt in optimizers]
        if k == 0:
            for opt in chosen:  # warm-up: compiled kernels loaded outside the timed calls
                HCOMCController(d.config, optimizer=opt).plan(
                    d.view, d.group, np.random.default_rng(0)
                )
        volumes: list[list[float]] = [[] for _ in optimizers]
        for r in range(repeats):
            first: np.ndarray | None = None
            for i, opt in enumerate(chosen):
                fresh = HCOMCController(d.config, optimizer=opt)  # no warm start between repeats
                start = time.perf_counter()
                plan = fresh.plan(d.view, d.group, np.random.default_rng(r))
                times[i].append((time.perf_counter() - start) * 1e3)
                assert isinstance(plan.details, HCOMCDetails)
                pareto = np.asarray(plan.details.pareto.X)
                first = pareto if i == 0 else first
                identical[i] += int(first is not None and np.array_equal(pareto, first))
                feasible = plan.details.pareto.F[plan.details.pareto.feasible]
                volumes[i].append(hypervolume(feasible, d.reference))
        for i in range(len(optimizers)):
            rows[i].append({"problem": d.name, "hypervolume": float(np.mean(volumes[i]))})
    results = []
    for i, opt in enumerate(optimizers):
        ms = np.array(times[i])
        results.append(
            {
                "optimizer": (opt or optimizer_from_config(decisions[0].config.control)).name,
                "budget": decisions[0].config.control.budget,
                "problems": len(decisions),
                "decisions": int(ms.size),
                "median_ms": round(float(np.median(ms)), 1),
                "p95_ms": round(float(np.percentile(ms, 95)), 1),
                "max_ms": round(float(ms.max()), 1),
                "with_feasible_front": sum(r["hypervolume"] > 0 for r in rows[i]),
                "identical_to_first": identical[i],
                "per_problem": rows[i],
            }
        )
    return results


def against_baseline(result: dict[str, Any], baseline: dict[str, Any]) -> dict[str, float]:
    """Hypervolume ratios to the baseline over problems where the baseline has a front."""
    base = {r["problem"]: r["hypervolume"] for r in baseline["per_problem"]}
    ratios = np.array(
        [
            r["hypervolume"] / base[r["problem"]]
            for r in result["per_problem"]
            if base.get(r["problem"], 0.0) > 0
        ]
    )
    return {
        "problems": int(ratios.size),
        "mean_ratio": round(float(ratios.mean()), 4),
        "median_ratio": round(float(np.median(ratios)), 4),
        "min_ratio": round(float(ratios.min()), 4),
    }


def _problems(path: Path, record_first: bool, count: int, budget: int | None) -> list[Decision]:
    """The problems of ``path`` (recorded first with ``record_first``), at ``budget`` if
    given."""
    if record_first:
        record(count, path)
    if not path.exists():
        fail(f"{path} missing; run with --record first")
    decisions = load_decisions(path)
    try:
        return decisions if budget is None else with_budget(decisions, budget)
    except ConfigError as exc:
        fail(str(exc))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", action="store_true", help="capture the problems first")
    parser.add_argument("--count", type=int, default=60, help="problems to record (>= 50)")
    parser.add_argument(
        "--optimizer",
        choices=sorted(OPTIMIZERS),
        action="append",
        default=None,
        help="optimiser to evaluate (default: each config's own, NSGA-II); repeat it to "
        "compare several side by side in one run, e.g. --optimizer nsga2-pymoo --optimizer nsga2",
    )
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--budget", type=int, default=None, help="candidate evaluations per decision "
        "(default: each recorded config's own, 360)",
    )  # fmt: skip
    parser.add_argument(
        "--save-baseline",
        action="store_true",
        help="store the hypervolumes as the baseline (<problems>_baseline.json)",
    )
    parser.add_argument("--problems", type=Path, default=PROBLEMS_FILE, help="problems file")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.count < 1 or args.repeats < 1:
        parser.error("--count and --repeats must be >= 1")
    if args.budget is not None and args.save_baseline:
        parser.error("--save-baseline records the configs' own budget; drop --budget")
    baseline = args.problems.with_name(args.problems.stem + "_baseline.json")
    if args.save_baseline and baseline.exists():
        fail(f"{baseline} exists; remove it to store a new baseline (nothing was overwritten)")
    decisions = _problems(args.problems, args.record, args.count, args.budget)
    optimizers: list[Optimizer | None] = [None]
    if args.optimizer is not None:
        optimizers = []
        for name in args.optimizer:
            control = decisions[0].config.control.model_copy(update={"optimizer": name})
            optimizers.append(optimizer_from_config(control))
    results = evaluate_side_by_side(decisions, optimizers, args.repeats)
    if args.save_baseline:
        baseline.write_text(json.dumps({"machine": machine(), **results[0]}, indent=1) + "\n")
    if baseline.exists():
        reference = json.loads(baseline.read_text())
        for result in results:
            result["vs_baseline"] = against_baseline(result, reference)
    if args.json:
        print(json.dumps({"machine": machine(), "results": results}))
        return
    print("machine:", ", ".join(f"{k} {v}" for k, v in machine().items()))
    for result in results:
        print(
            f"{result['optimizer']}: {result['problems']} problems x {args.repeats} decisions, "
            f"budget {result['budget']}; {result['with_feasible_front']} with a feasible front; "
            f"{result['identical_to_first']} Pareto sets identical to {results[0]['optimizer']}'s"
        )
        print(
            f"  decision time median {result['median_ms']} ms, p95 {result['p95_ms']} ms, "
            f"max {result['max_ms']} ms"
        )
        hv = np.array([r["hypervolume"] for r in result["per_problem"]])
        print(f"  hypervolume per problem: median {np.median(hv):.4g}, mean {hv.mean():.4g}")
        if "vs_baseline" in result:
            print("  vs baseline:", ", ".join(f"{k} {v}" for k, v in result["vs_baseline"].items()))


if __name__ == "__main__":
    main()
