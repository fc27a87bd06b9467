"""Test problems on a box, shared by the tests of the optimisers on arrays (PSO, SA):
single-objective ones and a constrained two-objective one, each keeping every batch of rows it
evaluated, so that two runs can be compared call by call; and :class:`Recording`, any problem
wrapped to keep every row it scores with its objectives and constraints, with
:func:`expected_rows`, the set an optimiser must return of those rows."""

from __future__ import annotations

from typing import Any

import numpy as np

from hcomc._typing import FloatArray, IntArray
from hcomc.optim.base import ParetoResult, archive_front


class ScalarProblem:
    """A single-objective problem on the box [xl, xu] that keeps every evaluated batch."""

    n_obj = 1
    n_constr = 0
    objective_names = ("f",)

    def __init__(self, xl: FloatArray, xu: FloatArray) -> None:
        self.n_var = xl.size
        self.xl, self.xu = xl, xu
        self.xl.flags.writeable = False  # an in-place change by an optimiser would raise
        self.xu.flags.writeable = False
        self.evaluated: list[FloatArray] = []

    def f(self, X: FloatArray) -> FloatArray:
        raise NotImplementedError

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        self.evaluated.append(np.array(X, copy=True))
        return self.f(X)[:, None], np.zeros((X.shape[0], 0))

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        return F[:, 0] + 1000.0 * np.maximum(G, 0.0).sum(axis=1)


class Sphere(ScalarProblem):
    """Shifted sphere on [xl, xu]^n, minimum 0 at (1, -2, 0.5, ...) in the default box."""

    def __init__(self, n_var: int, xl: float = -5.0, xu: float = 5.0) -> None:
        super().__init__(np.full(n_var, xl), np.full(n_var, xu))
        self.centre = np.resize([1.0, -2.0, 0.5], n_var)

    def f(self, X: FloatArray) -> FloatArray:
        return ((X - self.centre) ** 2).sum(axis=1)


class Rastrigin(ScalarProblem):
    """Rastrigin on [-5.12, 5.12]^n: many local minima, global minimum 0 at the origin."""

    def __init__(self, n_var: int) -> None:
        super().__init__(np.full(n_var, -5.12), np.full(n_var, 5.12))

    def f(self, X: FloatArray) -> FloatArray:
        return 10.0 * X.shape[1] + (X**2 - 10.0 * np.cos(2.0 * np.pi * X)).sum(axis=1)


class Rosenbrock(ScalarProblem):
    """Rosenbrock on [-2, 2]^n: a narrow curved valley, minimum 0 at (1, ..., 1)."""

    def __init__(self, n_var: int) -> None:
        super().__init__(np.full(n_var, -2.0), np.full(n_var, 2.0))

    def f(self, X: FloatArray) -> FloatArray:
        return (100.0 * (X[:, 1:] - X[:, :-1] ** 2) ** 2 + (1.0 - X[:, :-1]) ** 2).sum(axis=1)


class Constrained:
    """Binh-Korn, two objectives and two constraints; ``scalarise`` penalises violations."""

    n_var = 2
    n_obj = 2
    n_constr = 2
    objective_names = ("f1", "f2")

    def __init__(self) -> None:
        self.xl, self.xu = np.zeros(2), np.array([5.0, 3.0])
        self.evaluated: list[FloatArray] = []

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        self.evaluated.append(np.array(X, copy=True))
        x, y = X[:, 0], X[:, 1]
        F = np.column_stack([4 * x**2 + 4 * y**2, (x - 5) ** 2 + (y - 5) ** 2])
        G = np.column_stack([(x - 5) ** 2 + y**2 - 20, 7.7 - (x - 8) ** 2 - (y + 3) ** 2])
        return F, G

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        return F.sum(axis=1) / 100.0 + 1000.0 * np.maximum(G, 0.0).sum(axis=1)


class Recording:
    """``problem`` wrapped to keep every row it scores through ``evaluate``, with its ``F``
    and ``G`` as returned (copies, in call order); bounds, sizes and ``scalarise`` are the
    problem's. :func:`recording` adds the single-row path where the problem has one."""

    def __init__(self, problem: Any) -> None:
        self.problem = problem
        self.n_var, self.n_obj = int(problem.n_var), int(problem.n_obj)
        self.n_constr = int(problem.n_constr)
        self.xl, self.xu = problem.xl, problem.xu
        self.objective_names = problem.objective_names
        self.rows: list[tuple[FloatArray, FloatArray, FloatArray]] = []

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        F, G = self.problem.evaluate(X)
        self.rows.append((np.array(X, copy=True), np.array(F, copy=True), np.array(G, copy=True)))
        return F, G

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        costs: FloatArray = self.problem.scalarise(F, G)
        return costs

    def scored(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Every row scored, its ``F`` and ``G``, in call order."""
        X, F, G = (np.concatenate(part) for part in zip(*self.rows, strict=True))
        return X, F, G


class RowRecording(Recording):
    """:class:`Recording` of a problem with the single-row path, which it keeps too."""

    def evaluate_row(self, x: FloatArray, F: FloatArray, G: FloatArray) -> float:
        cost = float(self.problem.evaluate_row(x, F, G))
        self.rows.append((x[None, :].copy(), F[None, :].copy(), G[None, :].copy()))
        return cost


def recording(problem: Any) -> Recording:
    """``problem`` wrapped to keep its rows, by the path(s) it offers."""
    return RowRecording(problem) if hasattr(problem, "evaluate_row") else Recording(problem)


def best_scalarised(costs: FloatArray) -> int:
    """The row a scalarised search ranks best: the first of the lowest cost, NaN as +inf."""
    return int(np.argmin(np.where(np.isnan(costs), np.inf, costs)))


def expected_rows(F: FloatArray, G: FloatArray, costs: FloatArray) -> IntArray:
    """Rows (with objectives ``F``, constraints ``G`` and scalarised ``costs``, in evaluation
    order) that an optimiser which evaluated them must return: the feasible, mutually
    non-dominated subset, one per distinct objective vector in evaluation order
    (:func:`hcomc.optim.base.archive_front`), or, when none is feasible, the best-scalarised
    row alone."""
    keep = archive_front(F, G)
    return keep if keep.size else np.array([best_scalarised(costs)])


def assert_returns_expected_set(result: ParetoResult, problem: Recording) -> None:
    """``result`` is the set :func:`expected_rows` gives for every row ``problem`` scored."""
    X, F, G = problem.scored()
    rows = expected_rows(F, G, problem.scalarise(F, G))
    for name, values in (("X", X), ("F", F), ("G", G)):
        np.testing.assert_array_equal(getattr(result, name), values[rows], err_msg=name)
    np.testing.assert_array_equal(result.feasible, np.all(G[rows] <= 0.0, axis=1))
    assert result.n_eval == X.shape[0]


def assert_holds_best_scalarised(result: ParetoResult, problem: Recording) -> None:
    """``result`` holds what a scalarised search alone would return among the feasible rows
    ``problem`` scored: a member equal to or weakly dominating the best-scalarised feasible
    row, at its cost (a scalarisation non-decreasing in every objective cannot rank a member
    that is no worse everywhere higher)."""
    _, F, G = problem.scored()
    cost = problem.scalarise(F, G)
    feasible = np.all(G <= 0.0, axis=1)
    assert feasible.any()
    best = best_scalarised(np.where(feasible, cost, np.inf))
    members = np.all(F[best] >= result.F, axis=1)
    assert members.any()
    assert problem.scalarise(result.F[members], result.G[members]).min() == cost[best]
