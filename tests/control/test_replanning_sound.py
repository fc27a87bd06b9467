"""HCOMC-R (``control.replan_period > 0``, a labelled extension) made sound.

1. The merge position is capped at the point of no return (the acceleration-lane end minus
   the stopping distance at MOBIL's b_safe, the engine's release rule) less the distance VR
   covers in one replan period, at VR's predicted speed when it begins its change.
2. The engine's execution criterion (MOBIL's safety criterion of a commanded change) is a
   constraint of the planner, in the predicted state in which VR begins its change.
3. A replan keeping the committed cooperation does not move its merge position downstream.

Planning once (``replan_period = 0``, the paper) the two constraints are 0 and nothing else
changes.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from functools import cache

import numpy as np
import pytest

from hcomc.config import ScenarioConfig, load_config
from hcomc.control.hierarchical.controller import HCOMCController
from hcomc.control.hierarchical.problem_terms import CONSTRAINTS
from hcomc.control.prediction.layout import N_PARAMS, N_ROLES, P_S0
from hcomc.control.prediction.scoring import execution_violation, no_return_violation
from hcomc.control.prediction.step import behind
from hcomc.equations.safety import stopping_distance
from hcomc.road import VMC, VMF, VMR, VNF, VNR, VR, Kind
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind

COL = {name: i for i, name in enumerate(CONSTRAINTS)}
PERIOD = 1.0


def _config(name: str, period: float = PERIOD) -> ScenarioConfig:
    return load_config(name, control={"controller": "hcomc", "replan_period": period})


def _cap(config: ScenarioConfig, v: float, s0: float) -> float:
    """The last merge position HCOMC-R may plan at VR's speed v [m]."""
    b_safe = config.lane_change.safe_decel
    period = config.control.replan_period
    return config.road.accel_lane_end - float(stopping_distance(v, b_safe, s0)) - v * period


# ------------------------------------------------------------------------ the kernels
def test_no_return_violation_is_the_distance_beyond_the_cap():
    for v, s0, period in ((20.0, 2.0, 1.0), (30.0, 1.5, 2.0), (0.0, 2.0, 1.0)):
        cap = 950.0 - (v * v / (2.0 * 4.0) + s0) - v * period
        for merge_x in (cap - 30.0, cap, cap + 12.5):
            got = no_return_violation(merge_x, v, s0, 950.0, 4.0, period)
            assert got == pytest.approx(merge_x - cap, abs=1e-9)


def _params() -> np.ndarray:
    row = np.array([33.3, 1.0, 2.0, 1.4, 2.0, 4.0, 0.0, 5.0, 1.8, 0.0])  # IDM cars
    assert row.size == N_PARAMS
    return np.tile(row, (N_ROLES, 1))


def test_execution_violation_is_the_engines_criterion(role_state: Callable[..., np.ndarray]):
    """VR beginning its change between VMF (ahead) and VMC (its new follower): feasible with
    room, infeasible when the new follower would brake harder than b_safe, or when VR is
    beside a vehicle (bumper gap below the minimum)."""
    params = _params()
    v = {VR: 25.0, VMC: 25.0, VMF: 25.0, VMR: 25.0, VNF: 25.0, VNR: 25.0}
    roomy = {VR: 800.0, VMC: 760.0, VMF: 840.0, VMR: 700.0, VNF: 900.0, VNR: 780.0}
    S = role_state(roomy, v)
    assert execution_violation(S, params, True, 4.0, 2.0) <= 0.0
    # the new follower 10 m behind at 30 m/s: it brakes hard behind VR
    fast = {**v, VMC: 30.0}
    tight = {**roomy, VMC: 785.0}
    S = role_state(tight, fast)
    a_fol = behind(S, params, VMC, VR)
    assert a_fol < -4.0
    got = execution_violation(S, params, True, 4.0, 2.0)
    assert got == pytest.approx(-a_fol - 4.0, rel=1e-12)
    # lateral mode, VMC's change to lane 2 ended: VMR is the new follower instead
    assert execution_violation(S, params, False, 4.0, 2.0) <= 0.0
    # VR beside its future leader (VMF 1 m behind VR's front): the gap criterion fails
    beside = {**roomy, VMF: 799.0}
    assert execution_violation(role_state(beside, v), params, True, 4.0, 2.0) > 0.0


# ---------------------------------------------------------------- the merge problem
@cache
def _instant(name: str, seed: int) -> tuple[object, object]:
    sim = Simulation(_config(name), seed)
    assert sim.run_until_plan() is not None
    return sim.requests[0]


@pytest.mark.parametrize("seed", [0, 1])
def test_the_constraints_apply_to_replanning_alone_and_change_nothing_else(seed):
    """The same candidates scored by HCOMC-R's problem and by the plan-once problem: equal
    objectives and constraints but the two new columns, which are 0 when planning once; the
    no-return column is the merge position minus the cap at VR's predicted speed."""
    view, group = _instant("C2", seed)
    config_r = _config("C2")
    once = HCOMCController(_config("C2", 0.0)).problem(view, group)[0]
    replan = HCOMCController(config_r).problem(view, group)[0]
    X = np.random.default_rng(seed).uniform(replan.xl, replan.xu, size=(60, 5))
    F0, G0 = once.evaluate(X)
    F1, G1 = replan.evaluate(X)
    new = [COL["no_return"], COL["execution"]]
    others = [j for j in range(len(CONSTRAINTS)) if j not in new]
    assert (G0[:, new] == 0.0).all()
    assert np.array_equal(F0, F1)
    assert np.array_equal(G0[:, others], G1[:, others])
    pred = replan.predict(X)
    s0 = float(replan.states[0].params[VR, P_S0])
    checked = 0
    for c in range(X.shape[0]):
        if pred.sequence[c] != 0:
            continue  # "behind" rows are rolled out in their own group (another VR s0: same)
        start = np.flatnonzero(pred.X[c, :, VR] >= X[c, 0])
        if start.size == 0:
            assert G1[c, COL["no_return"]] == 0.0
            continue
        v = float(pred.V[c, start[0], VR])
        assert G1[c, COL["no_return"]] == pytest.approx(X[c, 0] - _cap(config_r, v, s0), abs=1e-6)
        checked += 1
    assert checked >= 5
    assert (G1[:, COL["no_return"]] > 0.0).any()  # late merge positions are cut off


# ------------------------------------------------------------------ closed loop
CONDITIONS = ("C1", "C2", "C3", "C4", "C5")
SEEDS = (0, 1, 2)


@cache
def _run(name: str, seed: int) -> Simulation:
    sim = Simulation(_config(name), seed)
    sim.run()
    return sim


def _start(plan) -> tuple[float, float]:
    """VR's predicted position and speed at the step it begins its change in the plan's own
    prediction (the step its predicted position first reaches the merge position)."""
    pred = plan.details.prediction
    k = np.flatnonzero(pred.X[0, :, VR] >= plan.merge_x)
    assert k.size, "a feasible plan begins VR's change within its window"
    return float(pred.X[0, k[0], VR]), float(pred.V[0, k[0], VR])


@pytest.mark.parametrize("name", CONDITIONS)
def test_no_plan_lies_past_the_point_of_no_return(name):
    checked = 0
    for seed in SEEDS:
        sim = _run(name, seed)
        for plan in sim.decisions:
            if plan.fallback or not np.isfinite(plan.merge_x):
                continue
            s0 = float(sim.fleet.s0[plan.group.vr])
            _, v = _start(plan)
            assert plan.merge_x <= _cap(sim.config, v, s0) + 1e-6
            checked += 1
    assert checked > 0


@pytest.mark.parametrize("name", CONDITIONS)
def test_planned_starts_are_not_refused_by_the_engine(name):
    """A commanded (CAV) VR's change begins where its last plan puts it (the engine's first
    step at or past the merge position, not later: no refusal), and the engine never releases
    a planned VR. (An HDV VR is not commanded: it changes lane by its own gap acceptance.)"""
    checked = 0
    for seed in SEEDS:
        sim = _run(name, seed)
        log, dt = sim.log, sim.config.dt
        plans: dict[int, list] = {}
        for plan in sim.decisions:
            plans.setdefault(plan.group.vr, []).append(plan)
        starts = log.events_of(EventKind.LANE_CHANGE_START)
        fallbacks = log.events_of(EventKind.FALLBACK)
        for vr, own in plans.items():
            fallback_plans = sum(bool(p.fallback) for p in own)
            assert (fallbacks["vehicle"] == vr).sum() == fallback_plans  # no engine release
            last = own[-1]
            if last.fallback or sim.fleet.kind[vr] != Kind.CAV:
                continue
            checked += 1
            mine = starts[(starts["vehicle"] == vr) & (starts["t"] >= last.t0)]
            assert mine.size, f"{name} seed {seed}: VR {vr} never began its change"
            x0 = float(mine["x"][0])
            v_max = float(np.nanmax(log.v[:, vr]))
            assert last.merge_x <= x0 <= last.merge_x + v_max * dt + 1e-6, (
                f"{name} seed {seed}: VR {vr} began at {x0:.1f} m, planned at "
                f"{last.merge_x:.1f} m: refused {(x0 - last.merge_x) / max(v_max * dt, 1e-9):.0f}"
                " steps"
            )
    assert checked > 0


@pytest.mark.parametrize("name", CONDITIONS)
def test_the_merge_position_does_not_drift_downstream(name):
    """A replan that keeps the committed cooperation never moves its merge position further
    downstream than the live plan's (or, VR being past it, than VR's next position)."""
    kept = 0
    for seed in SEEDS:
        sim = _run(name, seed)
        by_vr: dict[int, list] = {}
        for plan in sim.decisions:
            by_vr.setdefault(plan.group.vr, []).append(plan)
        for own in by_vr.values():
            for before, after in itertools.pairwise(own):
                if before.fallback or after.details.commitment != "kept":
                    continue
                x_vr = float(after.details.prediction.X[0, 0, VR])
                start = sim.config.road.accel_lane_start
                bound = max(before.merge_x, start, x_vr + 1.0)
                assert after.merge_x <= bound + 1e-9
                kept += 1
    assert kept > 0


def test_planning_once_makes_one_plan_per_vr():
    """The faithful HCOMC (replan_period 0) plans once per VR."""
    sim = Simulation(_config("C2", 0.0), 0)
    sim.run()
    vrs = [p.group.vr for p in sim.decisions]
    assert len(vrs) == len(set(vrs)) > 0
