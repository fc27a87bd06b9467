"""The compiled NSGA-II's generation steps against pymoo's operators, one step at a time.

Each step of a generation (rank-and-crowding survival with the tournaments that follow, SBX with
polynomial mutation, the archive's Pareto set) is compared with the pymoo operator it reproduces,
or with the code it replaced, on random inputs rich in ties, from the same generator state:
the same decisions and the same generator state after. The variation operators take powers with
the C library's ``pow`` (the same on every processor), pymoo with numpy's (chosen by the CPU at
run time): their offspring are held to pymoo's within a relative 1e-12; the quality of whole
runs is tested in ``test_nsga2_compiled.py``.
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from pymoo.algorithms.moo.nsga2 import binary_tournament
from pymoo.core.population import Population as PymooPopulation
from pymoo.core.problem import Problem as PymooProblem
from pymoo.operators.crossover.sbx import SBX
from pymoo.operators.mutation.pm import PM
from pymoo.operators.selection.tournament import TournamentSelection
from pymoo.operators.survival.rank_and_crowding import RankAndCrowding

from hcomc._typing import FloatArray, IntArray
from hcomc.equations.pareto import pareto_optimal
from hcomc.optim import variation
from hcomc.optim.base import archive_front
from hcomc.optim.evaluated import violation
from hcomc.optim.nsga2 import survive_and_mate
from hcomc.optim.variation import offspring, polynomial_mutation


def _same_state(a: np.random.Generator, b: np.random.Generator) -> None:
    """Both generators have drawn exactly the same numbers."""
    assert a.bit_generator.state == b.bit_generator.state


# --------------------------------------------------------------------------------------------
# powers
# --------------------------------------------------------------------------------------------


def _c_power(base: float, exponent: float) -> float:
    """``base ** exponent`` by the C library's ``pow`` (Python's ``math.pow``), with its special
    values where Python raises: inf for 0 to a negative power or an overflow, NaN for a negative
    base to a non-integer power."""
    try:
        return math.pow(base, exponent)
    except OverflowError:
        return math.inf
    except ValueError:
        return math.inf if base == 0.0 else math.nan


def test_kernel_powers_are_the_c_librarys() -> None:
    """The operators' powers are the C library's ``pow``, whatever numpy's ``power`` is."""
    rng = np.random.default_rng(3)
    base = np.concatenate([rng.random(2000), 1.0 + rng.random(2000) * 50.0,
                           [0.0, 1.0, np.inf, np.nan, -1.5, 1e-300, 1e300]])  # fmt: skip
    for exponent in (-16.0, 1.0 / 16.0, 21.0, 1.0 / 21.0, 0.5, 2.0, -7.3, 31.0):
        expected = [_c_power(b, exponent) for b in base.tolist()]
        np.testing.assert_array_equal(variation._power(base, exponent), expected)


# --------------------------------------------------------------------------------------------
# variation against pymoo's SBX and PM
# --------------------------------------------------------------------------------------------


def _bounds(n_var: int, rng: np.random.Generator) -> tuple[FloatArray, FloatArray]:
    xl = -rng.random(n_var) * 3.0
    xu = xl + rng.random(n_var) * 5.0
    same = rng.random(n_var) < 0.15
    xu[same] = xl[same]  # coinciding bounds: never crossed nor mutated
    return xl, xu


def _parents(
    n_matings: int, xl: FloatArray, xu: FloatArray, rng: np.random.Generator
) -> FloatArray:
    X = xl + (xu - xl) * rng.random((2, n_matings, xl.size))
    same = rng.random(n_matings) < 0.2
    X[1, same] = X[0, same]  # equal parents: never crossed
    X[:, rng.random(n_matings) < 0.2, 0] = xl[0]  # on a bound
    return X


def _assert_close(got: FloatArray, expected: FloatArray, xl: FloatArray, xu: FloatArray) -> None:
    """Offspring within 1e-12 of the box's width of pymoo's, per variable (the same crossed and
    mutated variables: another decision would move a value by far more)."""
    assert got.shape == expected.shape
    gap = np.abs(got - expected)
    assert (gap <= 1e-12 * (xu - xl)).all(), f"largest difference {gap.max():.3g}"


@pytest.mark.parametrize("seed", range(12))
def test_offspring_equal_pymoo_sbx_then_pm(seed: int) -> None:
    setup = np.random.default_rng(seed)
    n_var, n_matings = int(setup.integers(1, 7)), int(setup.integers(1, 13))
    xl, xu = _bounds(n_var, setup)
    X = _parents(n_matings, xl, xu, setup)
    crossover = (float(setup.uniform(2.0, 30.0)), float(setup.choice([0.0, 0.5, 0.9, 1.0])))
    mutation = (float(setup.uniform(2.0, 30.0)), float(setup.choice([0.0, 0.6, 0.9, 1.0])))
    problem = PymooProblem(n_var=n_var, n_obj=1, xl=xl, xu=xu)
    pop = PymooPopulation.new(X=np.vstack([X[0], X[1]]))
    pairs = np.column_stack([np.arange(n_matings), n_matings + np.arange(n_matings)])
    ref_rng, new_rng = np.random.default_rng(seed + 100), np.random.default_rng(seed + 100)
    children = SBX(eta=crossover[0], prob=crossover[1]).do(
        problem, pop, pairs, random_state=ref_rng
    )
    expected = (
        PM(eta=mutation[0], prob=mutation[1]).do(problem, children, random_state=ref_rng).get("X")
    )
    got = offspring(X, xl, xu, crossover, mutation, new_rng)
    _assert_close(got, expected, xl, xu)
    _same_state(ref_rng, new_rng)


@pytest.mark.parametrize("seed", range(8))
def test_polynomial_mutation_equals_pymoo_pm(seed: int) -> None:
    setup = np.random.default_rng(seed)
    n_var, n = int(setup.integers(1, 7)), int(setup.choice([1, 1, 5, 24]))  # PSO mutates one row
    xl, xu = _bounds(n_var, setup)
    X = xl + (xu - xl) * setup.random((n, n_var))
    eta, prob = float(setup.uniform(5.0, 30.0)), float(setup.choice([0.5, 0.9, 1.0]))
    problem = PymooProblem(n_var=n_var, n_obj=1, xl=xl, xu=xu)
    ref_rng, new_rng = np.random.default_rng(seed), np.random.default_rng(seed)
    expected = (
        PM(eta=eta, prob=prob)
        .do(problem, PymooPopulation.new(X=X.copy()), random_state=ref_rng)
        .get("X")
    )
    _assert_close(polynomial_mutation(X, xl, xu, eta, prob, new_rng), expected, xl, xu)
    _same_state(ref_rng, new_rng)


# --------------------------------------------------------------------------------------------
# survival and selection against pymoo's RankAndCrowding and TournamentSelection
# --------------------------------------------------------------------------------------------


def _pymoo_survive_and_mate(
    F: FloatArray, G: FloatArray, n_survive: int, n_matings: int, rng: np.random.Generator
) -> tuple[IntArray, IntArray]:
    """pymoo's survivors (indices of rows) and their parents (positions among the survivors)."""
    n = F.shape[0]
    problem = PymooProblem(n_var=1, n_obj=F.shape[1], n_ieq_constr=G.shape[1], xl=0.0, xu=1.0)
    pop = PymooPopulation.new(X=np.arange(n, dtype=float)[:, None], F=F, G=G)  # pymoo's CV
    survivors = RankAndCrowding().do(problem, pop, n_survive=n_survive, random_state=rng)
    rows = survivors.get("X")[:, 0].astype(np.int64)
    if n_matings == 0:
        return rows, np.empty((0, 2), dtype=np.int64)
    algorithm = SimpleNamespace(tournament_type="comp_by_dom_and_crowding", random_state=rng)
    parents = TournamentSelection(func_comp=binary_tournament).do(
        problem, survivors, n_matings, 2, to_pop=False, random_state=rng, algorithm=algorithm
    )
    return rows, parents.astype(np.int64)


@pytest.fixture
def stable_ties(monkeypatch: pytest.MonkeyPatch) -> None:
    """pymoo's sorts (``np.argsort``, quicksort) with ties in a stable order, as the compiled
    NSGA-II orders them: numpy's quicksort orders equal keys by the CPU (its AVX-512 sort
    differently from its portable one), so pymoo's own survivors depend on the machine."""
    argsort = np.argsort

    def stable(a: Any, axis: int = -1, kind: str | None = None, **options: Any) -> Any:
        return argsort(a, axis=axis, kind="stable", **options)

    monkeypatch.setattr(np, "argsort", stable)


@pytest.mark.parametrize("seed", range(40))
@pytest.mark.usefixtures("stable_ties")
def test_survive_and_mate_equal_pymoo(seed: int) -> None:
    setup = np.random.default_rng(seed)
    n, n_obj, n_constr = int(setup.integers(2, 60)), int(setup.integers(1, 4)), int(seed % 3)
    F = setup.integers(0, 4, (n, n_obj)).astype(float)  # few values: ties in every rule
    G = setup.integers(-3, 2, (n, n_constr)).astype(float) * (setup.random((n, n_constr)) < 0.4)
    n_survive = int(setup.integers(1, n + 1))
    n_matings = int(setup.integers(0, 2 * n_survive + 1))
    ref_rng, new_rng = np.random.default_rng(seed), np.random.default_rng(seed)
    rows, parents = _pymoo_survive_and_mate(F, G, n_survive, n_matings, ref_rng)
    idx, mates, _, _ = survive_and_mate(
        F, violation(G), np.arange(n), n_survive, n_matings, new_rng
    )
    np.testing.assert_array_equal(idx, rows)
    np.testing.assert_array_equal(mates, parents)
    _same_state(ref_rng, new_rng)


def test_survive_and_mate_reads_the_population_through_rows() -> None:
    """Rows of a larger archive in any order: the same decisions as on the gathered rows."""
    setup = np.random.default_rng(5)
    F, cv = setup.integers(0, 3, (50, 2)).astype(float), setup.integers(0, 2, 50) * 0.5
    rows = setup.permutation(50)[:30]
    a = survive_and_mate(F, cv, rows, 12, 6, np.random.default_rng(1))
    b = survive_and_mate(F[rows], cv[rows], np.arange(30), 12, 6, np.random.default_rng(1))
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


# --------------------------------------------------------------------------------------------
# the archive's Pareto set against the code it replaced
# --------------------------------------------------------------------------------------------


def _archive_front_by_sorting(F: FloatArray, G: FloatArray) -> IntArray:
    """The replaced code: feasible rows, their non-dominated mask, then numpy's unique rows."""
    rows = np.flatnonzero(np.all(G <= 0.0, axis=1))
    if rows.size == 0:
        return rows
    rows = rows[pareto_optimal(F[rows])]
    _, distinct = np.unique(F[rows], axis=0, return_index=True)
    return rows[np.sort(distinct)]


_values = st.sampled_from([0.0, -0.0, 1.0, 2.0, 3.0, np.inf, -np.inf, np.nan])


@settings(max_examples=300, deadline=None)
@given(
    st.integers(0, 40).flatmap(
        lambda n: st.tuples(
            arrays(np.float64, st.tuples(st.just(n), st.integers(1, 3)), elements=_values),
            arrays(np.float64, st.tuples(st.just(n), st.integers(0, 2)),
                   elements=st.sampled_from([-1.0, 0.0, -0.0, 0.5, np.nan])),
        )
    )
)  # fmt: skip
def test_archive_front_equals_sorting_unique_rows(FG: tuple[FloatArray, FloatArray]) -> None:
    F, G = FG
    np.testing.assert_array_equal(archive_front(F, G), _archive_front_by_sorting(F, G))


def test_archive_front_on_continuous_values() -> None:
    rng = np.random.default_rng(2)
    F = rng.random((400, 3))
    F[rng.integers(0, 400, 40)] = F[rng.integers(0, 400, 40)]  # duplicates
    G = rng.random((400, 2)) - 0.3
    np.testing.assert_array_equal(archive_front(F, G), _archive_front_by_sorting(F, G))
