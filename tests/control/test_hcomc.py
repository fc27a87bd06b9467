"""HCOMC controller: optimiser quality, determinism, closed loop, fallback, CLI."""

from __future__ import annotations

import json
from functools import cache

import numpy as np
import pytest
from pymoo.indicators.hv import HV
from typer.testing import CliRunner

from hcomc.cli import app
from hcomc.config import ScenarioConfig, load_config
from hcomc.control.hierarchical.controller import HCOMCController, HCOMCDetails
from hcomc.control.hierarchical.problem import MergeProblem
from hcomc.control.hierarchical.problem_terms import CONSTRAINTS
from hcomc.control.report import plan_report
from hcomc.equations.pareto import pareto_optimal
from hcomc.interface import Mode
from hcomc.road import Kind
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind


def _config(name: str = "C1", **control: object) -> ScenarioConfig:
    return load_config(name, control={"controller": "hcomc", **control})


@cache
def _instant(seed: int) -> tuple[ScenarioConfig, object, object]:
    """The first planning request of C1 with ``seed`` (mainline inserted at 30 m/s)."""
    config = load_config("C1", control={"controller": "hcomc"}, demand={"main_speed": 30.0})
    sim = Simulation(config, seed)
    assert sim.run_until_plan() is not None
    return (config, *sim.requests[0])


def _problem(seed: int) -> MergeProblem:
    config, view, group = _instant(seed)
    return HCOMCController(config).problem(view, group)[0]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_nsga2_set_is_non_dominated_and_beats_random_sampling(seed):
    """Same budget (360 rows): NSGA-II's feasible front has a larger hypervolume."""
    problem = _problem(seed)
    controller = HCOMCController(_instant(seed)[0])
    result = controller.optimizer.minimize(problem, budget=360, rng=np.random.default_rng(9))
    assert result.n_eval == 360
    assert result.feasible.all()
    assert pareto_optimal(result.F).all()
    X = np.random.default_rng(9).uniform(problem.xl, problem.xu, size=(360, 5))
    F, G = problem.evaluate(X)
    feasible = (G <= 0).all(axis=1)
    rand = F[feasible][pareto_optimal(F[feasible])]
    both = np.vstack([result.F, rand])
    ref = both.max(axis=0) + 0.1 * (both.max(axis=0) - both.min(axis=0)) + 1e-9
    hv = HV(ref_point=ref)
    assert hv(result.F) > hv(rand)


def test_constraints_flag_overrun_and_inadmissible_lateral_mode():
    problem = _problem(1)
    x = np.array([[problem.xl[0], 4.0, 10.0, 0.0, 0.0], [problem.xu[0] + 60.0, 6.0, 10.0, 0.0, 0.0],
                  [problem.xl[0], 4.0, 10.0, 1.0, 0.0]])  # fmt: skip
    problem.lateral_allowed = (False, False)
    _, G = problem.evaluate(x)
    col = {name: i for i, name in enumerate(CONSTRAINTS)}
    assert G[1, col["overrun"]] > 0  # lane change would end beyond the acceleration lane
    assert G[2, col["lateral"]] == 1.0
    assert G[0, col["lateral"]] == 0.0


@pytest.mark.parametrize("optimizer", ["nsga2", "pso", "sa"])
def test_same_seed_same_plan(optimizer):
    plans = []
    for _ in range(2):
        sim = Simulation(_config(optimizer=optimizer), 2)
        plans.append(sim.run_until_plan())
    a, b = plans
    assert a.mode == b.mode
    assert (a.merge_x, a.vr_duration, a.horizon) == (b.merge_x, b.vr_duration, b.horizon)
    assert a.objectives == b.objectives
    assert isinstance(a.details, HCOMCDetails)
    assert isinstance(b.details, HCOMCDetails)
    np.testing.assert_array_equal(a.details.pareto.X, b.details.pareto.X)
    assert a.details.pareto.algorithm == optimizer
    assert (a.details.chosen, a.details.eq19_branch) == (b.details.chosen, b.details.eq19_branch)


def test_full_run_with_hcomc_is_deterministic():
    logs = [Simulation(_config("C2"), 4).run() for _ in range(2)]
    for name in ("x", "y", "v", "a", "lane"):
        np.testing.assert_array_equal(getattr(logs[0], name), getattr(logs[1], name))


def test_cav_vr_starts_its_change_at_the_planned_position():
    sim = Simulation(_config(), 0)  # C1 seed 0: a CAV VR on a longitudinal plan
    log = sim.run()
    vr = sim.key_group.vr
    starts = log.events_of(EventKind.LANE_CHANGE_START)
    start = starts[starts["vehicle"] == vr][0]
    plan = [p for p in sim.decisions if p.group.vr == vr and p.t0 <= start["t"]][-1]
    assert plan.mode == Mode.LONGITUDINAL
    # the change starts in the first step at or past merge_x (one step covers < 4 m)
    assert plan.merge_x <= start["x"] <= plan.merge_x + 4.0
    merges = log.events_of(EventKind.MERGE)
    assert vr in merges["vehicle"]


def test_fallback_when_no_candidate_is_feasible():
    """With a 4-5 s horizon VV1 cannot morph from VMF to a far VR: every candidate fails."""
    sim = Simulation(_config(horizon_min=4.0, horizon_max=4.5, virtual_max_decel=0.5), 0)
    log = sim.run()
    plan = sim.decisions[0]
    assert plan.fallback
    assert plan.mode == Mode.NONE
    assert "gap acceptance" in plan.reason
    fallbacks = log.events_of(EventKind.FALLBACK)
    assert plan.group.vr in fallbacks["vehicle"]
    assert plan.group.vr in log.events_of(EventKind.MERGE)["vehicle"]
    assert log.events_of(EventKind.COLLISION).size == 0


CONDITIONS = ["C1", "C2", "C3", "C4", "C5"]


@pytest.mark.slow
@pytest.mark.parametrize("name", CONDITIONS)
def test_closed_loop_twenty_seeds_no_key_vehicle_collision(name):
    planned = 0
    for seed in range(20):
        sim = Simulation(_config(name), seed)
        log = sim.run()
        ev = log.events
        collisions = ev[ev["kind"] == EventKind.COLLISION]
        for plan in sim.decisions:
            keys = set(plan.group.as_array().tolist()) - {-1}
            hit = set(collisions["vehicle"].tolist()) | set(collisions["other"].tolist())
            assert not (keys & hit), (name, seed, plan.group)
        planned += bool(sim.decisions)
        merged = set(log.events_of(EventKind.MERGE)["vehicle"].tolist())
        waiting = set(log.events_of(EventKind.RAMP_WAIT)["vehicle"].tolist())
        for plan in sim.decisions:  # merged, or waiting at the lane end (logged)
            assert plan.group.vr in merged | waiting, (name, seed)
    assert planned == 20


def test_hdv_vmc_is_never_commanded():
    """Low penetration: whenever VMC is an HDV the plan has no cooperation mode."""
    seen = 0
    for seed in range(8):
        sim = Simulation(_config("C5"), seed)
        plan = sim.run_until_plan()
        if plan.group.vmc >= 0 and sim.fleet.kind[plan.group.vmc] == Kind.HDV:
            assert plan.mode == Mode.NONE
            assert plan.vv1 is None
            seen += 1
    assert seen >= 1


def test_plan_cli_json():
    result = CliRunner().invoke(app, ["plan", "C1", "--seed", "1", "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    for key in ("key_vehicles", "pareto", "chosen", "decision_ms", "mode", "game"):
        assert key in report
    assert set(report["key_vehicles"]) == {"VR", "VMC", "VMF", "VMR", "VNF", "VNR"}
    assert report["chosen"]["index"] < len(report["pareto"])
    assert report["n_eval"] == 360
    for p in report["pareto"]:
        assert {"merge_x", "vr_duration", "horizon", "mode", "safety", "fuel",
                "efficiency"} <= p.keys()  # fmt: skip


REPORT_KEYS = {"scenario", "seed", "t", "optimizer", "safety_threshold", "n_eval",
               "key_vehicles", "game", "pareto", "chosen", "mode", "sequence", "eq19_branch",
               "fallback", "reason", "decision_ms", "controller", "merge_x", "vr_duration",
               "horizon"}  # fmt: skip


def test_plan_report_is_read_from_the_typed_details():
    sim = Simulation(_config("C1"), 1)
    plan = sim.run_until_plan()
    assert plan is not None
    d = plan.details
    assert isinstance(d, HCOMCDetails)
    report = json.loads(json.dumps(plan_report(sim, plan)))
    assert set(report) == REPORT_KEYS
    assert (report["optimizer"], report["n_eval"]) == (d.pareto.algorithm, d.pareto.n_eval)
    assert len(report["pareto"]) == int(d.pareto.feasible.sum()) > 0
    assert d.chosen >= 0
    assert report["chosen"]["index"] == d.chosen
    assert report["chosen"]["merge_x"] == d.pareto.X[d.chosen, 0] == plan.merge_x
    assert report["chosen"]["safety"] == d.pareto.F[d.chosen, 0] == plan.objectives["safety"]
    assert report["eq19_branch"] == d.eq19_branch != ""
    assert d.game is d.games[0]
    assert d.game is not None  # C1's first VMC is a CAV
    assert report["game"]["change"] == d.game.change
    assert sim.log.meta["plans"][-1]["eq19_branch"] == d.eq19_branch


def test_plan_report_of_a_plan_without_hcomc_details():
    sim = Simulation(_config("C1", controller="fifo"), 1)
    plan = sim.run_until_plan()
    assert plan is not None
    report = plan_report(sim, plan)
    assert set(report) == REPORT_KEYS
    assert (report["pareto"], report["chosen"], report["game"]) == ([], None, None)
    assert (report["n_eval"], report["eq19_branch"]) == (0, "")
    assert report["optimizer"] == sim.config.control.optimizer
    assert report["controller"] == "fifo"


def test_plan_cli_table_and_errors():
    runner = CliRunner()
    result = runner.invoke(app, ["plan", "C3", "--seed", "2", "--optimizer", "pso"])
    assert result.exit_code == 0, result.output
    assert "key vehicles" in result.stdout
    assert "chosen" in result.stdout or "fallback" in result.stdout
    bad = runner.invoke(app, ["plan", "C1", "--optimizer", "ga"])
    assert bad.exit_code == 2
    assert "control.optimizer" in bad.stderr
    assert "'ga'" in bad.stderr
    none = runner.invoke(app, ["plan", "platoon"])
    assert none.exit_code == 2
    assert "no ramp vehicle entered the control zone" in none.stderr


def _accel(p: np.ndarray, role: int, lead: int, x, v, a) -> float:
    """Car following of ``role`` behind ``lead`` (-1: free road) with its parameter row."""
    from hcomc.equations.car_following import follow_accel

    row = p[role]
    s = np.inf if lead < 0 else x[lead] - p[lead, 7] - x[role]
    vl, al = (v[role], 0.0) if lead < 0 else (v[lead], a[lead])
    return float(follow_accel(s, v[role], vl, al, *row[:7], bool(row[9] > 0.5)))


def _nearest_ahead(role: int, lanes: dict[int, int], x, present) -> int:
    ahead = [j for j, ln in lanes.items() if j != role and present[j] and ln == lanes[role]
             and x[j] > x[role]]  # fmt: skip
    return min(ahead, key=lambda j: x[j]) if ahead else -1


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_efficiency_objective_is_eq17_at_the_lane_change_decision(seed):
    """-F[:, efficiency] is Eq. 17 recomputed from the predicted states, with the model's car
    following: "before" at the step VR begins its change (VR at its free-road acceleration,
    lanes "ori": VR on the ramp, VMC in lane 1), "after" at the step it completes it (lanes
    "new": VR in lane 1, VMC in lane 2 if lateral): (a_VR,after - a_VR,before) + eta * sum
    over VMC, VMR, VNR of (a_after - a_before)."""
    problem = _problem(seed)
    state, eta = problem.state, problem.config.lane_change.politeness
    rng = np.random.default_rng(seed)
    X = rng.uniform(problem.xl, problem.xu, size=(40, 5))
    X[:, 4] = 0.0  # the group as identified ("ahead"): its roles are the state's
    problem.lateral_allowed = (True, False)
    pred = problem.predict(X)
    checked = 0
    for c in range(X.shape[0]):
        start = np.flatnonzero(pred.X[c, :, 0] >= X[c, 0])
        if pred.k_merge[c] < 0 or start.size == 0:
            continue
        k0, k1 = int(start[0]), int(pred.k_merge[c])
        xb, vb, ab = pred.X[c, k0], pred.V[c, k0], pred.A[c, k0]
        xa, va, aa = pred.X[c, k1], pred.V[c, k1], pred.A[c, k1]
        lateral = X[c, 3] >= 0.5 and bool(state.coop[1])
        base = {0: 0, 1: 1, 2: 1, 3: 1, 4: 2, 5: 2}
        new, ori = {**base, 0: 1, 1: 2 if lateral else 1}, {**base, 0: -1}
        p, present = state.params, state.present
        want = _accel(p, 0, _nearest_ahead(0, new, xa, present), xa, va, aa) - _accel(
            p, 0, -1, xb, vb, ab
        )
        for r in (1, 3, 5):
            if present[r]:
                want += eta * (
                    _accel(p, r, _nearest_ahead(r, new, xa, present), xa, va, aa)
                    - _accel(p, r, _nearest_ahead(r, ori, xb, present), xb, vb, ab)
                )
        assert -pred.F[c, 2] == pytest.approx(want, rel=1e-9, abs=1e-12)
        checked += 1
    assert checked >= 10
