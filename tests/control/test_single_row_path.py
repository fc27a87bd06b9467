"""The merge problem's single-row path equals the population kernel bit for bit.

Simulated annealing scores one row per call; :meth:`MergeProblem.evaluate_row` does that in
one compiled call (:func:`~hcomc.control.prediction.population.rollout_into` with VMC's pre-pass
tracks prepared once per problem, U_fuel, the objectives, constraints and the cost), and
:meth:`MergeProblem.evaluate` runs the same body row by row for the population optimisers.
Both are compared, byte for byte, with the population kernel (the objectives and
constraints of :meth:`MergeProblem.predict`, which also returns the trajectories) and with
``scalarise`` on the 60 recorded planning instants
(C1-C5, ``benchmarks/data/decisions.pkl``), on both merge sequences, both modes, rows at the
bounds and at the 0.5 thresholds, a problem without a vehicle to merge behind and one with
lateral cooperation admitted; then whole SA decisions (``AnnealingOptimizer.minimize`` and
``HCOMCController.plan``) with and without the fast path: the same rows in the same order,
the same results. The shared scoring helpers are also checked against the numpy array forms
they replaced, special values included, so that the population path is unchanged too.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from functools import cache
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hcomc._typing import FloatArray
from hcomc.control.hierarchical.controller import HCOMCController, HCOMCDetails
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import AHEAD, BEHIND
from hcomc.control.prediction.population import VMC
from hcomc.control.prediction.scoring import objective_rows
from hcomc.optim.annealing import AnnealingOptimizer
from hcomc.optim.base import RowProblem
from recorded_decisions import recorded_instants, recorded_problem


@cache
def _cached_problem(index: int) -> MergeProblem:
    """:func:`recorded_problem`, built once per test session (for the many hypothesis
    examples)."""
    return recorded_problem(index)


def _variants(problem: MergeProblem) -> list[MergeProblem]:
    """The problem, the same without a vehicle to merge behind, and with lateral cooperation
    admitted in neither or in both sequences (the lateral constraint's two values)."""
    ahead = problem.states[AHEAD]
    return [
        problem,
        MergeProblem((ahead, None), problem.config, problem.lateral_allowed),
        MergeProblem(problem.states, problem.config, (True, True)),
        MergeProblem(problem.states, problem.config, (False, False)),
    ]


def _rows(problem: MergeProblem, n: int, seed: int) -> FloatArray:
    """``n`` rows: uniform in the bounds, a share at the bounds, and the mode and sequence
    variables at 0, 1, 0.5 and just below 0.5."""
    rng = np.random.default_rng(seed)
    xl, xu = np.asarray(problem.xl), np.asarray(problem.xu)
    X = xl + rng.random((n, xl.size)) * (xu - xl)
    at_bound = rng.random(X.shape) < 0.15
    X[at_bound] = np.where(rng.random(X.shape) < 0.5, xl, xu)[at_bound]
    edges = np.array([0.0, 1.0, 0.5, np.nextafter(0.5, 0.0)])
    pick = rng.random((n, 2)) < 0.3
    X[:, 3:][pick] = rng.choice(edges, size=int(pick.sum()))
    return X


def _bits(a: Any) -> bytes:
    """The bytes of a float64 value or array, every NaN replaced by one canonical NaN: equal
    bytes is equality bit for bit, signed zeros included. A NaN's sign and payload are not
    compared: IEEE 754 leaves them unspecified when an operand is NaN (the compiler may
    swap the operands of an addition), and no optimiser can observe them."""
    a = np.array(a, dtype=np.float64)
    a[np.isnan(a)] = np.nan
    return a.tobytes()


def _row(problem: MergeProblem, x: FloatArray) -> tuple[FloatArray, FloatArray, float]:
    F, G = np.empty(problem.n_obj), np.empty(problem.n_constr)
    cost = problem.evaluate_row(x, F, G)
    assert isinstance(cost, float)
    return F, G, cost


def _assert_row_equals_population(problem: MergeProblem, X: FloatArray) -> None:
    """Each row of ``X`` through the fast path, and ``evaluate`` of all of them (which scores
    row by row with the same body), equal the population kernel that :meth:`MergeProblem.
    predict` runs, byte for byte."""
    prediction = problem.predict(X)
    F, G = prediction.F, prediction.G
    cost = problem.scalarise(F, G)
    F_eval, G_eval = problem.evaluate(X)
    assert _bits(F_eval) == _bits(F)
    assert _bits(G_eval) == _bits(G)
    for i, x in enumerate(X):
        f, g, c = _row(problem, x)
        assert _bits(f) == _bits(F[i]), (i, x, f, F[i])
        assert _bits(g) == _bits(G[i]), (i, x, g, G[i])
        assert _bits(c) == _bits(cost[i]), (i, x, c, cost[i])


def test_merge_problem_offers_the_row_path() -> None:
    assert isinstance(recorded_problem(0), RowProblem)


@pytest.mark.parametrize("index", range(60))
def test_row_path_equals_evaluate_on_recorded_instants(index: int) -> None:
    """200 rows per recorded instant and variant (12,000 per variant in all)."""
    for k, problem in enumerate(_variants(recorded_problem(index))):
        X = _rows(problem, 200, seed=1000 * index + k)
        _assert_row_equals_population(problem, X)


def test_rows_cover_both_sequences_modes_and_constraints() -> None:
    """The rows above reach what they must: both sequences, lateral rows scored with the
    lateral constraint on and off, "behind" without a vehicle, merged and unmerged rows,
    feasible and infeasible ones."""
    seen: dict[str, set[bool]] = {}
    for index in range(0, 60, 6):
        for k, problem in enumerate(_variants(recorded_problem(index))):
            X = _rows(problem, 200, seed=1000 * index + k)
            seq = problem.predict(X).sequence
            G = problem.evaluate(X)[1]
            lateral = X[:, 3] >= 0.5
            for name, values in {
                "behind": seq == BEHIND,
                "lateral_flag": G[lateral, 5] > 0,
                "no_behind": G[:, 6] > 0,
                "not_merged": G[:, 1] > 0,
                "feasible": np.all(G <= 0, axis=1),
            }.items():
                seen.setdefault(name, set()).update(bool(v) for v in np.unique(values))
    for name in ("behind", "lateral_flag", "no_behind", "not_merged", "feasible"):
        assert seen[name] == {False, True}, name


_fraction = st.one_of(st.floats(0.0, 1.0), st.sampled_from([0.0, 1.0]))
_switch = st.one_of(_fraction, st.sampled_from([0.5, float(np.nextafter(0.5, 0.0))]))


@settings(max_examples=300, deadline=None)
@given(
    index=st.integers(0, 59),
    variant=st.integers(0, 3),
    u=st.tuples(_fraction, _fraction, _fraction, _switch, _switch),
)
def test_row_path_equals_single_row_evaluate(
    index: int, variant: int, u: tuple[float, ...]
) -> None:
    """Any row, against the population kernel on that row alone."""
    problem = _variants(_cached_problem(index))[variant]
    xl, xu = np.asarray(problem.xl), np.asarray(problem.xu)
    x = xl + np.array(u) * (xu - xl)
    _assert_row_equals_population(problem, x[None, :])


def test_row_path_without_a_cooperating_vehicle() -> None:
    """U_fuel's VR-only branch (no VMC): not met at the recorded instants, so built here."""
    problem = recorded_problem(3)
    state = problem.states[AHEAD]
    present = state.present.copy()
    present[VMC] = False
    alone = dataclasses.replace(state, present=present)
    bare = MergeProblem((alone, None), problem.config, (True, False))
    _assert_row_equals_population(bare, _rows(bare, 300, seed=9))


# ------------------------------------------------------------------- shared scoring helpers
def _scalarise_array_form(problem: MergeProblem, F: FloatArray, G: FloatArray) -> FloatArray:
    """``MergeProblem.scalarise`` as numpy arrays computed it before the compiled helper."""
    gate = 10.0 * np.maximum(F[:, 0] - problem.safety.threshold, 0.0)
    penalty = gate + 1000.0 * np.maximum(G, 0.0).sum(axis=1)
    out: FloatArray = F[:, 1] / problem._fuel_ref + F[:, 2] + penalty
    return out


_special = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, np.nan, np.inf, -np.inf, 1e3, 1e-300, -1e-300]),
    st.floats(-50.0, 50.0),
)


@settings(max_examples=400, deadline=None)
@given(values=st.lists(_special, min_size=10 * 5, max_size=10 * 5), n=st.integers(1, 5))
def test_scalarise_equals_array_form(values: list[float], n: int) -> None:
    """Special values included (NaN, infinities, signed zeros), so that the PSO baseline's
    costs, which go through ``scalarise``, are unchanged."""
    problem = _cached_problem(0)
    a = np.array(values).reshape(5, 10)[:n]
    F, G = a[:, :3], a[:, 3:]
    with np.errstate(all="ignore"):
        expected = _scalarise_array_form(problem, F, G)
        got = problem.scalarise(F, G)
    assert _bits(got) == _bits(expected)


@settings(max_examples=400, deadline=None)
@given(values=st.lists(_special, min_size=3 * 6, max_size=3 * 6), n=st.integers(0, 6))
def test_objective_rows_equal_array_form(values: list[float], n: int) -> None:
    """The objective vector as ``np.column_stack`` of the capped U_safe, U_fuel, -U_eff."""
    u_safe, fuel, u_eff = (np.array(v[:n]) for v in np.array(values).reshape(3, 6))
    expected = np.column_stack([np.minimum(u_safe, 1e3), fuel, -u_eff])
    assert _bits(objective_rows(u_safe, fuel, u_eff)) == _bits(expected)


def test_scalarise_equals_array_form_on_evaluated_rows() -> None:
    for index in range(0, 60, 5):
        problem = recorded_problem(index)
        F, G = problem.evaluate(_rows(problem, 300, seed=index))
        assert _bits(problem.scalarise(F, G)) == _bits(_scalarise_array_form(problem, F, G))


# ------------------------------------------------------------------------ whole decisions
Calls = list[tuple[bytes, bytes, bytes]]


def _record(owner: Any, name: str, calls: Calls, setter: Callable[..., None]) -> None:
    """Wrap ``owner.name`` (evaluate_row or evaluate) to log every row with its F and G."""
    method = getattr(owner, name)

    def evaluate_row(self: MergeProblem, x: FloatArray, F: FloatArray, G: FloatArray) -> float:
        cost: float = method(self, x, F, G)
        calls.append((_bits(x), _bits(F), _bits(G)))
        return cost

    def evaluate(self: MergeProblem, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        F, G = method(self, X)
        calls.extend((_bits(X[i]), _bits(F[i]), _bits(G[i])) for i in range(X.shape[0]))
        return F, G

    setter(owner, name, evaluate_row if name == "evaluate_row" else evaluate)


def _assert_same_result(a: Any, b: Any) -> None:
    for name in ("X", "F", "G", "feasible"):
        assert _bits(getattr(a, name)) == _bits(getattr(b, name)), name
    assert a.n_eval == b.n_eval


@pytest.mark.parametrize("index", range(0, 60, 2))
def test_sa_minimize_identical_with_and_without_row_path(
    index: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same rows in the same order with the same F and G, the same result."""
    fast_calls: Calls = []
    slow_calls: Calls = []
    _record(MergeProblem, "evaluate_row", fast_calls, monkeypatch.setattr)
    _record(MergeProblem, "evaluate", slow_calls, monkeypatch.setattr)
    results = []
    for row_path in (True, False):
        problem = recorded_problem(index)
        initial = None if index % 4 else _rows(problem, 3, seed=index)  # warm starts too
        results.append(
            AnnealingOptimizer(row_path=row_path).minimize(
                problem, budget=360, rng=np.random.default_rng(index), initial=initial
            )
        )
    assert len(fast_calls) == results[0].n_eval
    assert fast_calls == slow_calls
    _assert_same_result(*results)


@pytest.mark.parametrize("index", range(1, 60, 6))
def test_hcomc_plan_with_sa_identical_with_and_without_row_path(
    index: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Whole decisions, a replanned (warm-started) second decision included."""
    name, config, view, group = recorded_instants()[index]
    config = config.model_copy(
        update={"control": config.control.model_copy(update={"optimizer": "sa"})}
    )
    plans: list[list[Any]] = []
    calls: list[Calls] = []
    for row_path in (True, False):
        log: Calls = []
        _record(MergeProblem, "evaluate_row" if row_path else "evaluate", log, monkeypatch.setattr)
        controller = HCOMCController(config, AnnealingOptimizer(row_path=row_path))
        plans.append([controller.plan(view, group, np.random.default_rng(s)) for s in (0, 1)])
        calls.append(log)
        monkeypatch.undo()
    assert calls[0] == calls[1], name
    for fast, slow in zip(*plans, strict=True):
        for field in ("group", "mode", "fallback", "reason", "sequence"):
            assert getattr(fast, field) == getattr(slow, field), (name, field)
        assert list(fast.objectives) == list(slow.objectives)
        assert _bits(list(fast.objectives.values())) == _bits(list(slow.objectives.values()))
        for field in ("merge_x", "vr_duration", "horizon", "vv0", "vv1", "vv2"):
            a, b = getattr(fast, field), getattr(slow, field)
            assert (a is None and b is None) or _bits(a) == _bits(b), (name, field)
        assert isinstance(fast.details, HCOMCDetails)
        assert isinstance(slow.details, HCOMCDetails)
        _assert_same_result(fast.details.pareto, slow.details.pareto)
