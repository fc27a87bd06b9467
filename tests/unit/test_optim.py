"""Tests for hcomc.optim: Eq. 19 selection, the non-dominated filter, NSGA-II, PSO and SA,
and the set every optimiser returns (the feasible non-dominated subset of all its rows)."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from pymoo.indicators.hv import HV
from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

from hcomc._typing import FloatArray
from hcomc.equations.pareto import pareto_optimal
from hcomc.equations.selection import select_eq19
from hcomc.optim.annealing import AnnealingOptimizer
from hcomc.optim.base import Archive, ParetoResult
from hcomc.optim.nsga2 import CompiledNSGA2Optimizer
from hcomc.optim.pso.optimizer import CompiledPSOOptimizer
from hcomc.optim.pymoo_backend import NSGA2Optimizer, PSOOptimizer
from hcomc.optim.registry import OPTIMIZERS, POPULATION_BASED, make_optimizer
from hcomc.optim.sa import CompiledAnnealingOptimizer
from scalar_problems import (
    RowRecording,
    assert_returns_expected_set,
    best_scalarised,
    recording,
)

PAPER_THRESHOLD = 4.0  # the paper's Eq. 19 gate on U_safe [m/s^2]
eq19 = partial(select_eq19, safety_threshold=PAPER_THRESHOLD)
NAMES = ("safety", "fuel", "efficiency")


# --------------------------------------------------------------------------------------------
# test problems (vectorised, implementing optim.base.Problem)
# --------------------------------------------------------------------------------------------


class ConstrainedDTLZ2:
    """DTLZ2-like, 4 variables, 3 objectives, minus the corner x0 + x1 > 1.5 of the box.

    The distance function is 10x DTLZ2's, g = 10 sum (x_i - 0.5)^2 over x2, x3, so that
    converging matters: with DTLZ2's own g (at most 0.5 here), the non-dominated subset of 360
    random points has a larger hypervolume than NSGA-II's final 24-point population.
    """

    n_var = 4
    n_obj = 3
    n_constr = 1
    objective_names = NAMES

    def __init__(self) -> None:
        self.xl = np.zeros(4)
        self.xu = np.ones(4)
        self.xl.flags.writeable = False  # any in-place change by an optimiser would raise
        self.xu.flags.writeable = False
        self.n_rows = 0
        self.evaluated: list[FloatArray] = []  # the populations, in call order

    def objectives(self, X: FloatArray) -> FloatArray:
        g = 10.0 * ((X[:, 2:] - 0.5) ** 2).sum(axis=1)
        a, b = 0.5 * np.pi * X[:, 0], 0.5 * np.pi * X[:, 1]
        return (1.0 + g)[:, None] * np.column_stack(
            [np.cos(a) * np.cos(b), np.cos(a) * np.sin(b), np.sin(a)]
        )

    def constraints(self, X: FloatArray) -> FloatArray:
        return (X[:, 0] + X[:, 1] - 1.5)[:, None]

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        self.evaluated.append(np.array(X, copy=True))
        self.n_rows += X.shape[0]
        return self.objectives(X), self.constraints(X)

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        return F.sum(axis=1) + 1000.0 * np.maximum(G, 0.0).sum(axis=1)


class UnconstrainedDTLZ2(ConstrainedDTLZ2):
    """The same objectives with no constraint (G has zero columns)."""

    n_constr = 0

    def constraints(self, X: FloatArray) -> FloatArray:
        return np.zeros((X.shape[0], 0))


class InfeasibleDTLZ2(ConstrainedDTLZ2):
    """Nothing is feasible: G = 0.2 + x0 > 0 everywhere (least violation at x0 = 0)."""

    def constraints(self, X: FloatArray) -> FloatArray:
        return (0.2 + X[:, 0])[:, None]


SPHERE_CENTRE = np.array([1.0, -2.0, 0.5, 3.0])


class PenalisedSphere:
    """min |x - c|^2 on [-5, 5]^4 s.t. x0 >= 1.5; optimum 0.25 at (1.5, -2, 0.5, 3)."""

    n_var = 4
    n_obj = 1
    n_constr = 1
    objective_names = ("f",)
    optimum = 0.25

    def __init__(self) -> None:
        self.xl = np.full(4, -5.0)
        self.xu = np.full(4, 5.0)

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        return ((X - SPHERE_CENTRE) ** 2).sum(axis=1)[:, None], (1.5 - X[:, 0])[:, None]

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        return F[:, 0] + 1000.0 * np.maximum(G, 0.0).sum(axis=1)


class NonFiniteSphere(PenalisedSphere):
    """Scalarised cost +inf where x0 < 0 and NaN where x1 < -4 (an infinite penalty)."""

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        cost = super().scalarise(F, G)
        return np.where(F[:, 0] > 60.0, np.nan, np.where(G[:, 0] > 1.5, np.inf, cost))


def _run(name: str, problem: object, budget: int, seed: int) -> ParetoResult:
    return make_optimizer(name).minimize(problem, budget=budget, rng=np.random.default_rng(seed))


# --------------------------------------------------------------------------------------------
# Eq. 19 selection
# --------------------------------------------------------------------------------------------


def test_select_eq19_safe_branch_normalised_sums() -> None:
    F = np.array(
        [
            [3.0, 10.0, -1.0],
            [2.0, 14.0, -3.0],
            [5.0, 1.0, -9.0],  # best fuel and efficiency but unsafe: excluded by the gate
            [4.0, 11.0, -2.0],  # safety == threshold passes the gate
        ]
    )
    # subset {0, 1, 3}: fuel 10, 14, 11 -> 0, 1, 0.25; efficiency -1, -3, -2 -> 1, 0, 0.5
    # sums 1.0, 1.0, 0.75 -> row 3
    assert eq19(F, NAMES) == 3


def test_select_eq19_ties_in_sum_go_to_lower_index() -> None:
    F = np.array([[3.0, 10.0, -1.0], [2.0, 14.0, -3.0], [4.0, 12.0, -2.0]])
    # fuel 0, 1, 0.5; efficiency 1, 0, 0.5 -> sums all 1.0
    assert eq19(F, NAMES) == 0


def test_select_eq19_unsafe_branch_min_safety_then_fuel_then_index() -> None:
    F = np.array([[6.0, 1.0, 0.0], [5.0, 3.0, -5.0], [5.0, 2.0, 0.0], [7.0, 0.0, -9.0]])
    assert eq19(F, NAMES) == 2  # safety 5 twice; lower fuel wins
    F2 = np.array([[6.0, 1.0, 0.0], [5.0, 2.0, 0.0], [5.0, 2.0, -1.0]])
    assert eq19(F2, NAMES) == 1  # full tie on safety and fuel: lower index


def test_select_eq19_threshold_is_a_parameter() -> None:
    F = np.array([[4.5, 1.0, 0.0], [3.0, 5.0, 0.0]])
    assert eq19(F, NAMES) == 1
    assert eq19(F, NAMES, safety_threshold=5.0) == 0
    assert eq19(F, NAMES, safety_threshold=2.0) == 1  # both unsafe: min safety


def test_select_eq19_ignores_infeasible_rows() -> None:
    F = np.array([[1.0, 0.0, -10.0], [2.0, 5.0, -1.0], [3.0, 4.0, -2.0]])
    assert eq19(F, NAMES) == 0
    feasible = np.array([False, True, True])
    # rows 1, 2: fuel 1, 0; efficiency 1, 0 -> row 2
    assert eq19(F, NAMES, feasible=feasible) == 2
    # infeasible safe row does not trigger the safe branch for feasible unsafe rows
    F3 = np.array([[1.0, 0.0, 0.0], [6.0, 1.0, 0.0], [5.0, 2.0, 0.0]])
    assert eq19(F3, NAMES, feasible=np.array([False, True, True])) == 2


def test_select_eq19_no_feasible_row_considers_all() -> None:
    F = np.array([[1.0, 0.0, -10.0], [2.0, 5.0, -1.0]])
    assert eq19(F, NAMES, feasible=np.zeros(2, dtype=bool)) == eq19(F, NAMES) == 0


def test_select_eq19_constant_column_normalises_to_zero() -> None:
    F = np.array([[1.0, 5.0, -1.0], [2.0, 5.0, -4.0], [3.0, 5.0, -2.0]])
    # fuel constant -> 0; efficiency 1, 0, 2/3 -> row 1
    assert eq19(F, NAMES) == 1
    both_constant = np.array([[9.0, 5.0, -1.0], [2.0, 5.0, -1.0], [3.0, 5.0, -1.0]])
    assert eq19(both_constant, NAMES) == 1  # all sums 0: lowest safe index
    assert eq19(np.array([[9.0, 1.0, 1.0], [3.0, 7.0, 7.0]]), NAMES) == 1  # singleton


def test_select_eq19_finds_columns_by_name() -> None:
    F = np.array([[3.0, 10.0, -1.0], [2.0, 14.0, -3.0], [5.0, 1.0, -9.0], [4.0, 11.0, -2.0]])
    order = [2, 0, 1]
    names = tuple(NAMES[i] for i in order)
    extra = np.column_stack([F[:, order], np.arange(4.0)])
    assert eq19(extra, (*names, "other")) == 3


def test_select_eq19_rejects_bad_input() -> None:
    F = np.ones((2, 3))
    with pytest.raises(ValueError, match="'fuel' not found"):
        eq19(F, ("safety", "cost", "efficiency"))
    with pytest.raises(ValueError, match="shape"):
        eq19(F, ("safety", "fuel"))
    with pytest.raises(ValueError, match="empty"):
        eq19(np.zeros((0, 3)), NAMES)
    with pytest.raises(ValueError, match="feasible"):
        eq19(F, NAMES, feasible=np.ones(3, dtype=bool))


# --------------------------------------------------------------------------------------------
# non-dominated filter
# --------------------------------------------------------------------------------------------


def _pymoo_front(F: FloatArray) -> np.ndarray:
    mask = np.zeros(len(F), dtype=bool)
    mask[NonDominatedSorting().do(F, only_non_dominated_front=True)] = True
    return mask


@settings(max_examples=60, deadline=None)
@given(
    arrays(
        np.float64,
        st.tuples(st.integers(1, 25), st.integers(1, 4)),
        elements=st.integers(0, 4).map(float),  # small integer grid: many ties and duplicates
    )
)
def test_pareto_optimal_matches_pymoo(F: FloatArray) -> None:
    np.testing.assert_array_equal(pareto_optimal(F), _pymoo_front(F))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_pareto_optimal_matches_pymoo_on_random_sets(seed: int) -> None:
    F = np.random.default_rng(seed).random((200, 3))
    np.testing.assert_array_equal(pareto_optimal(F), _pymoo_front(F))


def test_pareto_optimal_keeps_identical_rows() -> None:
    F = np.array([[1.0, 2.0], [1.0, 2.0], [2.0, 1.0], [2.0, 2.0], [2.0, 2.0]])
    np.testing.assert_array_equal(pareto_optimal(F), [True, True, True, False, False])
    assert pareto_optimal(np.ones((4, 3))).all()
    assert pareto_optimal(np.zeros((0, 2))).shape == (0,)


# --------------------------------------------------------------------------------------------
# NSGA-II
# --------------------------------------------------------------------------------------------


def _hypervolume(F: FloatArray) -> float:
    return float(HV(ref_point=np.full(3, 2.0))(F))


def test_nsga2_returns_feasible_mutually_non_dominated_set() -> None:
    problem = ConstrainedDTLZ2()
    res = _run("nsga2", problem, 360, seed=0)
    assert res.algorithm == "nsga2"
    assert res.X.shape[0] > 1
    assert res.feasible.all()
    assert (res.G <= 0.0).all()
    assert pareto_optimal(res.F).all()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nsga2_hypervolume_beats_random_sampling(seed: int) -> None:
    problem = ConstrainedDTLZ2()
    budget = 360
    res = _run("nsga2", problem, budget, seed)
    X = np.random.default_rng(seed).uniform(problem.xl, problem.xu, (budget, problem.n_var))
    F, G = problem.evaluate(X)
    F = F[(G <= 0.0).all(axis=1)]
    assert _hypervolume(res.F) > _hypervolume(F[pareto_optimal(F)])


@pytest.mark.parametrize(("budget", "expected"), [(48, 48), (240, 240), (100, 96), (5, 24)])
def test_nsga2_budget_layout(budget: int, expected: int) -> None:
    problem = ConstrainedDTLZ2()
    res = _run("nsga2", problem, budget, seed=3)
    assert res.n_eval == expected >= problem.n_rows  # a repeated row is not evaluated again


def test_nsga2_deterministic_per_seed() -> None:
    a, b = (_run("nsga2", ConstrainedDTLZ2(), 120, seed=7) for _ in range(2))
    np.testing.assert_array_equal(a.X, b.X)
    np.testing.assert_array_equal(a.F, b.F)
    c = _run("nsga2", ConstrainedDTLZ2(), 120, seed=8)
    assert a.X.shape != c.X.shape or not np.array_equal(a.X, c.X)


def test_nsga2_operator_parameters_are_used() -> None:
    opt = make_optimizer("nsga2", pop_size=10, crossover_eta=5.0, mutation_eta=5.0)
    assert isinstance(opt, CompiledNSGA2Optimizer)
    assert (opt.pop_size, opt.crossover_eta, opt.mutation_eta) == (10, 5.0, 5.0)
    res = opt.minimize(ConstrainedDTLZ2(), budget=50, rng=np.random.default_rng(0))
    assert res.n_eval == 50
    # the operators really receive them: other distribution indices, other search, same seed
    other = make_optimizer("nsga2", pop_size=10, crossover_eta=30.0, mutation_eta=40.0)
    res2 = other.minimize(ConstrainedDTLZ2(), budget=50, rng=np.random.default_rng(0))
    assert res.X.shape != res2.X.shape or not np.array_equal(res.X, res2.X)
    with pytest.raises(ValueError, match="pop_size"):
        NSGA2Optimizer(pop_size=1)
    with pytest.raises(ValueError, match="pop_size"):
        CompiledNSGA2Optimizer(pop_size=1)


def test_warm_start_rows_open_the_first_population() -> None:
    """With ``initial``, NSGA-II's first generation contains those rows (clipped)."""
    problem = ConstrainedDTLZ2()
    start = np.clip(np.full((3, problem.n_var), 0.25), problem.xl, problem.xu)
    opt = make_optimizer("nsga2", pop_size=10)
    opt.minimize(problem, budget=10, rng=np.random.default_rng(1), initial=start)
    first = problem.evaluated[0]
    for row in start:
        assert np.isclose(first, row).all(axis=1).any()


# --------------------------------------------------------------------------------------------
# PSO and SA on a penalised sphere
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "budget", "tol"),
    [("pso", 960, 0.01), ("pso-pymoo", 960, 0.01), ("sa", 2000, 0.1), ("sa-scipy", 2000, 0.1)],
)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_single_objective_reaches_known_optimum(name: str, budget: int, tol: float, seed: int):
    res = _run(name, PenalisedSphere(), budget, seed)
    assert res.feasible.all()
    assert res.X.shape == (1, 4)  # one objective: the front is the lowest feasible row
    assert res.F[0, 0] == pytest.approx(PenalisedSphere.optimum, abs=tol)
    np.testing.assert_allclose(res.X[0, 1:], SPHERE_CENTRE[1:], atol=np.sqrt(tol))


@pytest.mark.parametrize("name", ["pso", "pso-pymoo"])
@pytest.mark.parametrize("budget", [1, 10, 100, 360])
def test_pso_respects_budget(name: str, budget: int) -> None:
    res = _run(name, PenalisedSphere(), budget, seed=0)
    assert res.n_eval == 24 * max(1, budget // 24)
    assert res.n_eval <= budget + 24


@pytest.mark.parametrize("name", ["sa", "sa-scipy"])
@pytest.mark.parametrize("budget", [1, 7, 100, 360])
def test_sa_spends_exactly_the_budget(name: str, budget: int) -> None:
    assert _run(name, PenalisedSphere(), budget, seed=0).n_eval == budget


class _CountingSphere(PenalisedSphere):
    def __init__(self) -> None:
        super().__init__()
        self.n_rows = 0

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        self.n_rows += X.shape[0]
        return super().evaluate(X)


@pytest.mark.parametrize("optimizer", [AnnealingOptimizer, CompiledAnnealingOptimizer])
def test_sa_hard_cap_when_scipy_overshoots_maxfun(optimizer: type[AnnealingOptimizer]) -> None:
    # With restart_temp_ratio 0.5 SciPy re-anneals after one chain: start point (1 call),
    # chain (2 n_var = 8 calls), re-anneal start (call 10), next chain's first call would be
    # the 11th: SciPy checks maxfun only after it, so maxfun=10 alone gives 11 calls.
    problem = _CountingSphere()
    res = optimizer(restart_temp_ratio=0.5).minimize(
        problem, budget=10, rng=np.random.default_rng(0)
    )
    assert res.n_eval == problem.n_rows == 10


class _RowSphere(PenalisedSphere):
    """The sphere with the single-row fast path (``optim.base.RowProblem``) writing into the
    optimiser's buffers; logs which path scored each row."""

    def __init__(self) -> None:
        super().__init__()
        self.paths: list[str] = []

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        self.paths.append("evaluate")
        return PenalisedSphere.evaluate(self, X)

    def evaluate_row(self, x: FloatArray, F: FloatArray, G: FloatArray) -> float:
        self.paths.append("row")
        f, g = PenalisedSphere.evaluate(self, x[None, :])
        F[:], G[:] = f[0], g[0]
        return float(self.scalarise(f, g)[0])


class _NonFiniteRowSphere(_RowSphere, NonFiniteSphere):
    """The row path with infinite and NaN costs."""


@pytest.mark.parametrize(
    ("row_cls", "plain_cls"),
    [(_RowSphere, PenalisedSphere), (_NonFiniteRowSphere, NonFiniteSphere)],
)
@pytest.mark.parametrize("row_path", [True, False])
@pytest.mark.parametrize("optimizer", [AnnealingOptimizer, CompiledAnnealingOptimizer])
def test_sa_row_path_used_when_offered_and_decides_the_same(
    row_cls: type[_RowSphere],
    plain_cls: type[PenalisedSphere],
    row_path: bool,
    optimizer: type[AnnealingOptimizer],
) -> None:
    # the row path is taken for every row when offered (unless switched off), and the result
    # equals that of the plain problem: the best row is copied out of the reused buffers
    initial = np.array([[2.0, -1.0, 0.0, 2.0]])
    problem = row_cls()
    res = optimizer(row_path=row_path).minimize(
        problem, budget=200, rng=np.random.default_rng(3), initial=initial
    )
    ref = optimizer().minimize(
        plain_cls(), budget=200, rng=np.random.default_rng(3), initial=initial
    )
    assert problem.paths == ["row" if row_path else "evaluate"] * 200
    for name in ("X", "F", "G", "feasible"):
        np.testing.assert_array_equal(getattr(res, name), getattr(ref, name))
    assert res.n_eval == ref.n_eval == 200


@pytest.mark.parametrize("name", ["pso", "pso-pymoo", "sa", "sa-scipy"])
def test_single_objective_deterministic_per_seed(name: str) -> None:
    a, b = (_run(name, PenalisedSphere(), 240, seed=11) for _ in range(2))
    np.testing.assert_array_equal(a.X, b.X)
    np.testing.assert_array_equal(a.F, b.F)
    c = _run(name, PenalisedSphere(), 240, seed=12)
    assert not np.array_equal(a.X, c.X)


def test_archive_keeps_every_row_in_order_and_the_best_scalarised() -> None:
    archive = Archive(2, 1, 1, 1)
    archive.add(np.array([[0.0], [1.0], [2.0]]), np.array([[np.nan], [3.0], [3.0]]),
                np.zeros((3, 1)), np.array([np.nan, 3.0, 3.0]))  # fmt: skip
    assert (archive.size, archive.best) == (3, 1)  # grown; NaN ranks last, first of equals
    k = archive.size
    archive.X[k], archive.F[k], archive.G[k] = 3.0, 2.0, 1.0  # a row scored in place
    archive.keep(k, 2.0)
    archive.add(np.array([[4.0]]), np.array([[1.0]]), np.array([[0.0]]))  # no cost: not offered
    assert (archive.size, archive.best) == (5, 3)
    np.testing.assert_array_equal(archive.X[:5, 0], [0.0, 1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(archive.F[:5, 0], [np.nan, 3.0, 3.0, 2.0, 1.0])
    res = archive.result(5, "test")  # the front: the NaN row (never dominated) and row 4
    np.testing.assert_array_equal(res.X[:, 0], [0.0, 4.0])
    assert res.feasible.all()
    first = Archive(1, 1, 1, 1)
    first.X[0], first.F[0], first.G[0] = 0.5, 0.0, 1.0  # infeasible
    first.keep(0, np.inf)  # the first row is the best even at +inf
    assert first.best == 0
    res = first.result(1, "test")  # nothing feasible: the best-scalarised row
    assert (res.X.tolist(), res.feasible.tolist()) == ([[0.5]], [False])


class _RowDTLZ2(ConstrainedDTLZ2):
    """The constrained DTLZ2 with the single-row path (``optim.base.RowProblem``)."""

    def evaluate_row(self, x: FloatArray, F: FloatArray, G: FloatArray) -> float:
        f, g = ConstrainedDTLZ2.evaluate(self, x[None, :])
        F[:], G[:] = f[0], g[0]
        return float(self.scalarise(f, g)[0])


def _assert_front_of(res: ParetoResult, F: FloatArray, G: FloatArray) -> None:
    """``res`` is a front of the rows ``F``, ``G`` by definition (numpy, pairwise): feasible,
    mutually non-dominated, distinct objective vectors, and every feasible row is a member or
    weakly dominated by one."""
    assert res.feasible.all()
    assert (res.G <= 0.0).all()
    assert pareto_optimal(res.F).all()
    assert np.unique(res.F, axis=0).shape[0] == res.F.shape[0]
    feasible = F[(G <= 0.0).all(axis=1)]
    covered = (res.F[None, :, :] <= feasible[:, None, :]).all(axis=2).any(axis=1)
    assert covered.all()


SCALARISED = ["pso", "pso-pymoo", "sa", "sa-scipy"]


@pytest.mark.parametrize("make", [ConstrainedDTLZ2, UnconstrainedDTLZ2, _RowDTLZ2])
@pytest.mark.parametrize("name", SCALARISED)
@pytest.mark.parametrize("seed", [0, 1])
def test_scalarised_search_returns_the_front_of_every_evaluated_row(
    name: str, make: type[ConstrainedDTLZ2], seed: int
) -> None:
    """PSO and SA search on the scalarised cost but return, as NSGA-II does, the feasible
    non-dominated set of every row they evaluated (recorded by a wrapping problem, through
    ``evaluate`` or SA's single-row path), which holds the best-scalarised feasible row."""
    problem = recording(make())
    assert isinstance(problem, RowRecording) == (make is _RowDTLZ2)
    res = _run(name, problem, 240, seed)
    assert_returns_expected_set(res, problem)
    X, F, G = problem.scored()
    _assert_front_of(res, F, G)
    assert res.X.shape[0] > 1  # three objectives: a set, not one row
    cost = problem.scalarise(F, G)
    feasible = (G <= 0.0).all(axis=1)
    best = best_scalarised(np.where(feasible, cost, np.inf))
    assert (X[best] == res.X).all(axis=1).any()  # the row PSO or SA alone would return
    assert problem.scalarise(res.F, res.G).min() == cost[best]


@pytest.mark.parametrize("name", SCALARISED)
@pytest.mark.parametrize("seed", [0, 1])
def test_scalarised_search_returns_best_scalarised_row_when_nothing_is_feasible(
    name: str, seed: int
) -> None:
    problem = recording(InfeasibleDTLZ2())
    res = _run(name, problem, 120, seed)
    X, F, G = problem.scored()
    best = best_scalarised(problem.scalarise(F, G))
    np.testing.assert_array_equal(res.X, X[best : best + 1])
    np.testing.assert_array_equal(res.F, F[best : best + 1])
    np.testing.assert_array_equal(res.G, G[best : best + 1])
    assert not res.any_feasible
    assert_returns_expected_set(res, problem)


@pytest.mark.parametrize("name", ["pso", "pso-pymoo", "sa", "sa-scipy"])
def test_single_objective_survives_non_finite_costs(name: str) -> None:
    problem = NonFiniteSphere()
    res = _run(name, problem, 240, seed=0)
    assert np.isfinite(problem.scalarise(res.F, res.G)).all()


# --------------------------------------------------------------------------------------------
# contract: every registered optimiser
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("problem_cls", [ConstrainedDTLZ2, UnconstrainedDTLZ2, InfeasibleDTLZ2])
@pytest.mark.parametrize("name", sorted(OPTIMIZERS))
def test_optimizer_contract(name: str, problem_cls: type[ConstrainedDTLZ2]) -> None:
    problem = problem_cls()
    xl, xu = problem.xl.copy(), problem.xu.copy()
    global_state = np.random.get_state()  # noqa: NPY002
    optimizer = make_optimizer(name, **({"pop_size": 12} if name in POPULATION_BASED else {}))
    budget = 60
    res = optimizer.minimize(problem, budget=budget, rng=np.random.default_rng(0))

    assert isinstance(res, ParetoResult)
    assert optimizer.name == res.algorithm == name
    p = res.X.shape[0]
    assert p >= 1
    assert res.X.shape == (p, problem.n_var)
    assert res.F.shape == (p, problem.n_obj)
    assert res.G.shape == (p, problem.n_constr)
    assert res.feasible.shape == (p,)
    assert res.feasible.dtype == np.bool_
    assert np.all(xl <= res.X)
    assert np.all(xu >= res.X)
    np.testing.assert_array_equal(problem.xl, xl)
    np.testing.assert_array_equal(problem.xu, xu)
    F, G = problem.evaluate(res.X)
    np.testing.assert_array_equal(res.F, F)
    np.testing.assert_array_equal(res.G, G)
    np.testing.assert_array_equal(res.feasible, (G <= 0.0).all(axis=1))
    assert 1 <= res.n_eval <= budget + 12
    if problem_cls is InfeasibleDTLZ2:
        assert not res.any_feasible
        assert p == 1
    else:
        assert res.any_feasible
    # no global RNG use
    after = np.random.get_state()  # noqa: NPY002
    assert global_state[0] == after[0]
    np.testing.assert_array_equal(global_state[1], after[1])
    assert global_state[2:] == after[2:]


@pytest.mark.parametrize("name", sorted(OPTIMIZERS))
def test_optimizer_consumes_only_the_given_rng(name: str) -> None:
    rng = np.random.default_rng(0)
    before = rng.bit_generator.state
    make_optimizer(name).minimize(ConstrainedDTLZ2(), budget=24, rng=rng)
    assert rng.bit_generator.state != before  # the seed is drawn from the caller's generator


def test_registry() -> None:
    assert set(OPTIMIZERS) == {"nsga2", "nsga2-pymoo", "pso", "pso-pymoo", "sa", "sa-scipy"}
    assert isinstance(make_optimizer("nsga2-pymoo", pop_size=8), NSGA2Optimizer)
    assert isinstance(make_optimizer("pso", pop_size=8), CompiledPSOOptimizer)
    assert isinstance(make_optimizer("pso-pymoo", pop_size=8), PSOOptimizer)
    assert isinstance(make_optimizer("sa"), CompiledAnnealingOptimizer)
    assert isinstance(make_optimizer("sa-scipy"), AnnealingOptimizer)
    for name in ("sa", "sa-scipy"):
        with pytest.raises(ValueError, match=rf"option 'pop_size' does not apply to .* '{name}'"):
            make_optimizer(name, pop_size=8)  # SA has no population: never silently ignored
    allowed = "nsga2, nsga2-pymoo, pso, pso-pymoo, sa, sa-scipy"
    with pytest.raises(ValueError, match=rf"^unknown optimizer 'nope'; allowed: {allowed}$"):
        make_optimizer("nope")


@pytest.mark.parametrize("name", sorted(OPTIMIZERS))
def test_rejects_non_positive_budget(name: str) -> None:
    with pytest.raises(ValueError, match="budget"):
        make_optimizer(name).minimize(PenalisedSphere(), budget=0, rng=np.random.default_rng(0))
