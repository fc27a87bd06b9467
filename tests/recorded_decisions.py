"""The recorded first planning instants of C1-C5 (``benchmarks/record_decisions.py``,
``benchmarks/data/decisions.pkl``), shared by the tests that score real merge problems, with
:func:`problem_variants` and :func:`threshold_rows` to vary them; and :func:`compare_quality`, a
compiled optimiser's solution quality against its library reference on them (hypervolume and
best Eq. 19 cost, paired over seeds)."""

from __future__ import annotations

import itertools
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
from pymoo.indicators.hv import HV

from hcomc._typing import FloatArray
from hcomc.config import ScenarioConfig
from hcomc.control.hierarchical.controller import HCOMCController
from hcomc.control.hierarchical.problem import OBJECTIVES, MergeProblem
from hcomc.equations.selection import eq19_costs
from hcomc.interface import MergeGroup, TrafficView
from hcomc.optim.base import ParetoResult
from hcomc.optim.registry import POPULATION_BASED, make_optimizer

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
Instant = tuple[str, ScenarioConfig, TrafficView, MergeGroup]


@cache
def recorded_instants() -> tuple[Instant, ...]:
    """The 60 recorded instants (``record_decisions.load_decisions``): name, config, view and
    key group of each."""
    sys.path.insert(0, str(BENCHMARKS))  # record_decisions imports its sibling throughput.py
    environ = dict(os.environ)  # the script pins its thread variables to 1 when imported
    try:
        from record_decisions import load_decisions
    finally:
        sys.path.remove(str(BENCHMARKS))
        # numba rereads NUMBA_NUM_THREADS at every compilation and refuses a change once its
        # threads run: the rest of the test session must see the variables it started with
        os.environ.clear()
        os.environ.update(environ)
    return tuple((d.name, d.config, d.view, d.group) for d in load_decisions())


def recorded_problem(index: int) -> MergeProblem:
    """A fresh merge problem of recorded instant ``index``, as the controller builds it."""
    _, config, view, group = recorded_instants()[index]
    return HCOMCController(config).problem(view, group)[0]


@dataclass(frozen=True, slots=True)
class Quality:
    """A compiled optimiser against its library reference on recorded problems, paired over
    seeds (one pair of runs per problem and seed, same generator seed, same budget).

    ``hv_ratio``: mean over the pairs of HV(compiled) / HV(library), each the hypervolume of
    the returned feasible set with the problem's objectives min-max normalised over the union
    of every feasible row returned on that problem (both optimisers, all seeds) and reference
    point 1.1 in every objective (the union's worst value plus 10 % of its range).
    ``cost_gap``: mean over the pairs of best(compiled) - best(library), ``best`` being the
    lowest Eq. 19 cost (:func:`hcomc.equations.selection.eq19_costs`, the quantity the controller's
    pick minimises) of a run's feasible rows, costs taken over that same union so that they are
    comparable across runs (0 is the best, 2 the worst row of the union in the gate branch). A
    row above the gate while other rows of the union pass it costs 2 plus its U_safe min-max
    normalised over those rows (:func:`union_costs`): worse than every row that passes, as
    Eq. 19 ranks them, so a run that found no row passing the gate scores in [2, 3].
    ``cost_spread``: the library's spread, the range (max - min) of the finite Eq. 19 costs of
    the rows a library run returns (those of :func:`~hcomc.equations.selection.eq19_costs`, the
    rows outside the gate left out), on the same scale, averaged over its runs: how much the
    candidates it offers the controller differ. ``pairs`` holds (problem index, seed,
    HV compiled, HV library, best compiled, best library) per pair.
    """

    hv_ratio: float
    cost_gap: float
    cost_spread: float
    pairs: tuple[tuple[int, int, float, float, float, float], ...]


MODE_EDGES = np.array([0.0, 1.0, 0.5, np.nextafter(0.5, 0.0), 1.5, np.nextafter(1.0, 0.0)])
"""Values of the mode and sequence variables at and beside their thresholds (0.5, 1.0)."""


def problem_variants(problem: MergeProblem) -> list[MergeProblem]:
    """The problem, without a vehicle to merge behind, with lateral cooperation admitted in
    both sequences, and HCOMC+ (the mode "none")."""
    plus = problem.config.model_copy(
        update={"control": problem.config.control.model_copy(update={"no_cooperation": True})}
    )
    return [
        problem,
        MergeProblem((problem.state, None), problem.config, problem.lateral_allowed),
        MergeProblem(problem.states, problem.config, (True, True)),
        MergeProblem(problem.states, plus, problem.lateral_allowed),
    ]


def threshold_rows(problem: MergeProblem, n: int, seed: int) -> FloatArray:
    """``n`` rows in the bounds, the mode and sequence variables often at their thresholds."""
    rng = np.random.default_rng(seed)
    xl, xu = np.asarray(problem.xl), np.asarray(problem.xu)
    X = xl + rng.random((n, xl.size)) * (xu - xl)
    pick = rng.random((n, 2)) < 0.4
    X[:, 3:][pick] = rng.choice(MODE_EDGES, size=int(pick.sum()))
    rows: FloatArray = np.clip(X, xl, xu)
    return rows


def _run(name: str, index: int, seed: int) -> ParetoResult:
    """Optimiser ``name`` (the config's budget, and population where it has one) on a fresh
    problem of recorded instant ``index``, generator seeded ``seed``."""
    control = recorded_instants()[index][1].control
    options = {"pop_size": control.pop_size} if name in POPULATION_BASED else {}
    problem = recorded_problem(index)
    return make_optimizer(name, **options).minimize(
        problem, budget=control.budget, rng=np.random.default_rng(seed)
    )


def _feasible(result: ParetoResult) -> FloatArray:
    F: FloatArray = result.F[result.feasible]
    return F


def union_costs(union: FloatArray, threshold: float) -> FloatArray:
    """Eq. 19's cost of every row of ``union`` (:func:`~hcomc.equations.selection.eq19_costs`),
    the rows outside the gate, when some pass it, at 2 plus their U_safe min-max normalised
    over them (:class:`Quality`)."""
    costs = eq19_costs(union, OBJECTIVES, safety_threshold=threshold)
    above = ~np.isfinite(costs)
    if above.any() and not above.all():
        safety = union[above, OBJECTIVES.index("safety")]
        span = np.ptp(safety)
        costs[above] = 2.0 + ((safety - safety.min()) / span if span > 0.0 else 0.0)
    return costs


def compare_quality(
    compiled: str,
    library: str,
    indices: Sequence[int],
    seeds: Sequence[int],
    library_seeds: Sequence[int] | None = None,
) -> Quality:
    """:class:`Quality` of optimiser ``compiled`` against ``library`` on the recorded instants
    ``indices``, one pair of runs per seed (the library's run seeded ``library_seeds`` instead,
    when given: unpaired runs, which share no draws, to measure how far the comparison moves
    between runs that have gone their own ways)."""
    pairs = []
    spreads = []
    for index in indices:
        threshold = recorded_problem(index).safety.threshold
        runs = [
            F
            for s, t in zip(seeds, library_seeds or seeds, strict=True)
            for F in (_feasible(_run(compiled, index, s)), _feasible(_run(library, index, t)))
        ]  # compiled, library, compiled, library, ...
        union = np.vstack(runs)
        assert union.shape[0] > 0, f"no feasible row on recorded instant {index}"
        lo, span = union.min(axis=0), np.ptp(union, axis=0)
        span[span == 0.0] = 1.0
        hv = HV(ref_point=np.full(union.shape[1], 1.1))
        costs, gate = (
            union_costs(union, threshold),
            eq19_costs(union, OBJECTIVES, safety_threshold=threshold),
        )
        ends = list(itertools.pairwise(np.cumsum([0] + [F.shape[0] for F in runs])))
        best = [float(costs[a:b].min()) if b > a else np.inf for a, b in ends]
        run_costs = [gate[a:b][np.isfinite(gate[a:b])] for a, b in ends]  # the spreads' rows
        volumes = [float(hv((F - lo) / span)) if F.shape[0] else 0.0 for F in runs]
        for k, seed in enumerate(seeds):
            i, j = 2 * k, 2 * k + 1  # the pair's compiled and library runs
            pairs.append((index, seed, volumes[i], volumes[j], best[i], best[j]))
        spreads += [float(np.ptp(c)) if c.size else 0.0 for c in run_costs[1::2]]
    hv_ours, hv_lib = np.array([p[2] for p in pairs]), np.array([p[3] for p in pairs])
    assert (hv_lib > 0.0).all(), "the library returned no feasible row on some run"
    gaps = np.array([p[4] - p[5] for p in pairs])
    return Quality(
        hv_ratio=float(np.mean(hv_ours / hv_lib)),
        cost_gap=float(np.mean(gaps)),
        cost_spread=float(np.mean(spreads)),
        pairs=tuple(pairs),
    )


QUALITY_INSTANTS = (0, 1, 2, 3, 4)
"""Recorded instants of the quality comparisons: the first of each condition, C1-C5."""
QUALITY_SEEDS = tuple(range(8))
"""Generator seeds of the quality comparisons: eight pairs of runs per instant."""
MIN_HV_RATIO = 0.95
"""The compiled optimiser's mean hypervolume ratio to its library's is at least this."""
MAX_COST_GAP = 0.10
"""The compiled optimiser's mean best Eq. 19 cost exceeds its library's by at most this share
of the library's spread (:class:`Quality`)."""


def assert_quality_matches(compiled: str, library: str) -> Quality:
    """Optimiser ``compiled`` against ``library`` (:func:`compare_quality`) on
    :data:`QUALITY_INSTANTS` with :data:`QUALITY_SEEDS`: mean hypervolume ratio at least
    :data:`MIN_HV_RATIO`, mean best Eq. 19 cost at most :data:`MAX_COST_GAP` of the library's
    spread above the library's. Returns the comparison."""
    quality = compare_quality(compiled, library, QUALITY_INSTANTS, QUALITY_SEEDS)
    summary = (
        f"{compiled} vs {library}: mean HV ratio {quality.hv_ratio:.4f}, mean best Eq. 19 cost "
        f"gap {quality.cost_gap:+.4f} (library's spread {quality.cost_spread:.4f})"
    )
    assert quality.hv_ratio >= MIN_HV_RATIO, summary
    assert quality.cost_gap <= MAX_COST_GAP * quality.cost_spread, summary
    return quality
