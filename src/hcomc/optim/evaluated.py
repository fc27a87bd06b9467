"""The rows an NSGA-II run evaluated, each distinct row evaluated once.

:class:`EvaluatedRows` keeps every row a run evaluated, in evaluation order, with its
objectives, constraints and violation. A row equal to one evaluated earlier (an offspring that
neither crossed nor mutated: about 5 % of the merge problem's rows) takes that row's values
instead of a second evaluation, the same numbers, since a problem's values are a function of the
row alone; it still counts as evaluated (in the budget and in ``n_eval``), as in pymoo without
duplicate elimination. "Equal" is equal in every bit (as the rows' bytes compare), found through
an open-addressing hash table of the rows' bit patterns (:func:`admit_rows`), so that a
generation's bookkeeping is two compiled calls around the problem's evaluation. For a
:class:`~hcomc.optim.base.CanonicalProblem` the canonical rows are compared: the merge
problem's rows that differ only where its mode and sequence variables select the same (7 % of
its rows) are rolled out once.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import FloatArray, IntArray
from hcomc.optim.base import CanonicalProblem, Problem

_EMPTY = -1  # a free place of the hash table


@kernel
def violation_into(G: np.ndarray, out: np.ndarray) -> None:
    """``out[r] = sum_j max(0, G[r, j])``, summed in column order from 0 (NaN propagates, as
    numpy's ``maximum`` does): the value does not depend on how a library orders a
    reduction."""
    for r in range(G.shape[0]):
        total = 0.0
        for j in range(G.shape[1]):
            g = G[r, j]
            total += g if g > 0.0 or math.isnan(g) else 0.0
        out[r] = total


def violation(G: FloatArray) -> FloatArray:
    """Constraint violation per row, ``sum(max(0, G))`` (0: feasible;
    :func:`violation_into`)."""
    out = np.empty(G.shape[0])
    violation_into(np.ascontiguousarray(G, dtype=np.float64), out)
    return out


@kernel(inline="always")
def _row_hash(bits: np.ndarray) -> np.uint64:
    """A 64-bit hash of one row's bit patterns (FNV-1a over the words, then a final mix)."""
    h = np.uint64(14695981039346656037)
    for w in bits:
        h = (h ^ w) * np.uint64(1099511628211)
    return h ^ (h >> np.uint64(29))


@kernel(inline="always")
def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two rows' bit patterns are equal."""
    j = 0
    while j < a.size and a[j] == b[j]:
        j += 1
    return j == a.size


@kernel
def admit_rows(
    X: np.ndarray, start: int, end: int, table: np.ndarray, first: np.ndarray, fresh: np.ndarray
) -> int:
    """Rows ``[start, end)`` of ``X`` against every earlier row: ``first[r]`` is the earliest
    row bitwise equal to row r (r itself for a new row), and the new rows go to ``fresh``,
    in order; returns their number. ``table`` is the hash table of the rows seen so far
    (a power of two in size, more than the rows; :data:`_EMPTY` where free)."""
    bits = X.view(np.uint64)
    mask = table.size - 1
    n_fresh = 0
    for r in range(start, end):
        place = np.int64(_row_hash(bits[r]) & np.uint64(mask))
        while True:
            p = table[place]
            if p == _EMPTY:
                table[place], first[r] = r, r
                fresh[n_fresh] = r
                n_fresh += 1
                break
            if _same(bits[p], bits[r]):
                first[r] = p
                break
            place = (place + 1) & mask
    return n_fresh


@kernel
def settle_rows(
    F: np.ndarray, G: np.ndarray, cv: np.ndarray, first: np.ndarray, start: int, end: int
) -> None:
    """Rows ``[start, end)``: a repeated row takes the values of its first occurrence, and
    every row its violation (:func:`violation_into`)."""
    for r in range(start, end):
        p = first[r]
        if p != r:
            F[r, :] = F[p, :]
            G[r, :] = G[p, :]
    violation_into(G[start:end], cv[start:end])


class ArchiveArrays(NamedTuple):
    """The arrays of an :class:`EvaluatedRows`, as compiled code that fills it takes them."""

    X: np.ndarray  # (n_rows, n_var) the rows, in evaluation order
    F: np.ndarray  # (n_rows, n_obj) their objectives
    G: np.ndarray  # (n_rows, n_constr) their constraints
    cv: np.ndarray  # (n_rows,) their violation
    keys: np.ndarray  # (n_rows, n_var) what is compared: the rows, or their canonical rows
    table: np.ndarray  # the hash table of :func:`admit_rows`
    first: np.ndarray  # (n_rows,) the earliest equal row of each row (admit_rows)
    fresh: np.ndarray  # (n_rows,) work space: the new rows of an admission


class EvaluatedRows:
    """Every row a run evaluated, in evaluation order: ``X``, ``F``, ``G`` and the violation
    ``cv``, their first ``size`` rows (module docstring); all its arrays in ``arrays``."""

    def __init__(self, problem: Problem, n_rows: int) -> None:
        self.problem = problem
        self.n_obj, self.n_constr = int(problem.n_obj), int(problem.n_constr)
        self.X, self.F = np.empty((n_rows, int(problem.n_var))), np.empty((n_rows, self.n_obj))
        self.G, self.cv = np.empty((n_rows, self.n_constr)), np.empty(n_rows)
        self.size = 0
        self._first = np.empty(n_rows, dtype=np.int64)
        self._fresh = np.empty(n_rows, dtype=np.int64)
        self._table = np.full(1 << (2 * n_rows).bit_length(), _EMPTY, dtype=np.int64)
        self._canonical = problem.canonical_rows if isinstance(problem, CanonicalProblem) else None
        self._keys = self.X if self._canonical is None else np.empty_like(self.X)  # compared

    @property
    def arrays(self) -> ArchiveArrays:
        """Every array of the archive, as compiled code that fills it takes them."""
        return ArchiveArrays(self.X, self.F, self.G, self.cv, self._keys, self._table,
                             self._first, self._fresh)  # fmt: skip

    def add(self, X: FloatArray) -> IntArray:
        """Evaluate the rows ``X`` into the archive's next rows; their archive rows."""
        start, end = self.size, self.size + X.shape[0]
        self.X[start:end] = X
        if self._canonical is not None:
            self._keys[start:end] = self._canonical(X)
        n = admit_rows(self._keys, start, end, self._table, self._first, self._fresh)
        if n:
            fresh = self._fresh[:n]
            F, G = self.problem.evaluate(X if n == X.shape[0] else self.X[fresh])
            self.F[fresh] = np.asarray(F, dtype=np.float64).reshape(n, self.n_obj)
            self.G[fresh] = np.asarray(G, dtype=np.float64).reshape(n, self.n_constr)
        settle_rows(self.F, self.G, self.cv, self._first, start, end)
        self.size = end
        return np.arange(start, end)


@functools.cache  # once per process
def warm_up() -> None:
    """Compile (or load from numba's cache) every kernel of this module now."""
    X = np.zeros((2, 1))
    table, first = np.full(8, _EMPTY, dtype=np.int64), np.empty(2, dtype=np.int64)
    admit_rows(X, 0, 2, table, first, np.empty(2, dtype=np.int64))
    settle_rows(np.zeros((2, 1)), np.zeros((2, 1)), np.empty(2), first, 0, 2)
