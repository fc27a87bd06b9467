"""HCOMC's commitment rule for replanning, and the labelled extension HCOMC+ (mode "none")."""

from __future__ import annotations

import itertools
from dataclasses import replace
from functools import cache

import numpy as np
import pytest

from hcomc.config import ScenarioConfig, load_config
from hcomc.control.hierarchical.commitment import (
    GRID_HORIZONS,
    GRID_POSITIONS,
    choose,
    continuations,
    executed,
)
from hcomc.control.hierarchical.controller import HCOMCController, merge_problem, sequence_groups
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import MODE_NONE
from hcomc.equations.selection import eq19_costs, select_eq19
from hcomc.experiments.results_row import plan_switches
from hcomc.interface import MergeGroup, MergePlan, Mode
from hcomc.road import VMC
from hcomc.sim.engine import Simulation


@cache
def _instant(seed: int, no_cooperation: bool = False) -> tuple[ScenarioConfig, object, object]:
    """The first planning request of C1 (a CAV VMC) with ``seed``."""
    config = load_config("C1", control={"controller": "hcomc", "no_cooperation": no_cooperation})
    sim = Simulation(config, seed)
    assert sim.run_until_plan() is not None
    return (config, *sim.requests[0])


def _cav_vmc_instant() -> tuple[ScenarioConfig, object, object]:
    for seed in range(10):
        config, view, group = _instant(seed)
        if view.is_cav(group.vmc) and sequence_groups(view, group)[1].vmc >= 0:
            return config, view, group
    raise AssertionError("no C1 instant with a CAV VMC and a vehicle behind it")


def _pool(problem: MergeProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two feasible longitudinal rows, "ahead" (row 0) and "behind" (row 1), with objectives
    chosen by hand: both pass the gate, row 1 is better on fuel, row 0 on efficiency."""
    x = 0.5 * (problem.xl + problem.xu)
    X = np.array([[*x[:3], 0.25, 0.25], [*x[:3], 0.25, 0.75]])
    F = np.array([[1.0, 0.50, -0.10], [1.0, 0.40, -0.05]])
    return X, F, np.ones(2, dtype=bool)


def _live(groups, mode: Mode = Mode.LONGITUDINAL) -> MergePlan:
    return MergePlan(groups[0], mode, 0.0, merge_x=800.0, vr_duration=4.0, horizon=8.0)


def test_a_replan_keeps_the_live_cooperation_within_the_margin():
    _config, view, group = _cav_vmc_instant()
    problem = merge_problem(view, group)
    groups = sequence_groups(view, group)
    X, F, feasible = _pool(problem)
    F[1, 2] = -0.11  # "behind" now better on both: Eq. 19 cost 0 against 2 for "ahead"
    costs = eq19_costs(F, ("safety", "fuel", "efficiency"), safety_threshold=4.0)
    assert costs.tolist() == [2.0, 0.0]
    live = _live(groups)  # commands the VMC of "ahead"
    assert choose(view, groups, problem, (X, F, feasible), live, 2.0).kept
    choice = choose(view, groups, problem, (X, F, feasible), live, 1.5)
    assert (choice.row, choice.kept, choice.margin) == (1, False, 2.0)
    assert executed(view, groups, problem, X[1])[1].vmc == groups[1].vmc != live.group.vmc


def test_by_default_a_replan_switches_for_safety_never_for_cost_alone():
    _config, view, group = _cav_vmc_instant()
    problem = merge_problem(view, group)
    groups = sequence_groups(view, group)
    margin = ScenarioConfig().control.commitment_margin
    X, F, feasible = _pool(problem)
    F[1, 2] = -0.11  # "behind" better on both objectives: the whole cost range, 2, apart
    choice = choose(view, groups, problem, (X, F, feasible), _live(groups), margin)
    assert (choice.row, choice.kept, choice.margin) == (0, True, 2.0)
    F[0, 0] = 4.5  # the committed "ahead" now fails Eq. 19's gate (U_safe > 4), "behind" passes
    choice = choose(view, groups, problem, (X, F, feasible), _live(groups), margin)
    assert (choice.row, choice.kept, choice.margin) == (1, False, np.inf)
    assert "Eq. 19's gate" in choice.why


def test_a_replan_switches_when_the_commitment_is_no_longer_feasible():
    _config, view, group = _cav_vmc_instant()
    problem = merge_problem(view, group)
    groups = sequence_groups(view, group)
    X, F, _ = _pool(problem)
    choice = choose(view, groups, problem, (X, F, np.array([False, True])), _live(groups), 2.0)
    assert (choice.row, choice.kept, choice.margin) == (1, False, np.inf)


def test_the_live_plan_continued_is_a_row_with_its_cooperation():
    _config, view, group = _cav_vmc_instant()
    problem = merge_problem(view, group)
    groups = sequence_groups(view, group)
    live = replace(_live(groups), t0=view.t - 1.0)
    rows = continuations(live, groups, problem, view.t)
    assert rows is not None
    assert rows.shape == (1 + GRID_POSITIONS * (1 + GRID_HORIZONS), 5)
    assert rows[0, 0] == pytest.approx(np.clip(800.0, problem.xl[0], problem.xu[0]))
    assert rows[0, 2] == pytest.approx(np.clip(7.0, problem.xl[2], problem.xu[2]))
    assert (rows >= problem.xl).all()
    assert (rows <= problem.xu).all()
    grid = np.linspace(problem.xl[0], problem.xu[0], GRID_POSITIONS)
    assert set(np.round(rows[1:, 0], 9)) == set(np.round(grid, 9))
    for row in rows:
        seq, exec_group, mode = executed(view, groups, problem, row)
        assert (seq, exec_group.vmc, mode) == (0, live.group.vmc, Mode.LONGITUDINAL)
    gone = replace(live, group=replace(live.group, vmc=10_000))  # no longer next to VR
    assert continuations(gone, groups, problem, view.t) is None


def test_eq19_costs_rank_as_select_eq19_picks():
    rng = np.random.default_rng(3)
    names = ("safety", "fuel", "efficiency")
    for _ in range(200):
        F = rng.uniform([2.0, 1.0, -1.0], [6.0, 2.0, 1.0], size=(12, 3))
        feasible = rng.random(12) < 0.8
        k = select_eq19(F, names, feasible=feasible, safety_threshold=4.0)
        costs = eq19_costs(F, names, feasible=feasible, safety_threshold=4.0)
        assert costs[k] == costs.min()


def test_plan_switches_count_changes_of_the_cooperating_vehicle():
    def plan(vmc: int, mode: Mode) -> MergePlan:
        return MergePlan(MergeGroup(vr=1, vmc=vmc), mode, 0.0)

    plans = [plan(5, Mode.LONGITUDINAL), plan(5, Mode.LONGITUDINAL), plan(7, Mode.LONGITUDINAL),
             plan(7, Mode.NONE), plan(7, Mode.NONE)]  # fmt: skip
    assert plan_switches(plans) == [2, 3]
    assert plan_switches(plans[:2]) == []


def test_replanning_hcomc_switches_only_by_the_rule():
    """Closed loop: every replan either keeps the live cooperation or switches, and a kept
    plan commands the same vehicle as the plan before (HCOMC-R: the faithful HCOMC plans
    once)."""
    config = load_config("C1", control={"controller": "hcomc", "replan_period": 1.0})
    kept = 0
    for seed in range(3):
        sim = Simulation(config, seed)
        sim.run()
        plans = sim.decisions
        assert plans[0].details.commitment == ""
        for before, after in itertools.pairwise(plans):
            if before.fallback:
                continue
            assert after.details.commitment == "kept" or after.details.commitment.startswith(
                "switched: "
            )
            if after.details.commitment == "kept":
                kept += 1
                assert after.cooperating == before.cooperating
                assert after.group.vmc == before.group.vmc
    assert kept > 0


# ----------------------------------------------------------------------------- HCOMC+
def test_faithful_hcomc_never_rolls_out_the_mode_none():
    _config, view, group = _cav_vmc_instant()
    problem = merge_problem(view, group)
    assert problem.xu[3] == 1.0
    X = np.random.default_rng(0).uniform(problem.xl, problem.xu, size=(64, 5))
    X[0, 3] = 1.0  # the upper bound is lateral, as always
    assert "none" not in problem.modes(X)
    assert problem.modes(X[:1]) == ["lateral"]


def test_hcomc_plus_mode_none_is_the_group_without_cooperation():
    """A "none" row of HCOMC+ predicts exactly what a longitudinal row predicts when the
    cooperating vehicle does not follow VV1."""
    config, view, group = _cav_vmc_instant()
    plus = merge_problem(view, group)
    plus = MergeProblem(
        plus.states, config.model_copy(update={"control": config.control.model_copy(
            update={"no_cooperation": True})}), plus.lateral_allowed,
    )  # fmt: skip
    assert plus.xu[3] == MODE_NONE + 0.5
    faithful = merge_problem(view, group)
    uncooperative = MergeProblem(
        tuple(None if st is None else replace(st, coop=_no_vmc(st.coop)) for st in faithful.states),
        config, faithful.lateral_allowed,
    )  # fmt: skip
    rng = np.random.default_rng(1)
    X = rng.uniform(faithful.xl, faithful.xu, size=(16, 5))
    X[:, 3] = 0.2
    none = X.copy()
    none[:, 3] = MODE_NONE + 0.2
    assert plus.modes(none) == ["none"] * 16
    got, want = plus.predict(none), uncooperative.predict(X)
    np.testing.assert_array_equal(got.X, want.X)
    np.testing.assert_array_equal(got.F, want.F)
    np.testing.assert_array_equal(got.G, want.G)
    F, G = plus.evaluate(none)  # the compiled scoring path agrees with the prediction
    np.testing.assert_array_equal(F, want.F)
    np.testing.assert_array_equal(G, want.G)
    f, g = np.empty(3), np.empty(G.shape[1])
    plus.evaluate_row(none[3], f, g)
    np.testing.assert_array_equal(f, want.F[3])
    # and it differs from the cooperating row: VMC follows VV1 there
    assert not np.array_equal(faithful.predict(X).A[:, :, VMC], got.A[:, :, VMC])


def _no_vmc(coop: np.ndarray) -> np.ndarray:
    out = coop.copy()
    out[VMC] = False
    return out


def test_hcomc_plus_plans_commands_nobody_when_it_chooses_none():
    config = load_config("C1", control={"controller": "hcomc", "no_cooperation": True})
    seen = 0
    for seed in range(6):
        sim = Simulation(config, seed)
        sim.run()
        for plan in sim.decisions:
            d = plan.details
            if plan.fallback or not 0 <= d.chosen < len(d.pareto.X):
                continue
            if d.pareto.X[d.chosen, 3] >= MODE_NONE:
                seen += 1
                assert plan.mode == Mode.NONE
                assert plan.vv1 is None
                assert plan.cooperating == -1
    assert seen > 0


def test_controller_reads_no_cooperation_from_config():
    config, view, group = _instant(0, no_cooperation=True)
    problem, _ = HCOMCController(config).problem(view, group)
    assert problem.no_cooperation
    assert problem.xu[3] == MODE_NONE + 0.5
