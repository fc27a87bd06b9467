"""Test problems on a box, shared by the tests that hold an optimiser on arrays to its
reference implementation (PSO against pymoo, SA against SciPy): single-objective ones and a
constrained two-objective one, each keeping every batch of rows it evaluated, so that two
runs can be compared call by call."""

from __future__ import annotations

import numpy as np

from hcomc._typing import FloatArray


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
