"""The merge problem's canonical rows: a row and its canonical row have the same values.

:meth:`MergeProblem.canonical_rows` sets the mode and sequence variables (3 and 4) to one value
of what they select, so that NSGA-II's archive rolls out once the rows that differ only there
(:class:`hcomc.optim.evaluated.EvaluatedRows`). That is exact only if a row's objectives and
constraints are those of its canonical row bit for bit, in every variant of the problem (both
sequences, no vehicle to merge behind, lateral cooperation admitted or not, HCOMC+'s mode
"none"), which is checked here on the recorded planning instants, rows at the 0.5 and 1.0
thresholds included; and a decision is the same with and without the canonical comparison.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc.control.hierarchical.controller import HCOMCController, HCOMCDetails
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.optim import evaluated
from hcomc.optim.base import CanonicalProblem
from recorded_decisions import (
    problem_variants,
    recorded_instants,
    recorded_problem,
    threshold_rows,
)


def _assert_same_values(problem: MergeProblem, X: np.ndarray) -> None:
    C = problem.canonical_rows(X)
    np.testing.assert_array_equal(C[:, :3], X[:, :3])
    np.testing.assert_array_equal(problem.canonical_rows(C), C)  # a canonical row is its own
    for a, b in zip(problem._rows(X), problem._rows(C), strict=True):
        np.testing.assert_array_equal(a, b)
    F, G = problem.evaluate(X)
    F_c, G_c = problem.evaluate(C)
    assert F.tobytes() == F_c.tobytes()
    assert G.tobytes() == G_c.tobytes()


def test_the_merge_problem_is_canonical() -> None:
    assert isinstance(recorded_problem(0), CanonicalProblem)


@pytest.mark.parametrize("index", [0, 9, 23, 38, 52])
def test_rows_and_their_canonical_rows_have_the_same_values(index: int) -> None:
    for k, problem in enumerate(problem_variants(recorded_problem(index))):
        _assert_same_values(problem, threshold_rows(problem, 120, seed=100 * index + k))


@settings(max_examples=60, deadline=None)
@given(index=st.integers(0, 59), variant=st.integers(0, 3), seed=st.integers(0, 2**16))
def test_any_rows_have_the_values_of_their_canonical_rows(
    index: int, variant: int, seed: int
) -> None:
    problem = problem_variants(recorded_problem(index))[variant]
    _assert_same_values(problem, threshold_rows(problem, 8, seed))


def test_a_decision_is_the_same_with_and_without_canonical_rows(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _, config, view, group = recorded_instants()[17]
    plans = [HCOMCController(config).plan(view, group, np.random.default_rng(2))]
    monkeypatch.setattr(evaluated, "CanonicalProblem", type("Never", (), {}))
    plans.append(HCOMCController(config).plan(view, group, np.random.default_rng(2)))
    a, b = plans
    assert isinstance(a.details, HCOMCDetails)
    assert isinstance(b.details, HCOMCDetails)
    assert (a.mode, a.sequence, a.fallback, a.objectives) == (b.mode, b.sequence, b.fallback,
                                                             b.objectives)  # fmt: skip
    for x, y in ((a.vv0, b.vv0), (a.vv1, b.vv1), ([a.merge_x, a.horizon], [b.merge_x, b.horizon])):
        assert np.asarray(x).tobytes() == np.asarray(y).tobytes()
    for name in ("X", "F", "G"):
        pa, pb = getattr(a.details.pareto, name), getattr(b.details.pareto, name)
        assert pa.tobytes() == pb.tobytes(), name
