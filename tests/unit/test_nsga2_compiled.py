"""The compiled NSGA-II: its runs, its kernels against pymoo's, and its quality against pymoo's
NSGA-II, its reference.

The kernels are compared with pymoo's non-dominated sorting and domination relation exactly
(decisions on exact comparisons) and with its crowding distance within a relative 1e-12, on
random sets. Whole runs of the compiled NSGA-II on ZDT1, ZDT2, a constrained and an infeasible
problem, odd population sizes, warm starts, other operator parameters and the HCOMC merge
problem converge, keep the constraints, and run again the same for the same seed. pymoo is the
reference for solution quality: hypervolume and best Eq. 19 cost on the recorded merge problems
(:func:`test_merge_problem_quality_matches_pymoo`).
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from pymoo.indicators.hv import HV
from pymoo.operators.survival.rank_and_crowding.metrics import get_crowding_function
from pymoo.util.dominator import Dominator
from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

from hcomc._typing import FloatArray
from hcomc.config import load_config
from hcomc.control.hierarchical.controller import HCOMCController
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.equations.pareto import pareto_mask, pareto_optimal
from hcomc.optim.base import ParetoResult
from hcomc.optim.dominance import (
    crowding_distance,
    pareto_ranks,
    relation,
    tournament,
)
from hcomc.optim.evaluated import violation
from hcomc.optim.nsga2 import CompiledNSGA2Optimizer, survive_and_mate
from hcomc.optim.registry import make_optimizer
from hcomc.sim.engine import Simulation
from recorded_decisions import assert_quality_matches


class _Recorder:
    """Counts and keeps every evaluated population (in call order)."""

    def __init__(self) -> None:
        self.evaluated: list[FloatArray] = []

    def _record(self, X: FloatArray) -> None:
        self.evaluated.append(np.array(X, copy=True))


class ZDT(_Recorder):
    """ZDT1 (``concave=False``) or ZDT2 on [0, 1]^n, two objectives, unconstrained."""

    n_obj = 2
    n_constr = 0
    objective_names = ("f1", "f2")

    def __init__(self, n_var: int = 6, concave: bool = False) -> None:
        super().__init__()
        self.n_var = n_var
        self.concave = concave
        self.xl, self.xu = np.zeros(n_var), np.ones(n_var)

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        self._record(X)
        f1 = X[:, 0]
        g = 1.0 + 9.0 * X[:, 1:].sum(axis=1) / (self.n_var - 1)
        h = 1.0 - (f1 / g) ** 2 if self.concave else 1.0 - np.sqrt(f1 / g)
        return np.column_stack([f1, g * h]), np.zeros((X.shape[0], 0))

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        return F.sum(axis=1)


class ConstrainedBNH(_Recorder):
    """Binh-Korn: two objectives, two inequality constraints, x in [0, 5] x [0, 3]."""

    n_var = 2
    n_obj = 2
    n_constr = 2
    objective_names = ("f1", "f2")

    def __init__(self, shift: float = 0.0) -> None:
        super().__init__()
        self.shift = shift  # > 0 makes the first constraint harder, 30 makes it infeasible
        self.xl, self.xu = np.zeros(2), np.array([5.0, 3.0])

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        self._record(X)
        x, y = X[:, 0], X[:, 1]
        F = np.column_stack([4 * x**2 + 4 * y**2, (x - 5) ** 2 + (y - 5) ** 2])
        G = np.column_stack(
            [(x - 5) ** 2 + y**2 - 25 + self.shift, 7.7 - (x - 8) ** 2 - (y + 3) ** 2]
        )
        return F, G

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        return F.sum(axis=1) + 1000.0 * np.maximum(G, 0.0).sum(axis=1)


def _run(
    make: type, budget: int, seed: int, *, initial: FloatArray | None = None, **options: float
) -> tuple[ParetoResult, _Recorder]:
    """The compiled NSGA-II on a fresh problem ``make()``, twice with the same seed: the same
    rows, generation by generation, and the same result. Returns the result and the problem
    with its evaluated rows."""
    runs = []
    for _ in range(2):
        problem = make()
        result = CompiledNSGA2Optimizer(**options).minimize(  # type: ignore[arg-type]
            problem, budget=budget, rng=np.random.default_rng(seed), initial=initial
        )
        evaluated = np.concatenate(problem.evaluated)  # each distinct row once
        assert np.unique(evaluated, axis=0).shape[0] == evaluated.shape[0] <= result.n_eval
        runs.append((result, problem))
    (first, p_first), (again, p_again) = runs
    assert len(p_first.evaluated) == len(p_again.evaluated)
    for a, b in zip(p_first.evaluated, p_again.evaluated, strict=True):
        np.testing.assert_array_equal(a, b)
    for name in ("X", "F", "G", "feasible"):
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name))
    return first, p_first


# --------------------------------------------------------------------------------------------
# whole runs
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("concave", [False, True], ids=["ZDT1", "ZDT2"])
def test_zdt_runs_converge(concave: bool, seed: int) -> None:
    new, _ = _run(lambda: ZDT(concave=concave), 2000, seed, pop_size=40)
    hv = HV(ref_point=np.array([1.1, 1.1]))
    # converging: above random sampling at the same budget, below the true front's hypervolume
    # (ref 1.1, 1.1: 1.21 - 1/3 for ZDT1, 1.21 - 2/3 for ZDT2)
    problem = ZDT(concave=concave)
    F, _ = problem.evaluate(np.random.default_rng(seed).random((2000, problem.n_var)))
    assert hv(F[pareto_optimal(F)]) < hv(new.F) <= 1.21 - (2.0 / 3.0 if concave else 1.0 / 3.0)


@pytest.mark.parametrize(
    ("pop_size", "budget", "seed"), [(24, 240, 0), (40, 360, 1), (7, 100, 2), (3, 5, 3)]
)
def test_constrained_runs(pop_size: int, budget: int, seed: int) -> None:
    new, _ = _run(ConstrainedBNH, budget, seed, pop_size=pop_size)
    assert new.feasible.all()
    assert (new.G <= 0).all()
    assert new.n_eval == pop_size * max(1, budget // pop_size)


def test_infeasible_problem_returns_the_least_violating_row() -> None:
    new, p_new = _run(lambda: ConstrainedBNH(shift=30.0), 200, 4, pop_size=20)
    assert not new.any_feasible
    assert new.X.shape == (1, 2)
    evaluated = np.vstack(p_new.evaluated)
    cv = violation(ConstrainedBNH(shift=30.0).evaluate(evaluated)[1])
    assert violation(new.G)[0] == cv.min()  # elitist: the least violation ever seen survives


def test_operator_parameters_and_warm_start() -> None:
    options = {"pop_size": 12, "crossover_eta": 5.0, "crossover_prob": 0.6, "mutation_eta": 8.0}
    new, _ = _run(lambda: ZDT(n_var=4), 120, 5, **options)
    assert new.n_eval == 120
    initial = np.array([[0.0, 0.0, 0.0, 0.0], [1.5, -1.0, 0.5, 0.5]])  # the second is clipped
    _, p_new = _run(lambda: ZDT(n_var=4), 120, 6, initial=initial, pop_size=12)
    first = p_new.evaluated[0]
    np.testing.assert_array_equal(first[:2], np.clip(initial, 0.0, 1.0))


def test_violation_is_the_sum_of_positive_constraints() -> None:
    G = np.array([[-1.0, 0.0, 2.0, 0.5], [0.0, -0.0, -3.0, -1.0], [np.nan, 1.0, 0.0, 0.0]])
    np.testing.assert_array_equal(violation(G), [2.5, 0.0, np.nan])
    np.testing.assert_array_equal(violation(np.empty((3, 0))), np.zeros(3))


def test_deterministic_per_seed_and_seed_sensitive() -> None:
    opt = CompiledNSGA2Optimizer(pop_size=20)
    a, b, c = (
        opt.minimize(ConstrainedBNH(), budget=200, rng=np.random.default_rng(s)) for s in (7, 7, 8)
    )
    np.testing.assert_array_equal(a.X, b.X)
    np.testing.assert_array_equal(a.F, b.F)
    assert a.X.shape != c.X.shape or not np.array_equal(a.X, c.X)
    assert a.algorithm == "nsga2"
    assert make_optimizer("nsga2-pymoo").name == "nsga2-pymoo"


@cache
def _merge_problem(seed: int) -> MergeProblem:
    config = load_config("C1", control={"controller": "hcomc"})
    sim = Simulation(config, seed)
    assert sim.run_until_plan() is not None
    view, group = sim.requests[0]
    return HCOMCController(config).problem(view, group)[0]


@pytest.mark.parametrize("seed", [0, 3])
def test_merge_problem_runs(seed: int) -> None:
    """On the HCOMC problem at the default budget (pop 40, 360 rows): the whole budget spent,
    and the same set again for the same seed."""
    problem = _merge_problem(seed)
    results = [
        CompiledNSGA2Optimizer(pop_size=40).minimize(
            problem, budget=360, rng=np.random.default_rng(seed)
        )
        for _ in range(2)
    ]
    for name in ("X", "F", "G", "feasible"):
        np.testing.assert_array_equal(getattr(results[0], name), getattr(results[1], name))
    assert results[1].n_eval == 360


def test_merge_problem_evaluate_equals_predict() -> None:
    """``evaluate`` skips the trajectories but gives :meth:`predict`'s objectives bit for bit."""
    problem = _merge_problem(0)
    X = np.random.default_rng(2).uniform(problem.xl, problem.xu, size=(50, problem.n_var))
    F, G = problem.evaluate(X)
    p = problem.predict(X)
    np.testing.assert_array_equal(F, p.F)
    np.testing.assert_array_equal(G, p.G)


# --------------------------------------------------------------------------------------------
# kernels against pymoo's
# --------------------------------------------------------------------------------------------

_small_sets = arrays(
    np.float64,
    st.tuples(st.integers(1, 40), st.integers(1, 4)),
    elements=st.integers(0, 5).map(float),  # few values: ties and duplicates are common
)


@settings(max_examples=150, deadline=None)
@given(_small_sets)
def test_pareto_ranks_equal_pymoo_sorting(F: FloatArray) -> None:
    _, rank = NonDominatedSorting().do(F, return_rank=True)
    np.testing.assert_array_equal(pareto_ranks(F), rank)
    np.testing.assert_array_equal(pareto_mask(F), rank == 0)
    np.testing.assert_array_equal(pareto_optimal(F), rank == 0)


@settings(max_examples=150, deadline=None)
@given(_small_sets | arrays(np.float64, st.tuples(st.integers(1, 30), st.integers(1, 4)),
                            elements=st.floats(-1e3, 1e3)))  # fmt: skip
def test_crowding_distance_equals_pymoo(F: FloatArray) -> None:
    """pymoo's crowding distances, infinite at the boundaries, within a relative 1e-12."""
    expected = get_crowding_function("cd").do(F)
    np.testing.assert_allclose(crowding_distance(F), expected, rtol=1e-12, atol=0.0)


@settings(max_examples=200, deadline=None)
@given(arrays(np.float64, (2, 3), elements=st.integers(0, 3).map(float)))
def test_relation_equals_pymoo_dominator(ab: FloatArray) -> None:
    assert relation(ab[0], ab[1]) == Dominator.get_relation(ab[0], ab[1])


def test_tournament_rules() -> None:
    F = np.array([[0.0, 1.0], [1.0, 0.0], [1.0, 2.0], [0.5, 0.5]])
    cv = np.array([0.0, 0.0, 0.0, 2.0])
    crowd = np.array([np.inf, 1.0, 0.5, np.nan])
    P = np.array([[0, 1], [1, 2], [2, 3], [3, 2], [0, 0], [1, 0]], dtype=np.int64)
    # crowding decides between non-dominated rows, domination first, violation beats all
    np.testing.assert_array_equal(tournament(P, F, cv, crowd), [0, 1, 2, 2, -1, 0])


def test_survival_takes_feasible_fronts_then_least_violating() -> None:
    F = np.array([[0.0, 1.0], [1.0, 0.0], [2.0, 2.0], [0.0, 0.0], [3.0, 3.0], [5.0, 5.0]])
    cv = np.array([0.0, 0.0, 0.0, 3.0, 1.0, 0.0])
    rows = np.arange(F.shape[0])
    idx, _, rank, crowding = survive_and_mate(F, cv, rows, 5, 0, np.random.default_rng(0))
    # feasible: front {0, 1} (index order), then {2}, then {5}; infeasible by violation: 4
    np.testing.assert_array_equal(rows[idx], [0, 1, 2, 5, 4])
    np.testing.assert_array_equal(rank[idx][:4], [0, 0, 1, 2])
    assert np.isinf(crowding[idx][:4]).all()  # fronts of <= 2 rows are all boundary


def test_merge_problem_quality_matches_pymoo() -> None:
    """The compiled NSGA-II's solution quality is pymoo's, paired over seeds on the recorded
    merge problems (:func:`recorded_decisions.assert_quality_matches`: instants 0-4, the first
    of C1-C5, seeds 0-7, the config's budget and population).

    Tolerance: mean hypervolume ratio >= 0.95, and mean best Eq. 19 cost at most 10 % of the
    library's spread above pymoo's. Measured on a CPU whose numpy takes a SIMD ``power``
    (AVX-512), where 20 of the 40 runs part from pymoo's in the last bits: ratio 1 (no pair
    off by more than 9e-16), gap -2.6e-17 against a spread of 0.77. With the runs unpaired
    (pymoo seeded 1000-1007: runs that share no draws, the worst a divergence could do) ratio
    0.996 and gap +0.016 against a spread of 0.62 (2.6 %, one standard error 2.8 %).
    """
    assert_quality_matches("nsga2", "nsga2-pymoo")
