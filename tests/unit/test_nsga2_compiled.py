"""The compiled NSGA-II against pymoo, its reference: same rows evaluated, same Pareto sets
where numpy's power is the C library's, the same quality everywhere.

pymoo (``nsga2-pymoo``) is the oracle throughout: the kernels are compared with pymoo's
non-dominated sorting, crowding distance and domination relation on random sets, and whole runs
with pymoo's NSGA-II on the same problems, budgets and generators (ZDT1, ZDT2, a constrained and
an infeasible problem, odd population sizes, warm starts, other operator parameters, and the
HCOMC merge problem itself). The variation operators take powers with the C library's ``pow``,
pymoo with numpy's: the whole runs equal pymoo's bit for bit only where numpy's power is the C
library's, and are skipped elsewhere (:data:`scalar_problems.needs_libm_numpy`); on any CPU the
compiled NSGA-II's hypervolume and best Eq. 19 cost on recorded merge problems are held within
a stated tolerance of pymoo's (:func:`test_merge_problem_quality_matches_pymoo`).
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
from hcomc.optim.base import ParetoResult
from hcomc.optim.dominance import (
    crowding_distance,
    non_dominated_mask,
    pareto_ranks,
    relation,
    tournament,
)
from hcomc.optim.nsga2 import CompiledNSGA2Optimizer, survive_and_mate, violation
from hcomc.optim.pymoo_backend import NSGA2Optimizer
from hcomc.optim.registry import make_optimizer
from hcomc.optim.selection import non_dominated
from hcomc.sim.engine import Simulation
from recorded_decisions import assert_quality_matches
from scalar_problems import needs_libm_numpy


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


def _both(
    make: type, budget: int, seed: int, *, initial: FloatArray | None = None, **options: float
) -> tuple[ParetoResult, ParetoResult, _Recorder, _Recorder]:
    p_ref, p_new = make(), make()
    ref = NSGA2Optimizer(**options).minimize(  # type: ignore[arg-type]
        p_ref, budget=budget, rng=np.random.default_rng(seed), initial=initial
    )
    new = CompiledNSGA2Optimizer(**options).minimize(  # type: ignore[arg-type]
        p_new, budget=budget, rng=np.random.default_rng(seed), initial=initial
    )
    return ref, new, p_ref, p_new


def _assert_same(ref: ParetoResult, new: ParetoResult, p_ref: _Recorder, p_new: _Recorder) -> None:
    assert len(p_ref.evaluated) == len(p_new.evaluated)
    for a, b in zip(p_ref.evaluated, p_new.evaluated, strict=True):
        np.testing.assert_array_equal(a, b)  # the same rows, bit for bit, generation by generation
    for name in ("X", "F", "G", "feasible"):
        np.testing.assert_array_equal(getattr(ref, name), getattr(new, name))
    assert ref.n_eval == new.n_eval


# --------------------------------------------------------------------------------------------
# whole runs against pymoo
# --------------------------------------------------------------------------------------------


@needs_libm_numpy
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("concave", [False, True], ids=["ZDT1", "ZDT2"])
def test_zdt_runs_equal_pymoo_and_converge(concave: bool, seed: int) -> None:
    ref, new, p_ref, p_new = _both(lambda: ZDT(concave=concave), 2000, seed, pop_size=40)
    _assert_same(ref, new, p_ref, p_new)
    hv = HV(ref_point=np.array([1.1, 1.1]))
    assert hv(new.F) == hv(ref.F)
    # converging: above random sampling at the same budget, below the true front's hypervolume
    # (ref 1.1, 1.1: 1.21 - 1/3 for ZDT1, 1.21 - 2/3 for ZDT2)
    problem = ZDT(concave=concave)
    F, _ = problem.evaluate(np.random.default_rng(seed).random((2000, problem.n_var)))
    assert hv(F[non_dominated(F)]) < hv(new.F) <= 1.21 - (2.0 / 3.0 if concave else 1.0 / 3.0)


@needs_libm_numpy
@pytest.mark.parametrize(
    ("pop_size", "budget", "seed"), [(24, 240, 0), (40, 360, 1), (7, 100, 2), (3, 5, 3)]
)
def test_constrained_runs_equal_pymoo(pop_size: int, budget: int, seed: int) -> None:
    ref, new, p_ref, p_new = _both(ConstrainedBNH, budget, seed, pop_size=pop_size)
    _assert_same(ref, new, p_ref, p_new)
    assert new.feasible.all()
    assert (new.G <= 0).all()


@needs_libm_numpy
def test_infeasible_problem_returns_pymoos_least_violating_row() -> None:
    ref, new, p_ref, p_new = _both(lambda: ConstrainedBNH(shift=30.0), 200, 4, pop_size=20)
    _assert_same(ref, new, p_ref, p_new)
    assert not new.any_feasible
    assert new.X.shape == (1, 2)
    evaluated = np.vstack(p_new.evaluated)
    cv = violation(ConstrainedBNH(shift=30.0).evaluate(evaluated)[1])
    assert violation(new.G)[0] == cv.min()  # elitist: the least violation ever seen survives


@needs_libm_numpy
def test_operator_parameters_and_warm_start_equal_pymoo() -> None:
    options = {"pop_size": 12, "crossover_eta": 5.0, "crossover_prob": 0.6, "mutation_eta": 8.0}
    _assert_same(*_both(lambda: ZDT(n_var=4), 120, 5, **options))
    initial = np.array([[0.0, 0.0, 0.0, 0.0], [1.5, -1.0, 0.5, 0.5]])  # the second is clipped
    ref, new, p_ref, p_new = _both(lambda: ZDT(n_var=4), 120, 6, initial=initial, pop_size=12)
    _assert_same(ref, new, p_ref, p_new)
    first = p_new.evaluated[0]
    np.testing.assert_array_equal(first[:2], np.clip(initial, 0.0, 1.0))


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


@needs_libm_numpy
@pytest.mark.parametrize("seed", [0, 3])
def test_merge_problem_runs_equal_pymoo(seed: int) -> None:
    """On the HCOMC problem at the default budget (pop 40, 360 rows) the sets are identical."""
    problem = _merge_problem(seed)
    results = [
        opt.minimize(problem, budget=360, rng=np.random.default_rng(seed))
        for opt in (NSGA2Optimizer(pop_size=40), CompiledNSGA2Optimizer(pop_size=40))
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
# kernels against pymoo
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
    np.testing.assert_array_equal(non_dominated_mask(F), rank == 0)
    np.testing.assert_array_equal(non_dominated(F), rank == 0)


@settings(max_examples=150, deadline=None)
@given(_small_sets | arrays(np.float64, st.tuples(st.integers(1, 30), st.integers(1, 4)),
                            elements=st.floats(-1e3, 1e3)))  # fmt: skip
def test_crowding_distance_equals_pymoo(F: FloatArray) -> None:
    expected = get_crowding_function("cd").do(F)
    np.testing.assert_array_equal(crowding_distance(F), expected)


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
    """On any CPU, the compiled NSGA-II's solution quality is pymoo's, paired over seeds on the
    recorded merge problems (:func:`recorded_decisions.assert_quality_matches`: instants 0-4,
    the first of C1-C5, seeds 0-7, the config's budget and population).

    Tolerance: mean hypervolume ratio >= 0.95, and mean best Eq. 19 cost at most 10 % of the
    library's spread above pymoo's. Measured: here (numpy's power is the C library's) the
    runs are pymoo's bit for bit: ratio 1, gap 0; with pymoo's powers put one unit in the last
    place off on 30 % of results (as a SIMD power may be), every pymoo run changes, by at most
    4e-13 in a variable, ratio 1 within 2e-15, gap below 1e-14; with the runs unpaired (pymoo seeded
    1000-1007: runs that share no draws, the worst a divergence could do) ratio 0.996 and gap
    +0.016 against a spread of 0.62 (2.6 %, one standard error 2.8 %).
    """
    assert_quality_matches("nsga2", "nsga2-pymoo")
