"""The rows an NSGA-II run evaluated (hcomc.optim.evaluated): each distinct row evaluated once,
found by its bits, against a dictionary of the rows' bytes as the oracle; for a problem with
canonical rows, each distinct canonical row."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from hcomc._typing import FloatArray
from hcomc.optim.base import CanonicalProblem
from hcomc.optim.evaluated import EvaluatedRows, admit_rows, violation

# few values, signed zeros among them: repeated rows are common, and 0.0 and -0.0 differ in bits
_ROWS = arrays(np.float64, st.tuples(st.integers(1, 40), st.integers(1, 4)),
               elements=st.sampled_from([0.0, -0.0, 1.0, 2.5, np.inf]))  # fmt: skip


def _first_by_bytes(X: FloatArray) -> list[int]:
    """The earliest row with the same bytes as each row (the oracle)."""
    seen: dict[bytes, int] = {}
    return [seen.setdefault(row.tobytes(), r) for r, row in enumerate(X)]


@settings(max_examples=200, deadline=None)
@given(X=_ROWS, cut=st.integers(0, 40), table_bits=st.integers(0, 3))
def test_admit_rows_finds_the_first_equal_row(X: FloatArray, cut: int, table_bits: int) -> None:
    n = X.shape[0]
    # the least table that holds every row, or a few times more: few places, many collisions
    table = np.full(1 << (n.bit_length() + table_bits), -1, dtype=np.int64)
    first, fresh = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    cut = min(cut, n)
    m = admit_rows(X, 0, cut, table, first, fresh)  # two batches, as two generations
    m2 = admit_rows(X, cut, n, table, first, fresh[m:])
    expected = _first_by_bytes(X)
    assert first.tolist() == expected
    new = [r for r in range(n) if expected[r] == r]
    assert fresh[: m + m2].tolist() == new
    assert np.count_nonzero(table >= 0) == len(new)


class _Counting:
    """A two-objective problem that records the rows it is asked to evaluate."""

    n_var, n_obj, n_constr = 2, 2, 2
    xl, xu = np.zeros(2), np.ones(2)
    objective_names = ("f1", "f2")

    def __init__(self) -> None:
        self.asked: list[FloatArray] = []

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        self.asked.append(X.copy())
        return X + 1.0, np.column_stack([X[:, 0] - 0.5, -X[:, 1]])

    def scalarise(self, F: FloatArray, G: FloatArray) -> FloatArray:
        return F.sum(axis=1)


def test_repeated_rows_take_the_values_of_their_first_evaluation() -> None:
    problem = _Counting()
    rows = EvaluatedRows(problem, 6)  # type: ignore[arg-type]
    first = np.array([[0.25, 0.5], [0.75, 0.0], [0.25, 0.5]])
    second = np.array([[0.75, 0.0], [0.75, -0.0], [0.25, 0.5]])
    np.testing.assert_array_equal(rows.add(first), [0, 1, 2])
    np.testing.assert_array_equal(rows.add(second), [3, 4, 5])
    # evaluated: each distinct row once, in order (-0.0 is a row of its own)
    np.testing.assert_array_equal(np.concatenate(problem.asked),
                                  [[0.25, 0.5], [0.75, 0.0], [0.75, -0.0]])  # fmt: skip
    X = np.concatenate([first, second])
    np.testing.assert_array_equal(rows.X, X)
    F, G = problem.evaluate(X)
    np.testing.assert_array_equal(rows.F, F)
    np.testing.assert_array_equal(rows.G, G)
    np.testing.assert_array_equal(rows.cv, np.maximum(G[:, 0], 0.0) + np.maximum(G[:, 1], 0.0))
    assert rows.size == 6


def test_violation_sums_positive_parts_in_column_order() -> None:
    G = np.array([[1e16, 1.0, -1e16], [-1.0, -2.0, -0.0], [np.nan, 1.0, 2.0], [-np.inf, 3.0, 0.5]])
    expected = np.zeros(4)
    for j in range(G.shape[1]):
        expected += np.maximum(0.0, G[:, j])
    np.testing.assert_array_equal(violation(G), expected)


class _Thresholded(_Counting):
    """:class:`_Counting` whose second variable counts only as ``>= 0.5`` or not (its values
    use the canonical row), a :class:`~hcomc.optim.base.CanonicalProblem`."""

    def canonical_rows(self, X: FloatArray) -> FloatArray:
        out = np.array(X, dtype=np.float64)
        out[:, 1] = np.where(X[:, 1] >= 0.5, 1.0, 0.0)
        return out

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        return super().evaluate(self.canonical_rows(X))


def test_rows_with_equal_canonical_rows_are_evaluated_once() -> None:
    problem = _Thresholded()
    assert isinstance(problem, CanonicalProblem)
    assert not isinstance(_Counting(), CanonicalProblem)
    rows = EvaluatedRows(problem, 6)  # type: ignore[arg-type]
    first = np.array([[0.25, 0.5], [0.75, 0.1], [0.25, 0.9]])
    second = np.array([[0.75, 0.0], [0.25, 0.49], [0.75, 0.6]])
    rows.add(first)
    rows.add(second)
    # canonical rows (0.25, 1), (0.75, 0), (0.25, 0), (0.75, 1): each evaluated once, as given
    np.testing.assert_array_equal(np.concatenate(problem.asked),
                                  [[0.25, 1.0], [0.75, 0.0], [0.25, 0.0], [0.75, 1.0]])  # fmt: skip
    X = np.concatenate([first, second])
    np.testing.assert_array_equal(rows.X, X)  # the rows themselves are kept
    F, G = problem.evaluate(X)
    np.testing.assert_array_equal(rows.F, F)
    np.testing.assert_array_equal(rows.G, G)
