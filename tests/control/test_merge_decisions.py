"""The merge as the paper describes it: sequence as a decision, receding-horizon replanning, a
controlled VR that follows its plan, Eq. 15 over the pairs the merge creates, Eq. 16 over a
common distance, and every safety parameter read from the config."""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np
import pytest

from hcomc.config import ScenarioConfig, load_config
from hcomc.control.hierarchical.controller import HCOMCController, HCOMCDetails, merge_problem
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_setup import problem_constants
from hcomc.control.hierarchical.problem_terms import AHEAD, BEHIND
from hcomc.control.key_group import behind_group
from hcomc.control.lane_change_game.decision import game_params
from hcomc.control.prediction.population import (
    C_A_MERG,
    C_D,
    C_DELAY_CAV,
    C_DELAY_HDV,
    P_LEN,
    VMC,
    VMF,
    VMR,
    VR,
)
from hcomc.equations.fuel import fuel_rate
from hcomc.interface import Ramp
from hcomc.road import Kind
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind


def _config(name: str = "C1", **control: object) -> ScenarioConfig:
    return load_config(name, control={"controller": "hcomc", **control})


@cache
def _instant(seed: int):
    sim = Simulation(_config(replan_period=0.0), seed)
    assert sim.run_until_plan() is not None
    return sim.requests[0]


def test_behind_rows_roll_out_the_relabelled_group():
    view, group = _instant(1)
    problem = merge_problem(view, group)
    behind = problem.states[BEHIND]
    assert behind is not None
    relabelled = behind_group(view, group)
    assert behind.ids[VMF] == group.vmc == relabelled.vmf  # VR merges behind the old VMC
    assert behind.ids[VMC] == group.vmr  # the old VMR cooperates
    rows = np.array([[problem.xl[0], 4.0, 10.0, 0.0, 0.0], [problem.xl[0], 4.0, 10.0, 0.0, 1.0]])
    pred = problem.predict(rows)
    np.testing.assert_array_equal(pred.sequence, [AHEAD, BEHIND])
    for row, state in ((0, problem.states[AHEAD]), (1, behind)):
        km = pred.k_merge[row]
        assert km > 0
        # at merge completion VR is behind the vehicle of its sequence's VMF role
        assert pred.X[row, km, VR] < pred.X[row, km, VMF], state.ids


def test_lateral_rows_are_executed_in_the_ahead_group():
    view, group = _instant(1)
    problem = merge_problem(view, group, (True, True))
    row = np.array([[problem.xl[0], 4.0, 10.0, 1.0, 1.0]])  # lateral ignores the sequence
    assert problem.predict(row).sequence[0] == AHEAD


@pytest.mark.parametrize("period", [0.0, 1.0])
def test_receding_horizon_replans_until_vr_starts_its_change(period):
    sim = Simulation(_config(replan_period=period), 1)
    log = sim.run()
    vr = sim.key_group.vr
    plans = log.events_of(EventKind.PLAN)
    times = plans[plans["vehicle"] == vr]["t"]
    starts = log.events_of(EventKind.LANE_CHANGE_START)
    t_start = starts[starts["vehicle"] == vr]["t"][0]
    if period == 0.0:
        assert times.size == 1
    else:
        assert times.size >= 5
        gaps = np.diff(times)  # one period apart, or more after a commitment window
        assert (gaps >= period - 1e-6).all()
        assert np.median(gaps) == pytest.approx(period)
        assert times.max() <= t_start
        # it kept replanning up to the change, but kept the last plan during the final period
        # before the planned merge position (commitment)
        assert t_start - 2 * period - 1e-6 < times.max() <= t_start
    assert len(sim.log.meta["plans"]) == times.size


def test_warm_start_seeds_the_next_decision_with_the_last_pareto_set():
    view, group = _instant(1)
    controller = HCOMCController(view.config)
    first = controller.plan(view, group, np.random.default_rng(0))
    assert isinstance(first.details, HCOMCDetails)
    assert controller._pareto[group.vr].shape[0] == first.details.pareto.X.shape[0]


def test_controlled_vr_follows_its_plan_as_predicted():
    """A CAV VR follows VV0 on the ramp (the prediction has no lane-end term) as predicted:
    engine and prediction agree within 0.3 m and 0.15 m/s on the common 0.5 s grid until the
    horizon or VR's lane change (the rest is the 0.25 s vs 0.1 s integration step)."""
    for seed in range(6):
        sim = Simulation(_config(replan_period=0.0), seed)
        log = sim.run()
        plan = sim.decisions[0]
        vr = plan.group.vr
        if sim.fleet.kind[vr] != Kind.CAV:
            continue
        assert isinstance(plan.details, HCOMCDetails)
        pred = plan.details.prediction
        assert pred is not None
        starts = log.events_of(EventKind.LANE_CHANGE_START)
        t_lc = starts[starts["vehicle"] == vr]["t"][0]
        on_grid = np.isclose(np.mod(pred.t, 0.5), 0.0) | np.isclose(np.mod(pred.t, 0.5), 0.5)
        sel = on_grid & (plan.t0 + pred.t <= min(t_lc, plan.t0 + plan.horizon))
        rows = np.rint((plan.t0 + pred.t[sel]) / log.dt).astype(int)
        assert sel.sum() >= 10
        np.testing.assert_allclose(log.x[rows, vr], pred.X[0, sel, VR], atol=0.3)
        np.testing.assert_allclose(log.v[rows, vr], pred.V[0, sel, VR], atol=0.15)


def test_u_safe_ignores_pairs_the_merge_does_not_create():
    """Moving VMR to 3 m behind VMC (a pair the longitudinal 'ahead' merge does not change)
    leaves U_safe of every 'ahead' candidate unchanged."""
    view, group = _instant(1)
    problem = merge_problem(view, group)
    ahead = problem.states[AHEAD]
    x = ahead.x.copy()
    v = ahead.v.copy()
    x[VMR] = x[VMC] - ahead.params[VMC, P_LEN] - 3.0
    v[VMR] = v[VMC]
    squeezed = MergeProblem((replace(ahead, x=x, v=v), None), view.config)
    rows = np.array([[problem.xl[0] + d, 4.0, 12.0, 0.0, 0.0] for d in (0.0, 20.0, 40.0)])
    F, G = problem.evaluate(rows)
    F2, _ = squeezed.evaluate(rows)
    assert (G[:, 1] == 0).all()  # merged
    np.testing.assert_allclose(F2[:, 0], F[:, 0], rtol=1e-12)


def test_fuel_is_compared_over_a_common_distance():
    """Constant-speed vehicles: U_fuel = cruise rate x distance / speed, whatever the window."""
    view, group = _instant(1)
    problem = merge_problem(view, group)
    K, dt = problem.n_steps, problem.dt
    t = np.arange(K + 1) * dt
    state = problem.states[AHEAD]
    distance = 400.0
    cf = np.zeros((3, K + 1, 6))
    cf[0, :, VR] = distance * t / t[-1]
    cf[0, :, VMC] = cf[0, :, VR]
    cf[1] = distance / t[-1]
    for speed in (20.0, 30.0):
        X = np.zeros((1, K + 1, 6))
        V = np.full((1, K + 1, 6), speed)
        X[0, :, VR] = X[0, :, VMC] = speed * t
        A = np.zeros_like(X)
        fuel = problem._fuel(X, V, A, cf, state)[0]
        vr_fuel = float(fuel_rate(speed, 0.0)) * distance / speed / 1000.0
        vmc_extra = vr_fuel - float(fuel_rate(distance / t[-1], 0.0)) * t[-1] / 1000.0
        assert fuel == pytest.approx(vr_fuel + vmc_extra, rel=1e-9)


def test_every_safety_parameter_comes_from_the_config():
    config = _config(
        safety_threshold=2.5,
        safety_delay_cav=0.3,
        safety_delay_hdv=1.4,
        safety_min_distance=3.0,
        safety_emergency_decel=6.0,
    )
    consts = problem_constants(config, Ramp.of(config.road))
    assert (consts[C_DELAY_CAV], consts[C_DELAY_HDV], consts[C_D], consts[C_A_MERG]) == (
        0.3,
        1.4,
        3.0,
        6.0,
    )
    game = game_params(config, config.road.lane_width)
    assert (game.safety_threshold, game.delay_cav, game.delay_hdv) == (2.5, 0.3, 1.4)
    assert (game.min_distance, game.emergency_decel) == (3.0, 6.0)
    view, group = _instant(1)
    view = replace(view, config=config)
    problem = merge_problem(view, group)
    assert problem.safety.threshold == 2.5
    F = np.array([[3.0, 0.1, 0.0]])
    G = np.zeros((1, problem.n_constr))
    default = merge_problem(replace(view, config=_config()), group)
    # PSO/SA scoring gates U_safe at the configured threshold, not at a constant
    assert problem.scalarise(F, G)[0] - default.scalarise(F, G)[0] == pytest.approx(5.0)
