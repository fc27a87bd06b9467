"""A lean NSGA-II on arrays that makes pymoo's decisions, without pymoo's per-individual objects.

:class:`CompiledNSGA2Optimizer` runs the algorithm of :class:`~hcomc.optim.pymoo_backend.
NSGA2Optimizer` (pymoo 0.6's ``NSGA2`` with SBX, polynomial mutation, binary tournament by
constraint violation, domination and crowding, rank-and-crowding survival with feasible rows
first, no duplicate elimination) on plain arrays: non-dominated ranks, crowding distance and the
tournaments are numba kernels (:mod:`hcomc.optim.dominance`), and so are SBX and polynomial
mutation (:mod:`hcomc.optim.variation`, powers through numpy as pymoo computes them). It draws
the same random numbers in the same order from a generator seeded like pymoo's, and computes
every floating-point value with the same operations, so for the same problem, budget and ``rng``
it evaluates the same rows and returns the same Pareto set as the pymoo optimiser (tests hold it
to that), at a fraction of the per-generation cost.

Budget, seeding, warm start and the returned set are those of the pymoo optimiser:
``n_gen = max(1, budget // pop_size)`` generations of ``pop_size`` rows; one integer seed
(:func:`hcomc.rng.draw_seed`) drawn from the caller's generator after the warm-start rows;
the feasible, mutually non-dominated subset of every evaluated row (one per distinct objective
vector), or the least-violating row of the final population when nothing is feasible.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.optim import dominance, variation
from hcomc.optim.base import (
    ParetoResult,
    Problem,
    archive_front,
    check_budget,
    check_pop_size,
    initial_rows,
)
from hcomc.optim.dominance import ranked_fronts, tournament
from hcomc.optim.variation import polynomial_mutation, sbx
from hcomc.rng import draw_seed


def violation(G: FloatArray) -> FloatArray:
    """Constraint violation per row, ``sum(max(0, G))`` (0: feasible)."""
    if G.shape[1] == 0:
        return np.zeros(G.shape[0])
    return np.maximum(0.0, G).sum(axis=1)


@dataclass(slots=True)
class Population:
    """Survivors of a generation, best first, with rank and crowding for the tournament."""

    X: FloatArray
    F: FloatArray
    cv: FloatArray
    rank: IntArray
    crowding: FloatArray
    row: IntArray  # index of each survivor among all evaluated rows

    def take(self, idx: IntArray) -> Population:
        """The rows ``idx``, in that order."""
        return Population(
            self.X[idx], self.F[idx], self.cv[idx], self.rank[idx], self.crowding[idx],
            self.row[idx],
        )  # fmt: skip

    @staticmethod
    def merge(a: Population, b: Population) -> Population:
        """``a``'s rows then ``b``'s."""
        return Population(
            np.vstack([a.X, b.X]), np.vstack([a.F, b.F]), np.concatenate([a.cv, b.cv]),
            np.concatenate([a.rank, b.rank]), np.concatenate([a.crowding, b.crowding]),
            np.concatenate([a.row, b.row]),
        )  # fmt: skip


def survive(pop: Population, n_survive: int, rng: np.random.Generator) -> Population:
    """Rank-and-crowding survival with feasible rows first (pymoo's ``RankAndCrowding``).

    Feasible rows are taken front by front (rows of a front in index order); the front that
    does not fit is cut by crowding distance, largest first, ties broken by a random
    permutation. The remaining places go to infeasible rows by increasing violation.
    """
    X, F, cv = pop.X, pop.F, pop.cv
    n_survive = min(n_survive, X.shape[0])
    feasible = cv <= 0.0
    feas = np.flatnonzero(feasible)
    infeas = np.flatnonzero(~feasible)
    infeas = infeas[np.argsort(cv[infeas])]
    rank = np.full(X.shape[0], -1, dtype=np.int64)
    crowd = np.full(X.shape[0], np.nan)
    idx = infeas[:n_survive]
    n_feasible = min(feas.size, n_survive)
    if n_feasible > 0:
        ranks, d, last = ranked_fronts(F[feas].astype(np.float64), n_feasible)
        rank[feas], crowd[feas] = ranks, d
        inner = np.flatnonzero(ranks < last)  # whole fronts, front by front, in index order
        inner = inner[np.argsort(ranks[inner], kind="stable")]
        front = np.flatnonzero(ranks == last)
        n_remove = inner.size + front.size - n_feasible
        if n_remove > 0:  # the front that does not fit: largest crowding first
            perm = rng.permutation(front.size)
            front = front[np.flip(perm[np.argsort(d[front][perm], kind="quicksort")])[:-n_remove]]
        idx = np.concatenate([feas[inner], feas[front], infeas[: n_survive - n_feasible]])
    return Population(X, F, cv, rank, crowd, pop.row).take(idx)


def select_parents(pop: Population, n_matings: int, rng: np.random.Generator) -> IntArray:
    """(n_matings, 2) parent rows by binary tournament (pymoo's ``TournamentSelection``)."""
    n = pop.X.shape[0]
    n_random = n_matings * 2 * 2
    n_perms = -(-n_random // n)
    P = np.concatenate([rng.permutation(n) for _ in range(n_perms)])[:n_random]
    P = P.reshape(n_matings * 2, 2)
    S = tournament(P, pop.F, pop.cv, pop.crowding)
    for i in np.flatnonzero(S < 0):
        # a fair coin, the draw pymoo's ``rng.choice([a, b])`` makes (same stream)
        S[i] = P[i, int(rng.integers(0, 2))]
    return S.reshape(n_matings, 2)


@dataclass(frozen=True, slots=True)
class CompiledNSGA2Optimizer:
    """NSGA-II on arrays with numba kernels; the same decisions as the pymoo optimiser.

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
        dominance.warm_up()  # load the compiled kernels now, not inside a timed decision
        variation.warm_up()

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
        n_gen = max(1, budget // self.pop_size)
        xl = np.array(problem.xl, dtype=np.float64, copy=True)
        xu = np.array(problem.xu, dtype=np.float64, copy=True)
        n_var, n_obj, n_constr = int(problem.n_var), int(problem.n_obj), int(problem.n_constr)
        first = initial_rows(problem, initial, self.pop_size, rng)
        gen = np.random.default_rng(draw_seed(rng))
        if first is None:
            first = xl + (xu - xl) * gen.random((self.pop_size, n_var))
        archive: list[tuple[FloatArray, FloatArray, FloatArray]] = []

        def evaluate(X: FloatArray) -> Population:
            F, G = problem.evaluate(X)
            n = X.shape[0]
            F = np.asarray(F, dtype=np.float64).reshape(n, n_obj)
            G = np.asarray(G, dtype=np.float64).reshape(n, n_constr)
            start = sum(part[0].shape[0] for part in archive)
            archive.append((X, F, G))
            rank, crowding = np.full(n, -1, dtype=np.int64), np.full(n, np.nan)
            return Population(X, F, violation(G), rank, crowding, np.arange(start, start + n))

        pop = survive(evaluate(first), first.shape[0], gen)
        n_matings = -(-self.pop_size // 2)
        for _ in range(n_gen - 1):
            parents = select_parents(pop, n_matings, gen)
            children = sbx(
                np.swapaxes(pop.X[parents], 0, 1), xl, xu, self.crossover_eta,
                self.crossover_prob, gen,
            )  # fmt: skip
            mutated = polynomial_mutation(
                children, xl, xu, self.mutation_eta, self.mutation_prob, gen
            )
            pop = survive(Population.merge(pop, evaluate(mutated[: self.pop_size])),
                          self.pop_size, gen)  # fmt: skip
        X, F, G = (np.concatenate(part) for part in zip(*archive, strict=True))
        keep = archive_front(F, G)
        feasible: BoolArray = np.ones(keep.size, dtype=bool)
        if keep.size == 0:
            # the least-violating row of the final population (the first of equals)
            keep = pop.row[[int(np.argmin(pop.cv))]]
            feasible = np.zeros(1, dtype=bool)
        return ParetoResult(X[keep], F[keep], G[keep], feasible, X.shape[0], self.name)
