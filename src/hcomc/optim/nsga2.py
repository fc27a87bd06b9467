"""A lean NSGA-II on arrays: pymoo's algorithm, without pymoo's per-individual objects.

:class:`CompiledNSGA2Optimizer` runs the algorithm of :class:`~hcomc.optim.pymoo_backend.
NSGA2Optimizer` (pymoo 0.6's ``NSGA2`` with SBX, polynomial mutation, binary tournament by
constraint violation, domination and crowding, rank-and-crowding survival with feasible rows first,
no duplicate elimination) on plain arrays. Between two evaluations a generation is one compiled
call (:func:`next_generation`): rank-and-crowding survival (:func:`hcomc.optim.dominance.
survival_fronts`, :func:`hcomc.optim.dominance.survive_and_select`), the tournaments and
crossover with mutation (:func:`hcomc.optim.variation.drawn_offspring`), their draws made by
numba's ``Generator`` methods, which draw what numpy's draw from the same state: all the same
numbers in the same order as pymoo's, from a generator seeded like pymoo's. Its sorts are stable,
so that ties keep one order on every machine. The formulas are pymoo's, but the powers are the C
library's (:mod:`hcomc.optim.variation`) and the constraint violation a plain sum
(:func:`hcomc.optim.evaluated.violation`), never numpy's CPU-dispatched functions, so that a run
is the same on every processor; where numpy's functions differ from the C library's, a run can
part from pymoo's in the last bit and go its own way. The tests hold it to
pymoo's solution quality on the recorded merge problems (``tests/unit/test_nsga2_compiled.py``).
Evaluated rows go into one preallocated archive (:class:`hcomc.optim.evaluated.EvaluatedRows`), from
which the Pareto set is taken in one compiled pass (:func:`hcomc.optim.base.archive_front`); a row
equal to one the run evaluated before takes that row's values instead of a second evaluation (the
same numbers), and still counts in the budget and in ``n_eval``, as in pymoo without duplicate
elimination.

Budget, seeding, warm start and the returned set are those of the pymoo optimiser:
``n_gen = max(1, budget // pop_size)`` generations of ``pop_size`` rows; one integer seed
(:func:`hcomc.rng.draw_seed`) drawn from the caller's generator after the warm-start rows;
the feasible, mutually non-dominated subset of every evaluated row (one per distinct objective
vector), or the least-violating row of the final population when nothing is feasible.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.optim import dominance, evaluated
from hcomc.optim.base import (
    ParetoResult,
    Problem,
    archive_front,
    check_budget,
    check_pop_size,
    generations,
    initial_rows,
)
from hcomc.optim.dominance import survival_fronts, survive_and_select
from hcomc.optim.evaluated import EvaluatedRows
from hcomc.optim.variation import Bounds, drawn_offspring
from hcomc.rng import draw_seed


@kernel
def survive_and_mate(
    F: FloatArray,
    cv: FloatArray,
    rows: IntArray,
    n_survive: int,
    n_matings: int,
    rng: np.random.Generator,
) -> tuple[IntArray, IntArray, IntArray, FloatArray]:
    """Rank-and-crowding survival with feasible rows first (pymoo's ``RankAndCrowding``), then
    ``n_matings`` pairs of parents by binary tournament among the survivors (pymoo's
    ``TournamentSelection``), drawing from ``rng`` what pymoo draws, in its order.

    Survival: feasible rows are taken front by front (rows of a front in position order); the
    front that does not fit is cut by crowding distance, largest first, ties broken by a random
    permutation. The remaining places go to infeasible rows by increasing violation.
    Selection: pairs of survivors from concatenated random permutations compete as
    :func:`hcomc.optim.dominance.tournament` decides; a tie is a fair coin. numba's
    ``Generator`` methods draw the numbers numpy's draw from the same state.

    Parameters
    ----------
    F, cv : objectives and violation of every evaluated row.
    rows : the population, rows of ``F`` and ``cv``.

    Returns
    -------
    The survivors (positions in ``rows``, best first), the parents (n_matings, 2) as positions
    among the survivors, and the rank and crowding distance of every position of ``rows``
    (-1 and NaN where not computed).
    """
    order, key, rank, crowding, counts = survival_fronts(F, cv, rows, n_survive)
    n_inner, n_front, n_remove, n_infeasible = counts[0], counts[1], counts[2], counts[3]
    none = np.empty(0, dtype=np.int64)
    perm, by_crowding, by_violation = none, none, none  # no permutation, no sort
    # Ties are ordered stably: numpy's default sort orders equal keys by the CPU's (its
    # AVX-512 sort differs from its portable one), so the survivors would depend on the machine
    if n_remove > 0:  # the front that does not fit: sorted from a random permutation
        perm = rng.permutation(n_front)
        by_crowding = np.argsort(key[n_inner : n_inner + n_front][perm], kind="mergesort")
    if n_infeasible > 0:
        by_violation = np.argsort(key[n_inner + n_front :], kind="mergesort")
    P = np.empty((2 * n_matings, 2), dtype=np.int64)
    pairs = P.reshape(4 * n_matings)
    n = min(n_survive, rows.size)
    if n == 0 and pairs.size > 0:
        raise ValueError("no survivors to mate")
    taken = 0
    while taken < pairs.size:  # concatenated permutations of the survivors, cut to size
        drawn = rng.permutation(n)
        m = min(n, pairs.size - taken)
        pairs[taken : taken + m] = drawn[:m]
        taken += m
    idx, S, ties = survive_and_select(
        F, cv, rows, crowding, order, counts, perm, by_crowding, by_violation, P
    )
    for i in ties:
        # a fair coin, the draw pymoo's ``rng.choice([a, b])`` makes (same stream)
        S[i] = P[i, rng.integers(0, 2)]
    return idx, S.reshape(n_matings, 2), rank, crowding


@kernel
def next_generation(
    X: FloatArray, F: FloatArray, cv: FloatArray, rows: IntArray, pop_size: int,
    n_matings: int, bounds: Bounds, crossover: tuple[float, float],
    mutation: tuple[float, float], rng: np.random.Generator,
) -> tuple[IntArray, FloatArray]:  # fmt: skip
    """One generation's steps between two evaluations, in one compiled call: the survivors of
    the population ``rows`` of the archive ``X``, ``F``, ``cv`` (:func:`survive_and_mate`, as
    rows of the archive, best first) and the offspring (2 ``n_matings``, n_var) of their
    ``n_matings`` tournaments (:func:`hcomc.optim.variation.drawn_offspring`; none when 0);
    ``crossover`` and ``mutation`` are (eta, probability)."""
    idx, parents, _, _ = survive_and_mate(F, cv, rows, pop_size, n_matings, rng)
    survivors = rows[idx]
    if n_matings == 0:
        return survivors, np.empty((0, X.shape[1]))
    mates = np.empty((2, n_matings, X.shape[1]))
    for i in range(n_matings):
        mates[0, i] = X[survivors[parents[i, 0]]]
        mates[1, i] = X[survivors[parents[i, 1]]]
    children = drawn_offspring(mates, bounds, crossover[0], crossover[1], mutation[0],
                               mutation[1], rng)  # fmt: skip
    return survivors, children


class Generations(NamedTuple):
    """A run's generations, as :func:`run_generations` takes them: ``n_gen`` generations of
    ``pop_size`` rows, ``n_matings`` tournaments a generation (none after the last), the
    variables' ``bounds``, and the operators' (eta, probability): ``crossover`` and
    ``mutation``."""

    n_gen: int
    pop_size: int
    n_matings: int
    bounds: Bounds
    crossover: tuple[float, float]
    mutation: tuple[float, float]


@runtime_checkable
class CompiledGenerations(Protocol):
    """A problem that runs NSGA-II's generations on itself in compiled code: the same rows,
    values and draws as :func:`run_generations` (with its ``evaluate`` and canonical rows),
    bit for bit, without returning to Python between generations."""

    def nsga2_generations(
        self, archive: EvaluatedRows, first: FloatArray, plan: Generations,
        rng: np.random.Generator,
    ) -> IntArray:  # fmt: skip
        """:func:`run_generations` on this problem."""
        ...


def run_generations(
    archive: EvaluatedRows, first: FloatArray, plan: Generations, rng: np.random.Generator
) -> IntArray:
    """NSGA-II's generations from the first population ``first``: its rows evaluated into
    ``archive``, then ``plan.n_gen`` times the survivors of the population, whose offspring
    (the first ``pop_size``; none after the last generation) are evaluated and join them
    (:func:`next_generation`). Returns the final population's rows of the archive."""
    rows = archive.add(first)
    X, F, cv = archive.X, archive.F, archive.cv
    for g in range(plan.n_gen):
        mate = plan.n_matings if g < plan.n_gen - 1 else 0  # the last survivors do not mate
        rows, children = next_generation(X, F, cv, rows, plan.pop_size, mate, plan.bounds,
                                         plan.crossover, plan.mutation, rng)  # fmt: skip
        if mate:
            rows = np.concatenate([rows, archive.add(children[: plan.pop_size])])
    return rows


@dataclass(frozen=True, slots=True)
class CompiledNSGA2Optimizer:
    """NSGA-II on arrays with numba kernels, pymoo's algorithm (see the module).

    Parameters
    ----------
    pop_size : population size (rows per generation).
    crossover_eta, crossover_prob : SBX distribution index and probability.
    mutation_eta : polynomial-mutation distribution index (per-variable probability
        min(0.5, 1/n_var), per-row probability ``mutation_prob``).
    mutation_prob : probability that an offspring row is mutated at all (pymoo's 0.9).
    """

    pop_size: int = 24
    crossover_eta: float = 15.0
    crossover_prob: float = 0.9
    mutation_eta: float = 20.0
    mutation_prob: float = 0.9
    name: str = field(default="nsga2", init=False)

    def __post_init__(self) -> None:
        check_pop_size(self.pop_size)
        warm_up()  # load the compiled kernels now, not inside a timed decision

    def minimize(
        self,
        problem: Problem,
        *,
        budget: int,
        rng: np.random.Generator,
        initial: FloatArray | None = None,
    ) -> ParetoResult:
        """Run ``max(1, budget // pop_size)`` generations and return the non-dominated set."""
        check_budget(budget)
        n_gen = generations(budget, self.pop_size)
        xl = np.array(problem.xl, dtype=np.float64, copy=True)
        xu = np.array(problem.xu, dtype=np.float64, copy=True)
        n_var = int(problem.n_var)
        first = initial_rows(problem, initial, self.pop_size, rng)
        gen = np.random.default_rng(draw_seed(rng))
        if first is None:
            first = xl + (xu - xl) * gen.random((self.pop_size, n_var))
        archive = EvaluatedRows(problem, first.shape[0] + (n_gen - 1) * self.pop_size)
        plan = Generations(
            n_gen, self.pop_size, -(-self.pop_size // 2), Bounds(xl, xu),
            (float(self.crossover_eta), float(self.crossover_prob)),
            (float(self.mutation_eta), float(self.mutation_prob)),
        )  # fmt: skip
        if isinstance(problem, CompiledGenerations):
            rows = problem.nsga2_generations(archive, first, plan, gen)
        else:
            rows = run_generations(archive, first, plan, gen)
        X_all, F_all, G_all, cv_all = archive.X, archive.F, archive.G, archive.cv
        keep = archive_front(F_all, G_all)
        feasible: BoolArray = np.ones(keep.size, dtype=bool)
        if keep.size == 0:
            # the least-violating row of the final population (the first of equals)
            keep = rows[[int(np.argmin(cv_all[rows]))]]
            feasible = np.zeros(1, dtype=bool)
        return ParetoResult(X_all[keep], F_all[keep], G_all[keep], feasible, archive.size,
                            self.name)  # fmt: skip


@functools.cache  # once per process
def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels a run calls: a generation's
    (:func:`next_generation`), the archive's (:mod:`hcomc.optim.evaluated`), the fronts'
    (:mod:`hcomc.optim.dominance`)."""
    dominance.warm_up()
    evaluated.warm_up()
    F, rng = np.array([[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]]), np.random.default_rng(0)
    bounds = Bounds(np.zeros(2), np.ones(2))
    next_generation(F, F, np.zeros(3), np.arange(3), 2, 1, bounds, (15.0, 0.9), (20.0, 0.9), rng)
