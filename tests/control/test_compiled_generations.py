"""NSGA-II's generations on the merge problem in one compiled call equal the Python loop.

:meth:`MergeProblem.nsga2_generations` (:mod:`hcomc.control.hierarchical.search`) runs
:func:`hcomc.optim.nsga2.run_generations` as one compiled loop. Both must make the same rows,
values and draws, bit for bit: the archives (rows, objectives, constraints, violations, in
evaluation order), the final population and the generator's state after are compared on the
recorded planning instants, in every variant of the problem (no vehicle to merge behind,
lateral cooperation admitted, HCOMC+'s mode "none"), from random and warm-started first
populations. The compiled decoding of rows is checked against the rules written with numpy,
and a copy of a problem with other key states (as the merge game makes) against its own
prediction.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import AHEAD, BEHIND, MODE_NONE, decode_rows
from hcomc.control.longitudinal_candidate import with_cooperation
from hcomc.optim.evaluated import EvaluatedRows
from hcomc.optim.nsga2 import CompiledGenerations, Generations, run_generations
from hcomc.optim.variation import Bounds
from recorded_decisions import MODE_EDGES, problem_variants, recorded_problem, threshold_rows


def _first(problem: MergeProblem, n: int, seed: int) -> np.ndarray:
    """``n`` first rows (:func:`threshold_rows`), two of them equal, as a warm start can repeat
    a row."""
    X = threshold_rows(problem, n, seed)
    X[1] = X[0]
    return X


def _run(
    problem: MergeProblem, first: np.ndarray, plan: Generations, seed: int, compiled: bool
) -> tuple[EvaluatedRows, np.ndarray, np.random.Generator]:
    """The archive, the final rows and the generator of one run of the generations."""
    archive = EvaluatedRows(problem, first.shape[0] + (plan.n_gen - 1) * plan.pop_size)
    rng = np.random.default_rng(seed)
    if compiled:
        rows = problem.nsga2_generations(archive, first, plan, rng)
    else:
        rows = run_generations(archive, first, plan, rng)
    return archive, rows, rng


@pytest.mark.parametrize("index", [0, 9, 23, 38, 51])
@pytest.mark.parametrize("variant", range(4))
def test_compiled_generations_equal_the_python_loop(index: int, variant: int) -> None:
    problem = problem_variants(recorded_problem(index))[variant]
    assert isinstance(problem, CompiledGenerations)
    bounds = Bounds(np.asarray(problem.xl, dtype=float), np.asarray(problem.xu, dtype=float))
    for seed, (pop_size, n_gen, n_first) in enumerate([(12, 4, 12), (10, 3, 7), (8, 1, 8)]):
        plan = Generations(n_gen, pop_size, pop_size // 2, bounds, (15.0, 0.9), (20.0, 0.9))
        first = _first(problem, n_first, 100 * index + seed)
        a, rows_a, rng_a = _run(problem, first, plan, seed, compiled=True)
        b, rows_b, rng_b = _run(problem, first, plan, seed, compiled=False)
        assert a.size == b.size == first.shape[0] + (n_gen - 1) * pop_size
        np.testing.assert_array_equal(rows_a, rows_b)
        for name in ("X", "F", "G", "cv"):
            assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name
        assert rng_a.bit_generator.state == rng_b.bit_generator.state


def _decoded_by_numpy(
    X: np.ndarray, no_cooperation: bool, has_behind: bool
) -> tuple[np.ndarray, ...]:
    """The rules of the decision vector (problem module docstring) with numpy's masks."""
    seq = np.where(X[:, 4] >= 0.5, BEHIND, AHEAD)
    none = (X[:, 3] >= MODE_NONE) & no_cooperation
    lateral = (X[:, 3] >= 0.5) & ~none
    seq[lateral] = AHEAD
    no_behind = (seq == BEHIND) & (not has_behind)
    seq[no_behind] = AHEAD
    return seq, lateral, seq + 2 * none, no_behind


@settings(max_examples=60, deadline=None)
@given(
    values=st.lists(
        st.tuples(
            st.sampled_from([*MODE_EDGES.tolist(), np.nan]), st.sampled_from(MODE_EDGES.tolist())
        ),
        min_size=1,
        max_size=20,
    ),
    no_cooperation=st.booleans(),
    has_behind=st.booleans(),
)
def test_decode_rows_follows_the_rules_of_the_decision_vector(
    values: list[tuple[float, float]], no_cooperation: bool, has_behind: bool
) -> None:
    X = np.zeros((len(values), 5))
    X[:, 3:] = values
    got = decode_rows(X, no_cooperation, has_behind)
    for a, b in zip(got, _decoded_by_numpy(X, no_cooperation, has_behind), strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_copy_with_other_key_states_scores_its_own_states() -> None:
    problem = recorded_problem(4)
    X = _first(problem, 16, 4)
    problem.evaluate(X)  # the original's scoring constants are prepared
    for cooperates in (False, True):
        copy = with_cooperation(problem, cooperates)
        F, G = copy.evaluate(X)
        prediction = copy.predict(X)
        assert F.tobytes() == prediction.F.tobytes()
        assert G.tobytes() == prediction.G.tobytes()
    F_after, _ = problem.evaluate(X)
    assert F_after.tobytes() == problem.predict(X).F.tobytes()


def test_an_archive_of_whole_rows_is_filled_by_the_python_loop() -> None:
    """An archive that compares whole rows (its keys are its rows) is left to the Python
    loop: its canonical keys would overwrite the rows, and its duplicates are not those of
    canonical rows. The rows and values it ends with are those of the loop."""
    problem = recorded_problem(2)
    bounds = Bounds(np.asarray(problem.xl, dtype=float), np.asarray(problem.xu, dtype=float))
    plan = Generations(3, 8, 4, bounds, (15.0, 0.9), (20.0, 0.9))
    first = _first(problem, 8, 0)
    runs = []
    for compiled in (True, False):
        archive = EvaluatedRows(problem, 8 + 2 * 8)
        archive._canonical, archive._keys = None, archive.X  # as for a problem of whole rows
        rng = np.random.default_rng(1)
        run = problem.nsga2_generations if compiled else run_generations
        runs.append((run(archive, first, plan, rng), archive))
    (rows_a, a), (rows_b, b) = runs
    np.testing.assert_array_equal(rows_a, rows_b)
    for name in ("X", "F", "G", "cv"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name
