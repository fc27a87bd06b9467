"""Optimisation interfaces: a vectorised Problem, the ParetoResult, and the Optimizer protocol.

A problem evaluates a whole population in one call: ``evaluate(X)`` with ``X`` of shape
``(n, n_var)`` returns objectives ``F`` ``(n, n_obj)`` (all minimised) and inequality
constraints ``G`` ``(n, n_constr)``, feasible where ``G <= 0`` (pymoo's convention).
Single-objective optimisers (PSO, SA) minimise ``problem.scalarise(F, G)`` instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable
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


@dataclass(frozen=True, slots=True)
class ParetoResult:
    """What an optimiser returns.

    Attributes
    ----------
    X : (p, n_var) decision vectors of the returned set: the feasible non-dominated solutions
        for a multi-objective optimiser, the best solution for a single-objective one; if no
        evaluated solution is feasible, the least-violating one(s).
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


class BestRow:
    """The best-scalarised row a single-objective optimiser (PSO, SA) has evaluated, kept with
    its true objectives and constraints.

    A NaN cost ranks as +inf; a row replaces the best only when strictly better, so the first
    of equals stays; the first row offered always sets it (even at +inf).
    """

    def __init__(self) -> None:
        self.cost = np.inf
        self.row: tuple[FloatArray, FloatArray, FloatArray] | None = None

    def offer(self, X: FloatArray, F: FloatArray, G: FloatArray, cost: FloatArray) -> None:
        """Rows ``X``, ``F``, ``G`` (n, ...) with their costs (n,): the first of the lowest
        may become the best."""
        ranked = np.where(np.isnan(cost), np.inf, cost)
        k = int(np.argmin(ranked))
        self.offer_one(float(cost[k]), lambda: (X[k], F[k], G[k]))

    def offer_one(self, cost: float, row: Callable[[], tuple[FloatArray, ...]]) -> None:
        """One row's cost; ``row()`` gives its x, F and G, called (and copied) only when the
        row becomes the best: most rows are not kept."""
        if self.row is not None and not cost < self.cost:  # NaN never compares lower
            return  # the common case, decided by one comparison (SA offers every row)
        self.cost = math.inf if math.isnan(cost) else cost
        x, f, g = (np.array(a, dtype=np.float64, copy=True) for a in row())
        self.row = (x, f, g)

    def result(self, n_eval: int, algorithm: str) -> ParetoResult:
        """The best row as a one-row :class:`ParetoResult`."""
        assert self.row is not None  # every optimiser evaluates at least one row
        x, f, g = self.row
        G = g[None, :]
        return ParetoResult(x[None, :], f[None, :], G, np.all(G <= 0.0, axis=1), n_eval, algorithm)


def check_budget(budget: int) -> None:
    """Raise unless ``budget`` allows at least one row evaluation."""
    if budget < 1:
        raise ValueError(f"budget must be >= 1 row evaluation, got {budget}")


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
