"""A population's rows scored on several threads equal the rows scored on one, bit for bit.

:func:`~hcomc.control.hierarchical.row_scoring.score_rows` scores a population on every core
of a main process (:func:`~hcomc.control.hierarchical.row_scoring.scoring_threads`) by
:func:`~hcomc.control.hierarchical.row_scoring.score_rows_parallel`, whose part p takes rows
p, p + n, ...; on one thread by :func:`~hcomc.control.hierarchical.row_scoring.
score_rows_serial`. The parallel kernel is called here with 1, 2, 3 and 7 parts whatever the
host's cores (a part is a loop iteration; one thread runs them all), on rows of the recorded
planning instants in every sequence and mode, and whole decisions are compared on one thread
and on all. Worker processes and threads other than the main one score on one thread.
"""

from __future__ import annotations

import multiprocessing
import threading

import numba
import numpy as np
import pytest

from hcomc.control.hierarchical import row_scoring
from hcomc.control.hierarchical.controller import HCOMCController, HCOMCDetails
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.row_scoring import (
    score_rows_parallel,
    score_rows_serial,
    scoring_threads,
)
from recorded_decisions import recorded_instants, recorded_problem


def _scored(problem: MergeProblem, X: np.ndarray, parts: int) -> tuple[np.ndarray, ...]:
    """F and G of every row of ``X`` in its variant, by the serial kernel (``parts`` 0) or
    the parallel one with ``parts`` parts."""
    X = np.ascontiguousarray(X)
    _, lateral, variant, no_behind = problem._rows(X)
    F, G = np.full((len(X), problem.n_obj), -7.0), np.full((len(X), problem.n_constr), -7.0)
    variants, scored, allowed = problem.scoring()
    args = (*variants, scored, allowed, X, variant, lateral, no_behind, F, G)
    if parts:
        score_rows_parallel(*args, parts)
    else:
        score_rows_serial(*args)
    return F, G


@pytest.mark.parametrize("index", [0, 7, 18, 31, 44, 59])
def test_parallel_parts_equal_the_serial_rows(index: int) -> None:
    problem = recorded_problem(index)
    rng = np.random.default_rng(index)
    xl, xu = np.asarray(problem.xl), np.asarray(problem.xu)
    X = xl + rng.random((37, xl.size)) * (xu - xl)
    F, G = _scored(problem, X, 0)
    assert np.all(F != -7.0)
    assert np.all(G != -7.0)
    for parts in (1, 2, 3, 7):
        F_par, G_par = _scored(problem, X, parts)
        assert F_par.tobytes() == F.tobytes(), parts
        assert G_par.tobytes() == G.tobytes(), parts


def test_evaluate_is_the_same_on_one_thread_and_on_all() -> None:
    problem = recorded_problem(12)
    rng = np.random.default_rng(3)
    xl, xu = np.asarray(problem.xl), np.asarray(problem.xu)
    X = xl + rng.random((40, xl.size)) * (xu - xl)
    F_all, G_all = problem.evaluate(X)
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        assert scoring_threads() == 1
        F_one, G_one = problem.evaluate(X)
    finally:
        numba.set_num_threads(before)
    assert F_one.tobytes() == F_all.tobytes()
    assert G_one.tobytes() == G_all.tobytes()


def test_a_decision_is_the_same_on_one_thread_and_on_all() -> None:
    _, config, view, group = recorded_instants()[5]
    plans = []
    before = numba.get_num_threads()
    for threads in (before, 1):
        numba.set_num_threads(threads)
        try:
            plans.append(HCOMCController(config).plan(view, group, np.random.default_rng(4)))
        finally:
            numba.set_num_threads(before)
    a, b = plans
    assert (a.mode, a.sequence, a.fallback, a.objectives) == (b.mode, b.sequence, b.fallback,
                                                             b.objectives)  # fmt: skip
    assert (
        np.array([a.merge_x, a.vr_duration, a.horizon]).tobytes()
        == np.array([b.merge_x, b.vr_duration, b.horizon]).tobytes()
    )
    assert isinstance(a.details, HCOMCDetails)
    assert isinstance(b.details, HCOMCDetails)
    for name in ("X", "F", "G"):
        pa, pb = getattr(a.details.pareto, name), getattr(b.details.pareto, name)
        assert pa.tobytes() == pb.tobytes(), name


def test_scoring_threads_follow_numba_on_the_main_thread_and_are_one_elsewhere(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    assert scoring_threads() == numba.get_num_threads()
    seen: list[int] = []
    other = threading.Thread(target=lambda: seen.append(scoring_threads()))
    other.start()
    other.join()
    assert seen == [1]
    parent = multiprocessing.current_process()
    monkeypatch.setattr(row_scoring.multiprocessing, "parent_process", lambda: parent)
    assert scoring_threads() == 1
