"""Optimisation interfaces: a vectorised Problem, the ParetoResult, and the Optimizer protocol.

A problem evaluates a whole population in one call: ``evaluate(X)`` with ``X`` of shape
``(n, n_var)`` returns objectives ``F`` ``(n, n_obj)`` (all minimised) and inequality
constraints ``G`` ``(n, n_constr)``, feasible where ``G <= 0`` (pymoo's convention).
Single-objective optimisers (PSO, SA) search on ``problem.scalarise(F, G)`` instead.

Every optimiser returns the same kind of set, so that a caller's selection rule (the HCOMC
controller's Eq. 19, paper Section III-C-2) is applied alike to all of them and a comparison of
optimisers (paper Section IV, Table II) compares their searches, not their selection rules: the
feasible, mutually non-dominated subset of every row it evaluated (:func:`archive_front`),
kept in an :class:`Archive` allocated once for the budget.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.optim.dominance import feasible_front


@runtime_checkable
class Problem(Protocol):
    """A box-bounded, vectorised, constrained multi-objective minimisation problem."""

    n_var: int
    n_obj: int
    n_constr: int
    xl: FloatArray
    xu: FloatArray
    objective_names: tuple[str, ...]

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Objectives ``F`` (n, n_obj) and constraints ``G`` (n, n_constr) of rows ``X``."""
        ...

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        """One cost per row (n,) for single-objective optimisers, penalising violations."""
        ...


@runtime_checkable
class RowProblem(Protocol):
    """A :class:`Problem` that also scores one row at a time without population overhead.

    Simulated annealing asks for one row per call; a problem whose :meth:`Problem.evaluate`
    carries per-call population machinery (index arrays, gathers, per-population set-up)
    may offer this fast path. It must return exactly what ``evaluate(x[None])`` and
    ``scalarise`` give, bit for bit (a NaN's sign and payload aside: IEEE 754 leaves them
    open, and no optimiser observes them): optimisers use it only as a faster route to the
    same decisions, and fall back to ``evaluate`` + ``scalarise`` for problems without it.
    """

    def evaluate_row(self, x: FloatArray, F: FloatArray, G: FloatArray) -> float:
        """Objectives of row ``x`` (n_var,) into ``F`` (n_obj,), its constraints into ``G``
        (n_constr,) (contiguous float64 buffers), and its scalarised cost returned."""
        ...


@runtime_checkable
class CanonicalProblem(Protocol):
    """A :class:`Problem` whose values depend on fewer distinctions than its rows make (a
    variable read only through a threshold, say). It maps rows to canonical rows such that
    rows with equal canonical rows have equal objectives and constraints, bit for bit, and
    an optimiser that keeps the rows it evaluated evaluates one of them
    (:class:`hcomc.optim.evaluated.EvaluatedRows`): the same decisions, fewer evaluations.
    """

    def canonical_rows(self, X: FloatArray) -> FloatArray:
        """The canonical row (n_var,) of each row of ``X`` (n, n_var)."""
        ...


@dataclass(frozen=True, slots=True)
class ParetoResult:
    """What an optimiser returns.

    Attributes
    ----------
    X : (p, n_var) decision vectors of the returned set: the feasible, mutually non-dominated
        subset of every row the optimiser evaluated (:func:`archive_front`: one per distinct
        objective vector, in evaluation order), whether it searched on the objectives
        (NSGA-II) or on a scalarisation of them (PSO, SA); if no evaluated row is feasible,
        one row: NSGA-II's least-violating row, PSO's and SA's best-scalarised row.
    F : (p, n_obj) their objectives.
    G : (p, n_constr) their constraints.
    feasible : (p,) whether each returned solution satisfies every constraint.
    n_eval : number of problem evaluations (rows) spent.
    algorithm : name of the optimiser.
    """

    X: FloatArray
    F: FloatArray
    G: FloatArray
    feasible: BoolArray
    n_eval: int
    algorithm: str

    @property
    def any_feasible(self) -> bool:
        """Whether at least one returned solution is feasible."""
        return bool(np.any(self.feasible))


class Optimizer(Protocol):
    """Minimises a :class:`Problem` within an evaluation budget, deterministically per ``rng``."""

    @property
    def name(self) -> str:
        """Registry name of the optimiser (``"nsga2"``, ``"pso"``, ``"sa"``)."""
        ...

    def minimize(
        self,
        problem: Problem,
        *,
        budget: int,
        rng: np.random.Generator,
        initial: FloatArray | None = None,
    ) -> ParetoResult:
        """Optimise ``problem`` using at most about ``budget`` row evaluations.

        ``initial`` (k, n_var): decision vectors to start from (a warm start, e.g. the previous
        Pareto set of a replanned decision), clipped to the bounds; the rest of the first
        population is sampled as usual.
        """
        ...


class Archive:
    """Every row an optimiser evaluates, in evaluation order, and the best-scalarised one.

    The arrays hold ``capacity`` rows (the budget), allocated once, so that keeping a row is a
    copy into place (or, for a row-at-a-time optimiser, scoring straight into its row:
    :meth:`keep`); a library optimiser that evaluates more rows than planned grows them.
    The best-scalarised row is tracked by index: a NaN cost ranks as +inf, a row replaces
    the best only when strictly better (so the first of equals stays), and the first row
    offered always sets it (even at +inf).

    Attributes
    ----------
    X, F, G : (capacity, n_var / n_obj / n_constr) the rows; the first :attr:`size` are kept.
    size : rows kept.
    best : index of the best-scalarised row (-1 before any).
    """

    def __init__(self, capacity: int, n_var: int, n_obj: int, n_constr: int) -> None:
        rows = max(1, int(capacity))
        self.X = np.empty((rows, int(n_var)))
        self.F = np.empty((rows, int(n_obj)))
        self.G = np.empty((rows, int(n_constr)))
        self.size = 0
        self.best = -1
        self.best_cost = math.inf

    def add(
        self, X: FloatArray, F: FloatArray, G: FloatArray, cost: FloatArray | None = None
    ) -> None:
        """Rows ``X``, ``F``, ``G`` (n, ...) kept; with their scalarised costs (n,), the first
        of the lowest is offered as the best."""
        n = X.shape[0]
        rows = slice(self._reserve(n), self.size)
        self.X[rows], self.F[rows], self.G[rows] = X, F, G
        if cost is not None:
            k = int(np.argmin(np.where(np.isnan(cost), np.inf, cost)))
            self.offer(rows.start + k, float(cost[k]))

    def keep(self, k: int, cost: float) -> None:
        """Row ``k == size`` (within the capacity), which the caller wrote in place into
        ``X[k]``, ``F[k]`` and ``G[k]`` (row views are contiguous: a row-at-a-time optimiser
        scores straight into them), is kept, and its scalarised cost offered."""
        self.size = k + 1
        if self.best < 0 or cost < self.best_cost:  # SA keeps every row: no call otherwise
            self.offer(k, cost)

    def offer(self, k: int, cost: float) -> None:
        """Row ``k``'s scalarised cost: it becomes the best if strictly lower."""
        if self.best >= 0 and not cost < self.best_cost:  # NaN never compares lower
            return
        self.best = k
        self.best_cost = math.inf if math.isnan(cost) else cost

    def _reserve(self, n: int) -> int:
        start = self.size
        if start + n > self.X.shape[0]:
            rows = max(start + n, 2 * self.X.shape[0])
            self.X, self.F, self.G = (
                np.concatenate([a, np.empty((rows - a.shape[0], a.shape[1]))])
                for a in (self.X, self.F, self.G)
            )
        self.size = start + n
        return start

    def result(self, n_eval: int, algorithm: str) -> ParetoResult:
        """The returned set: :func:`archive_front` of the kept rows, or, when none of them
        is feasible, the best-scalarised row alone (``feasible`` False)."""
        n = self.size
        keep = archive_front(self.F[:n], self.G[:n])
        if keep.size == 0:
            assert self.best >= 0  # every row evaluated was offered with its cost
            keep = np.array([self.best])
        X, F, G = self.X[keep], self.F[keep], self.G[keep]
        return ParetoResult(X, F, G, np.all(G <= 0.0, axis=1), n_eval, algorithm)


def check_budget(budget: int) -> None:
    """Raise unless ``budget`` allows at least one row evaluation."""
    if budget < 1:
        raise ValueError(f"budget must be >= 1 row evaluation, got {budget}")


def generations(budget: int, pop_size: int) -> int:
    """Generations of ``pop_size`` rows a population-based optimiser runs on a budget of
    ``budget`` row evaluations: ``max(1, budget // pop_size)`` (at least the first)."""
    return max(1, budget // pop_size)


def check_pop_size(pop_size: int) -> None:
    """Raise unless a population has at least two members."""
    if pop_size < 2:
        raise ValueError(f"pop_size must be >= 2, got {pop_size}")


def initial_rows(
    problem: Problem, initial: FloatArray | None, size: int, rng: np.random.Generator
) -> FloatArray | None:
    """A first population of ``size`` rows: ``initial`` (clipped, at most ``size``) topped up
    with uniform samples in the bounds; None when there is no warm start."""
    if initial is None or len(initial) == 0:
        return None
    xl, xu = np.asarray(problem.xl, dtype=np.float64), np.asarray(problem.xu, dtype=np.float64)
    seeds = np.clip(np.atleast_2d(np.asarray(initial, dtype=np.float64))[:size], xl, xu)
    rest = xl + rng.random((size - seeds.shape[0], xl.size)) * (xu - xl)
    return np.vstack([seeds, rest])


def archive_front(F: FloatArray, G: FloatArray) -> IntArray:
    """Rows of the feasible (``G <= 0``), mutually non-dominated subset of evaluated rows, one
    per distinct objective vector (the first evaluated), in evaluation order; empty if none is
    feasible. The set a multi-objective optimiser returns from its archive of evaluations
    (duplicates carry no information); one compiled pass,
    :func:`hcomc.optim.dominance.feasible_front`."""
    F = np.ascontiguousarray(F, dtype=np.float64)
    G = np.ascontiguousarray(G, dtype=np.float64)
    rows: IntArray = feasible_front(F, G)
    return rows
