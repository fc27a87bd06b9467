"""NSGA-II's generations on the merge problem in one compiled call.

:class:`~hcomc.optim.nsga2.CompiledNSGA2Optimizer` runs a problem's generations in Python
(:func:`hcomc.optim.nsga2.run_generations`): between two compiled scorings of a population it
returns to Python for the survivors and their offspring, the archive's admission of the new
rows and the problem's evaluation of those it has not seen. On the merge problem every one of
these steps is compiled already: NSGA-II's (:func:`hcomc.optim.nsga2.next_generation`), the
archive's (:func:`hcomc.optim.evaluated.admit_rows`, :func:`~hcomc.optim.evaluated.
settle_rows`), the problem's canonical rows and what a row selects
(:mod:`~hcomc.control.hierarchical.problem_terms`) and its rows' scoring
(:mod:`~hcomc.control.hierarchical.row_scoring`). :func:`nsga2_generations` runs them as one
compiled loop that makes the same calls in the same order, so that a decision returns to
Python once instead of twice a generation: the same rows, values and draws, bit for bit (the
tests compare both loops on the recorded planning instants). It is the merge problem's
:class:`~hcomc.optim.nsga2.CompiledGenerations`.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np

from hcomc._jit import kernel
from hcomc._typing import BoolArray, FloatArray, IntArray
from hcomc.control.hierarchical.problem_terms import (
    BEHIND,
    CONSTRAINTS,
    KeyState,
    canonical_form,
    decode_rows,
)
from hcomc.control.hierarchical.row_scoring import (
    RowConstants,
    score_rows_on,
    scoring_threads,
)
from hcomc.optim.evaluated import ArchiveArrays, EvaluatedRows, admit_rows, settle_rows
from hcomc.optim.nsga2 import Generations, next_generation, run_generations
from hcomc.optim.variation import Bounds

__all__ = [
    "Scoring",
    "SearchedProblem",
    "admit_and_score",
    "generations",
    "nsga2_generations",
    "warm_up",
]


class SearchedProblem(Protocol):
    """What :func:`nsga2_generations` reads of a merge problem
    (:class:`~hcomc.control.hierarchical.problem.MergeProblem`)."""

    no_cooperation: bool  # HCOMC+: the mode "none" exists
    states: tuple[KeyState, KeyState | None]  # the key groups ahead and behind

    def scoring(self) -> tuple[tuple[RowConstants, ...], BoolArray, BoolArray]:
        """The variants' constants, which exist, and the sequences' lateral admission."""
        ...


class Scoring(NamedTuple):
    """What the scoring of a merge problem's rows takes from the problem (the arguments of
    :func:`~hcomc.control.hierarchical.row_scoring.score_rows` that do not change from one
    population to the next) and what its rows' decoding takes."""

    ahead: RowConstants  # the variants' constants handles (sequence + 2 for mode "none")
    behind: RowConstants
    ahead_none: RowConstants
    behind_none: RowConstants
    scored: np.ndarray  # (4,) which variants exist
    allowed: np.ndarray  # (2,) per sequence, whether it admits lateral cooperation
    no_cooperation: bool  # HCOMC+: the mode "none" exists
    has_behind: bool  # a vehicle to merge behind exists


@kernel
def admit_and_score(
    archive: ArchiveArrays, start: int, end: int, scoring: Scoring, n_parts: int
) -> None:
    """:meth:`EvaluatedRows.add <hcomc.optim.evaluated.EvaluatedRows.add>` of the archive's
    rows ``[start, end)`` (already in ``archive.X``), compiled: their canonical rows, their
    admission, the new rows scored as :meth:`MergeProblem.evaluate
    <hcomc.control.hierarchical.problem.MergeProblem.evaluate>` scores them (on
    ``min(n_parts, new rows)`` threads), then every row's values settled."""
    X, F, G, c = archive.X, archive.F, archive.G, scoring
    archive.keys[start:end] = canonical_form(X[start:end], c.no_cooperation, c.has_behind)
    n = admit_rows(archive.keys, start, end, archive.table, archive.first, archive.fresh)
    if n > 0:
        fresh = archive.fresh[:n]
        rows = np.empty((n, X.shape[1]))
        for q in range(n):
            rows[q] = X[fresh[q]]
        _, lateral, variant, no_behind = decode_rows(rows, c.no_cooperation, c.has_behind)
        F_new, G_new = np.zeros((n, F.shape[1])), np.zeros((n, G.shape[1]))
        score_rows_on(c.ahead, c.behind, c.ahead_none, c.behind_none, c.scored, c.allowed, rows,
                      variant, lateral, no_behind, F_new, G_new, min(n_parts, n))  # fmt: skip
        for q in range(n):
            F[fresh[q]], G[fresh[q]] = F_new[q], G_new[q]
    settle_rows(F, G, archive.cv, archive.first, start, end)


@kernel
def generations(
    archive: ArchiveArrays, first: np.ndarray, plan: Generations, rng: np.random.Generator,
    scoring: Scoring, n_parts: int,
) -> tuple[np.ndarray, int]:  # fmt: skip
    """:func:`hcomc.optim.nsga2.run_generations` compiled, its rows admitted and scored by
    :func:`admit_and_score`: the final population's rows and the archive's rows used."""
    X, size = archive.X, first.shape[0]
    X[:size] = first
    admit_and_score(archive, 0, size, scoring, n_parts)
    rows = np.arange(size)
    for g in range(plan.n_gen):
        mate = plan.n_matings if g < plan.n_gen - 1 else 0  # the last survivors do not mate
        rows, children = next_generation(X, archive.F, archive.cv, rows, plan.pop_size, mate,
                                         plan.bounds, plan.crossover, plan.mutation,
                                         rng)  # fmt: skip
        if mate:
            end = size + min(plan.pop_size, children.shape[0])
            X[size:end] = children[: end - size]
            admit_and_score(archive, size, end, scoring, n_parts)
            rows = np.concatenate((rows, np.arange(size, end)))
            size = end
    return rows, size


def nsga2_generations(
    problem: SearchedProblem, archive: EvaluatedRows, first: FloatArray, plan: Generations,
    rng: np.random.Generator,
) -> IntArray:  # fmt: skip
    """:func:`hcomc.optim.nsga2.run_generations` on ``problem`` in one compiled call
    (:func:`generations`), its rows scored on :func:`~hcomc.control.hierarchical.row_scoring.
    scoring_threads` threads; the final population's rows. An archive that compares whole
    rows, not canonical ones (its keys are its rows), is filled by the Python loop, which
    evaluates the rows as that archive compares them."""
    if archive.arrays.keys is archive.X:
        return run_generations(archive, first, plan, rng)
    (ahead, behind, ahead_none, behind_none), scored, allowed = problem.scoring()
    scoring = Scoring(ahead, behind, ahead_none, behind_none, scored, allowed,
                      problem.no_cooperation, problem.states[BEHIND] is not None)  # fmt: skip
    first = np.ascontiguousarray(first, dtype=np.float64)
    rows, archive.size = generations(archive.arrays, first, plan, rng, scoring, scoring_threads())
    out: IntArray = rows
    return out


def warm_up(constants: RowConstants) -> None:
    """Compile (or load from numba's cache) :func:`generations` for the types a decision
    passes, with every variant's constants ``constants``."""
    X, F, G = np.zeros((4, 5)), np.empty((4, 3)), np.empty((4, len(CONSTRAINTS)))
    integers = (np.full(16, -1, dtype=np.int64), np.empty(4, dtype=np.int64),
                np.empty(4, dtype=np.int64))  # fmt: skip
    archive = ArchiveArrays(X, F, G, np.empty(4), np.empty_like(X), *integers)  # 2 + 2 rows
    first = np.array([[800.0, 4.0, 6.0, 0.0, 0.0], [800.0, 4.0, 6.0, 0.7, 0.7]])
    plan = Generations(2, 2, 1, Bounds(first[0], first[1] + 1.0), (15.0, 0.9), (20.0, 0.9))
    on = np.ones(4, dtype=np.bool_)
    scoring = Scoring(constants, constants, constants, constants, on, on[:2], False, True)
    generations(archive, first, plan, np.random.default_rng(0), scoring, 1)
