"""A lean NSGA-II on arrays: pymoo's algorithm, without pymoo's per-individual objects.

:class:`CompiledNSGA2Optimizer` runs the algorithm of :class:`~hcomc.optim.pymoo_backend.
NSGA2Optimizer` (pymoo 0.6's ``NSGA2`` with SBX, polynomial mutation, binary tournament by
constraint violation, domination and crowding, rank-and-crowding survival with feasible rows first,
no duplicate elimination) on plain arrays. A generation costs a handful of compiled calls: survival
(:func:`hcomc.optim.dominance.survival_fronts`), the rest of survival with the tournaments
(:func:`hcomc.optim.dominance.survive_and_select`), and crossover with mutation
(:func:`hcomc.optim.variation.offspring`, its draws included), with survival's and the tournaments'
draws made in Python in between: all the same numbers in the same order as pymoo's, from a generator
seeded like pymoo's. Numpy is left the two sorts whose order of ties is numpy's own. The formulas
are pymoo's, but the powers are the C library's (:mod:`hcomc.optim.variation`) and the constraint
violation a plain sum (:func:`hcomc.optim.evaluated.violation`), never numpy's CPU-dispatched
functions, so that a run is the same on every processor; where numpy's functions differ from the C
library's, a run can part from pymoo's in the last bit and go its own way. The tests hold it to
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

from dataclasses import dataclass, field

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.optim import dominance, evaluated, variation
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
from hcomc.optim.variation import offspring
from hcomc.rng import draw_seed

_NONE = np.empty(0, dtype=np.int64)  # no permutation or sort (read only by the kernels)
_NO_PAIRS = np.empty((0, 2), dtype=np.int64)  # no tournament


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
    ``TournamentSelection``), drawing from ``rng`` as pymoo does.

    Survival: feasible rows are taken front by front (rows of a front in position order); the
    front that does not fit is cut by crowding distance, largest first, ties broken by a random
    permutation. The remaining places go to infeasible rows by increasing violation.
    Selection: pairs of survivors from concatenated random permutations compete as
    :func:`hcomc.optim.dominance.tournament` decides; a tie is a fair coin.

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
    n_inner, n_front, n_remove, n_infeasible = counts.tolist()
    perm, by_crowding, by_violation, P = _NONE, _NONE, _NONE, _NO_PAIRS
    # Ties are ordered stably: numpy's default sort orders equal keys by the CPU's (its
    # AVX-512 sort differs from its portable one), so the survivors would depend on the machine
    if n_remove > 0:  # the front that does not fit: sorted from a random permutation
        perm = rng.permutation(n_front)
        by_crowding = key[n_inner : n_inner + n_front][perm].argsort(kind="stable")
    if n_infeasible > 0:
        by_violation = key[n_inner + n_front :].argsort(kind="stable")
    if n_matings > 0:
        n = min(n_survive, rows.size)
        n_random = n_matings * 2 * 2
        n_perms = -(-n_random // n)
        P = np.concatenate([rng.permutation(n) for _ in range(n_perms)])[:n_random]
        P = P.reshape(n_matings * 2, 2)
    idx, S, ties = survive_and_select(
        F, cv, rows, crowding, order, counts, perm, by_crowding, by_violation, P
    )
    for i in ties.tolist():
        # a fair coin, the draw pymoo's ``rng.choice([a, b])`` makes (same stream)
        S[i] = P[i, int(rng.integers(0, 2))]
    return idx, S.reshape(n_matings, 2), rank, crowding


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
        dominance.warm_up()  # load the compiled kernels now, not inside a timed decision
        variation.warm_up()
        evaluated.warm_up()

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
        crossover = (self.crossover_eta, self.crossover_prob)
        mutation = (self.mutation_eta, self.mutation_prob)
        n_matings = -(-self.pop_size // 2)
        rows = archive.add(first)
        X_all, F_all, G_all, cv_all = archive.X, archive.F, archive.G, archive.cv
        for g in range(n_gen):
            mate = n_matings if g < n_gen - 1 else 0  # the last survivors do not mate
            idx, parents, _, _ = survive_and_mate(F_all, cv_all, rows, self.pop_size, mate, gen)
            rows = rows[idx]
            if mate:
                children = offspring(X_all[rows[parents].T], xl, xu, crossover, mutation, gen)
                rows = np.concatenate([rows, archive.add(children[: self.pop_size])])
        keep = archive_front(F_all, G_all)
        feasible: BoolArray = np.ones(keep.size, dtype=bool)
        if keep.size == 0:
            # the least-violating row of the final population (the first of equals)
            keep = rows[[int(np.argmin(cv_all[rows]))]]
            feasible = np.zeros(1, dtype=bool)
        return ParetoResult(X_all[keep], F_all[keep], G_all[keep], feasible, archive.size,
                            self.name)  # fmt: skip
