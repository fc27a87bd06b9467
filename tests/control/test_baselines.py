"""FIFO and Game baseline merge controllers (paper Table III)."""

from __future__ import annotations

from dataclasses import replace
from functools import cache
from typing import Any

import numpy as np
import pytest

from hcomc.config import ScenarioConfig, load_config
from hcomc.control.fifo import FIFOController, FIFODetails
from hcomc.control.key_group import behind_group, find_key_vehicles
from hcomc.control.lane_change_game.solvers import solve_cooperative
from hcomc.control.longitudinal_candidate import (
    last_merge_position,
    merge_position,
    nearest_feasible,
    virtual_vehicle_feasible,
    with_cooperation,
)
from hcomc.control.merge_game.controller import GameController, GameDetails
from hcomc.control.merge_game.equilibrium import (
    AHEAD,
    BEHIND,
    NOT_YIELD,
    YIELD,
    kita_mixed,
    pure_nash,
    solve_merge_game,
)
from hcomc.control.merge_game.payoffs import INFEASIBLE_SAFETY, safety_term
from hcomc.control.prediction.population import VMC, VR
from hcomc.control.registry import make_controller
from hcomc.equations.virtual_vehicle import cubic_state
from hcomc.interface import Fleet, MergeGroup, MergePlan, Mode, Ramp, TrafficView
from hcomc.road import Kind, Lane
from hcomc.sim.engine import Simulation
from hcomc.sim.log import EventKind, SimulationLog
from search_grid import documented_grid

CONTROLLERS = ("fifo", "game")
CONDITIONS = ("C1", "C2", "C3", "C4", "C5")
SEEDS = range(5)
LOG_ARRAYS = ("t", "x", "y", "v", "a", "heading", "lane", "active")


def _config(name: str, controller: str, **kw: Any) -> ScenarioConfig:
    return load_config(name, control={"controller": controller}, **kw)


@cache
def _run(controller: str, condition: str, seed: int) -> tuple[Simulation, SimulationLog]:
    sim = Simulation(_config(condition, controller), seed)
    return sim, sim.run()


def _same_plan(a: MergePlan, b: MergePlan) -> None:
    """Everything but the wall-clock decision time is identical."""
    assert a.group == b.group
    assert (a.mode, a.t0, a.fallback, a.reason) == (b.mode, b.t0, b.fallback, b.reason)
    np.testing.assert_array_equal([a.merge_x, a.vr_duration, a.horizon],
                                  [b.merge_x, b.vr_duration, b.horizon])  # fmt: skip
    assert (a.vv1 is None) == (b.vv1 is None)
    if a.vv1 is not None:
        np.testing.assert_array_equal(a.vv1, b.vv1)
    assert a.vv2 is None
    assert b.vv2 is None
    assert a.objectives == b.objectives
    assert type(a.details) is type(b.details)
    if isinstance(a.details, FIFODetails) and isinstance(b.details, FIFODetails):
        assert (a.details.arrival, a.details.order, a.details.yielding) == (
            b.details.arrival, b.details.order, b.details.yielding)  # fmt: skip
    if isinstance(a.details, GameDetails) and isinstance(b.details, GameDetails):
        assert (a.details.outcome, a.details.cell) == (b.details.outcome, b.details.cell)
        np.testing.assert_array_equal(a.details.J_vr, b.details.J_vr)
        np.testing.assert_array_equal(a.details.J_lag, b.details.J_lag)


# ------------------------------------------------------------------ registry, closed loop
@pytest.mark.parametrize(
    ("name", "cls", "safety"),
    [("fifo", FIFOController, None), ("game", GameController, "linear"),
     ("game-capped", GameController, "capped")],
)  # fmt: skip
def test_registry_builds_the_baselines(name, cls, safety):
    controller = make_controller(_config("C1", name))
    assert isinstance(controller, cls)
    assert controller.name == name
    if safety is not None:
        assert controller.safety == safety


def test_game_rejects_an_unknown_safety_term():
    with pytest.raises(ValueError, match="safety = 'soft'; allowed 'linear', 'capped'"):
        GameController(_config("C1", "game"), safety="soft")


@pytest.mark.parametrize("condition", CONDITIONS)
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_closed_loop_is_safe_longitudinal_and_deterministic_per_request(controller, condition):
    for seed in SEEDS:
        sim, log = _run(controller, condition, seed)
        assert sim.decisions, "every run has one key merge"
        collisions = log.events_of(EventKind.COLLISION)
        merged = set(log.events_of(EventKind.MERGE)["vehicle"].tolist())
        waited = set(log.events_of(EventKind.RAMP_WAIT)["vehicle"].tolist())
        for plan, (view, group) in zip(sim.decisions, sim.requests, strict=True):
            assert plan.mode != Mode.LATERAL
            assert plan.vv2 is None
            assert plan.decision_ms > 0.0
            assert plan.reason
            assert plan.group.vr == group.vr
            cooperating = plan.group.vmc
            is_cav = cooperating >= 0 and view.fleet.kind[cooperating] == Kind.CAV
            if plan.mode == Mode.LONGITUDINAL:
                assert is_cav
                assert plan.vv1 is not None
                assert np.isfinite(plan.horizon)
            else:
                assert plan.vv1 is None
            assert plan.fallback or np.isfinite(plan.merge_x)
            keys = {int(i) for g in (group, plan.group) for i in g.as_array() if i >= 0}
            pairs = set(collisions["vehicle"].tolist()) | set(collisions["other"].tolist())
            assert not keys & pairs, f"collision involving key vehicles, seed {seed}"
            assert group.vr in merged or group.vr in waited
            # same request + same rng => same plan; the controller writes nothing: the view
            # is read-only and the simulation state is untouched
            assert not any(a.flags.writeable for a in (view.x, view.v, view.lane))
            state = sim.x.copy(), sim.v.copy(), sim.lane.copy()
            again = [sim.controller.plan(view, group, np.random.default_rng(11)) for _ in "ab"]
            _same_plan(*again)
            for arr, old in zip((sim.x, sim.v, sim.lane), state, strict=True):
                np.testing.assert_array_equal(arr, old)


@pytest.mark.parametrize("controller", CONTROLLERS)
def test_same_seed_gives_identical_plans_and_logs(controller):
    for condition, seed in (("C4", 1), ("C5", 3)):
        sim_a, log_a = _run(controller, condition, seed)
        sim_b = Simulation(_config(condition, controller), seed)
        log_b = sim_b.run()
        for a, b in zip(sim_a.decisions, sim_b.decisions, strict=True):
            _same_plan(a, b)
        for name in LOG_ARRAYS:
            np.testing.assert_array_equal(getattr(log_a, name), getattr(log_b, name))
        for field in log_a.events.dtype.names:  # NaN-aware, field by field
            np.testing.assert_array_equal(log_a.events[field], log_b.events[field])


# ----------------------------------------------------------------- FIFO on hand-built views
# vehicle 0 = VR on the ramp; 1-4 lane 1 (VMF, VMC, VMR, behind VMR); 5-6 lane 2
def _view(vmc_x: float, vmc_v: float, kinds: list[int] | None = None) -> TrafficView:
    config = _config("C1", "fifo")
    kind = np.array(kinds or [Kind.CAV] * 7, dtype=np.int64)
    x = np.array([400.0, 480.0, vmc_x, 250.0, 150.0, 350.0, 200.0])
    v = np.array([25.0, 30.0, vmc_v, 30.0, 30.0, 31.0, 31.0])
    lane = np.array([Lane.RAMP, *[Lane.MAIN_1] * 4, Lane.MAIN_2, Lane.MAIN_2], dtype=np.int64)
    fleet = Fleet.build(config, kind, np.zeros(7, dtype=bool))
    return TrafficView(t=3.0, x=x, v=v, a=np.zeros(7), lane=lane, active=np.ones(7, dtype=bool),
                       changing=np.zeros(7, dtype=bool), fleet=fleet, config=config,
                       ramp=Ramp.of(config.road))  # fmt: skip


def test_a_changing_vehicle_is_a_key_vehicle_of_one_lane_at_a_time():
    """Vehicle 5 changes from lane 2 to lane 1 between VR's projection (400 m) and VMC (330 m):
    before the lateral midpoint it is VNF (lane 2), after it VMC (lane 1), never both."""
    view = _view(vmc_x=330.0, vmc_v=30.0)
    changing = np.zeros(7, dtype=bool)
    changing[5] = True
    before = replace(view, changing=changing)
    group = find_key_vehicles(before, 0)
    assert group == find_key_vehicles(view, 0)
    assert (group.vmc, group.vnf, group.vnr) == (2, 5, 6)
    lane = view.lane.copy()
    lane[5] = Lane.MAIN_1
    after = find_key_vehicles(replace(before, lane=lane), 0)
    assert (after.vmf, after.vmc, after.vmr) == (1, 5, 2)
    assert 5 not in (after.vnf, after.vnr)


def test_merge_position_is_fixed_and_ends_on_the_acceleration_lane():
    view = _view(330.0, 30.0)
    assert merge_position(view, 0) == (710.0, view.config.cav.lane_change_duration)
    short = _config("C1", "fifo", road={"accel_lane_start": 700.0, "accel_lane_end": 805.0})
    view = replace(view, config=short, ramp=Ramp.of(short.road))  # the road is the ramp's
    merge_x, duration = merge_position(view, 0)
    assert merge_x == pytest.approx(805.0 - 25.0 * duration)  # clipped: change ends at 805 m
    assert merge_x >= 700.0


def test_fifo_vr_arriving_first_keeps_the_group_and_vmc_yields():
    view = _view(vmc_x=330.0, vmc_v=30.0)  # t_VR = 310/25 = 12.4 s < t_VMC = 380/30 = 12.7 s
    group = find_key_vehicles(view, 0)
    assert (group.vmf, group.vmc, group.vmr) == (1, 2, 3)
    plan = FIFOController(view.config).plan(view, group, np.random.default_rng(0))
    assert plan.group == group
    assert plan.mode == Mode.LONGITUDINAL
    d = plan.details
    assert isinstance(d, FIFODetails)
    assert d.order == ("VMF", "VR", "VMC")
    assert d.arrival["VR"] == pytest.approx(3.0 + 310.0 / 25.0)
    assert d.arrival["VMC"] == pytest.approx(3.0 + 380.0 / 30.0)
    assert plan.sequence == "ahead"
    assert d.yielding == 2
    # VV1 starts at VMF's state (Eq. 8-10) and is the prediction's cubic
    np.testing.assert_allclose(plan.vv1[:2], [480.0, 30.0])
    # ... and ends at VR's predicted state at the horizon (Eq. 8: x_VV1(tf') = x_VR(tf'))
    pred = d.prediction
    assert pred is not None
    assert d.feasible == bool((pred.G[0] <= 0.0).all())
    at_h = int(np.argmin(np.abs(pred.t - plan.horizon)))
    x_end, v_end, _ = cubic_state(plan.vv1, plan.horizon)
    dt_off = plan.horizon - pred.t[at_h]
    assert x_end == pytest.approx(pred.X[0, at_h, VR] + pred.V[0, at_h, VR] * dt_off, abs=1.0)
    assert v_end == pytest.approx(pred.V[0, at_h, VR], abs=0.2)
    assert 4.0 <= plan.horizon <= view.config.control.horizon_max


def test_fifo_vmc_arriving_first_relabels_the_group_so_vmr_yields():
    view = _view(vmc_x=390.0, vmc_v=32.0)  # t_VMC = 320/32 = 10 s < t_VR = 12.4 s
    group = find_key_vehicles(view, 0)
    plan = FIFOController(view.config).plan(view, group, np.random.default_rng(0))
    assert isinstance(plan.details, FIFODetails)
    assert plan.details.order == ("VMF", "VMC", "VR")
    assert plan.details.yielding == 3  # the old VMR yields
    assert plan.sequence == "behind"
    assert plan.group == MergeGroup(vr=0, vmc=3, vmf=2, vmr=4, vnf=5, vnr=6)
    assert plan.group == behind_group(view, group)
    assert plan.mode == Mode.LONGITUDINAL
    np.testing.assert_allclose(plan.vv1[:2], [390.0, 32.0])  # from the old VMC's state
    # an HDV behind the slot is never commanded
    kinds = [Kind.CAV, Kind.CAV, Kind.CAV, Kind.HDV, Kind.CAV, Kind.CAV, Kind.CAV]
    view = _view(vmc_x=390.0, vmc_v=32.0, kinds=kinds)
    plan = FIFOController(view.config).plan(
        view, find_key_vehicles(view, 0), np.random.default_rng(0)
    )
    assert plan.group.vmc == 3
    assert plan.mode == Mode.NONE
    assert plan.vv1 is None


def test_fifo_without_vmc_or_vmr():
    view = _view(vmc_x=390.0, vmc_v=32.0)
    alone = MergeGroup(vr=0, vmf=1)
    plan = FIFOController(view.config).plan(view, alone, np.random.default_rng(0))
    assert plan.mode == Mode.NONE
    assert plan.group == alone
    assert np.isfinite(plan.merge_x)
    tail = MergeGroup(vr=0, vmc=2, vmf=1)  # VMC is the last lane-1 vehicle
    assert behind_group(view, tail) == MergeGroup(vr=0, vmf=2)


def test_with_cooperation_copies_and_switches_only_the_vmc_flag():
    view = _view(vmc_x=330.0, vmc_v=30.0)
    problem = FIFOController(view.config).problem(view, find_key_vehicles(view, 0))
    off = with_cooperation(problem, False)
    assert problem.state.coop[VMC]
    assert not off.state.coop[VMC]
    assert not off.states[1].coop[VMC]  # both sequences
    np.testing.assert_array_equal(off.state.coop[:VMC], problem.state.coop[:VMC])
    np.testing.assert_array_equal(off.state.cav, problem.state.cav)  # kinds are untouched
    row = np.array([[710.0, 4.0, 11.0, 0.0, 0.0]])
    yield_, keep = problem.predict(row), off.predict(row)
    np.testing.assert_array_equal(yield_.vv1, keep.vv1)  # VV1 is fixed before the joint pass
    np.testing.assert_array_equal(yield_.X[0, :, 0], keep.X[0, :, 0])  # VR ignores VMC's choice
    assert yield_.A[0, :, VMC].min() > keep.A[0, :, VMC].min()  # yielding early brakes softer


# ----------------------------------------------------------------------- game equilibria
def test_pure_nash_enumeration_and_selection():
    # prisoner's dilemma in payoffs: the unique equilibrium is (1, 1)
    A, B = np.array([[3.0, 0.0], [5.0, 1.0]]), np.array([[3.0, 5.0], [0.0, 1.0]])
    assert pure_nash(A, B) == [(1, 1)]
    out = solve_merge_game(-A, -B, cooperative=False, rng=np.random.default_rng(0))
    assert (out.row, out.col, out.kind, out.pure) == (1, 1, "pure", ((1, 1),))
    # coordination game: two equilibria, the larger payoff sum wins
    A, B = np.array([[2.0, 0.0], [0.0, 1.0]]), np.array([[2.0, 0.0], [0.0, 1.0]])
    assert pure_nash(A, B) == [(0, 0), (1, 1)]
    out = solve_merge_game(-A, -B, cooperative=False, rng=np.random.default_rng(0))
    assert (out.row, out.col) == (AHEAD, YIELD)
    out = solve_merge_game(-A[::-1, ::-1], -B[::-1, ::-1], cooperative=False, rng=None)
    assert (out.row, out.col) == (BEHIND, NOT_YIELD)


def test_kita_mixed_equilibrium_by_hand():
    A = np.array([[4.0, 0.0], [1.0, 2.0]])  # row player (VR) payoffs
    B = np.array([[0.0, 3.0], [2.0, 1.0]])  # column player payoffs
    assert pure_nash(A, B) == []
    # q* = (a22 - a12) / (a11 - a12 - a21 + a22) = (2 - 0) / (4 - 0 - 1 + 2) = 0.4
    # p* = (b22 - b21) / (b11 - b12 - b21 + b22) = (1 - 2) / (0 - 3 - 2 + 1) = 0.25
    p, q = kita_mixed(A, B)
    assert (p, q) == pytest.approx((0.25, 0.4))
    # indifference: each player's mix equalises the other's payoffs
    assert q * A[0, 0] + (1 - q) * A[0, 1] == pytest.approx(q * A[1, 0] + (1 - q) * A[1, 1])
    assert p * B[0, 0] + (1 - p) * B[1, 0] == pytest.approx(p * B[0, 1] + (1 - p) * B[1, 1])
    # the played actions are drawn from (p*, q*) with the given rng: VR first, then the lag
    out = solve_merge_game(-A, -B, cooperative=False, rng=np.random.default_rng(5))
    u = np.random.default_rng(5).random(2)
    assert out.kind == "mixed"
    assert (out.p, out.q) == pytest.approx((0.25, 0.4))
    assert (out.row, out.col) == (AHEAD if u[0] < 0.25 else BEHIND, YIELD if u[1] < 0.4 else 1)
    rng = np.random.default_rng(1)
    rows = [solve_merge_game(-A, -B, cooperative=False, rng=rng).row for _ in range(4000)]
    assert np.mean(np.array(rows) == AHEAD) == pytest.approx(0.25, abs=0.03)


def test_cooperative_solution_is_the_joint_argmin():
    J_row, J_col = np.array([[1.0, 3.0], [2.0, 2.5]]), np.array([[0.9, 0.1], [0.0, 0.2]])
    out = solve_merge_game(J_row, J_col, cooperative=True, rng=None)
    assert (out.row, out.col, out.kind) == (AHEAD, YIELD, "cooperative")  # 1.9 < 2.0 < 2.7
    sol = solve_cooperative(J_row, J_col)
    assert (out.row, out.col) == (sol.sv_action, int(sol.fv_response[sol.sv_action, 0]))


def test_game_cav_vmc_plays_the_cooperative_cell_and_yields():
    seen_yield = False
    for condition in ("C1", "C2", "C3"):
        for seed in SEEDS:
            sim, _ = _run("game", condition, seed)
            for plan, (view, group) in zip(sim.decisions, sim.requests, strict=True):
                if group.vmc < 0 or view.fleet.kind[group.vmc] != Kind.CAV:
                    continue
                d = plan.details
                assert isinstance(d, GameDetails)
                out = d.outcome
                joint = d.J_vr + d.J_lag
                assert out.kind == "cooperative"
                assert joint[out.row, out.col] == joint.min()
                expected = group if out.row == AHEAD else behind_group(view, group)
                assert plan.group == expected
                if out.row == AHEAD and out.col == YIELD and not plan.fallback:
                    seen_yield = True
                    assert plan.mode == Mode.LONGITUDINAL
                    assert plan.group.vmc == group.vmc
                    pred = d.predictions[AHEAD][YIELD]
                    np.testing.assert_array_equal(plan.vv1, pred.vv1[0])
                if out.col == NOT_YIELD:
                    assert plan.mode == Mode.NONE
                    # VR still follows its plan unless its VV0 is infeasible (fallback)
                    assert np.isfinite(plan.merge_x) != plan.fallback
    assert seen_yield, "some CAV VMC should yield in the cooperative cell"


# ---------------------------------- Game as published: a safety term that does not saturate
def _game_state() -> tuple[TrafficView, MergeGroup]:
    """All CAVs; VMC 50 m behind VR's projection at 30 m/s: merging ahead of a VMC that does
    not yield leaves VR a short gap (U_safe about 6 m/s^2), yielding opens it (about 4)."""
    view = _view(vmc_x=350.0, vmc_v=30.0)
    return view, find_key_vehicles(view, 0)


@cache
def _game_plans() -> tuple[MergePlan, MergePlan]:
    view, group = _game_state()
    return tuple(  # type: ignore[return-value]
        GameController(view.config, safety=s).plan(view, group, np.random.default_rng(0))
        for s in ("linear", "capped")
    )


def test_linear_safety_term_does_not_saturate_and_reads_a_merg_from_config():
    view, group = _game_state()
    plan = _game_plans()[0]
    assert isinstance(plan.details, GameDetails)
    pred = plan.details.predictions[AHEAD][YIELD]  # a feasible prediction
    problem = GameController(view.config).problem(view, group)
    assert view.config.control.safety_emergency_decel == 7.5
    five, six = (safety_term(pred, problem, u) for u in (5.0, 6.0))
    assert (five, six) == (5.0 / 7.5, 6.0 / 7.5)
    assert six > five
    capped = [safety_term(pred, problem, u, "capped") for u in (5.0, 6.0, 2.0)]
    assert capped == [1.0, 1.0, 0.5]  # min(1, U_safe / 4): saturated above 4 m/s^2
    # continuous and strictly increasing, uncapped, up to and beyond a_merg
    u = np.linspace(0.0, 30.0, 301)
    j_s = np.array([safety_term(pred, problem, x) for x in u])
    np.testing.assert_allclose(j_s, u / 7.5, rtol=0, atol=1e-15)
    assert (np.diff(j_s) > 0).all()
    # infeasible: an unavoidable crash costs the infeasible cost under either term
    assert safety_term(pred, problem, np.inf) == INFEASIBLE_SAFETY
    assert safety_term(pred, problem, np.inf, "capped") == INFEASIBLE_SAFETY
    # a_merg is the config's value, read through the problem
    config = load_config("C1", control={"controller": "game", "safety_emergency_decel": 6.0})
    other = GameController(config).problem(replace(view, config=config), group)
    assert safety_term(pred, other, 5.0) == 5.0 / 6.0
    with pytest.raises(ValueError, match="safety = 'soft'"):
        safety_term(pred, problem, 5.0, "soft")


def test_cav_lag_vehicle_yields_when_yielding_opens_a_safer_gap():
    _, group = _game_state()
    plan = _game_plans()[0]
    d = plan.details
    assert isinstance(d, GameDetails)
    assert d.safety == "linear"
    # yielding opens a safer gap: VR's merge ahead of VMC needs less critical deceleration
    assert d.u_safe[AHEAD, YIELD] < 4.0 < d.u_safe[AHEAD, NOT_YIELD]
    # the payoffs, rebuilt from the reported terms (oracle): J_s = U_safe / a_merg, shared
    for i, row in enumerate(("ahead", "behind")):
        for j, col in enumerate(("yield", "not_yield")):
            t = d.terms[f"{row}/{col}"]
            assert t["VR"]["J_s"] == t["lag"]["J_s"] == pytest.approx(d.u_safe[i, j] / 7.5)
            vr = 0.5 * t["VR"]["J_s"] + 0.3 * t["VR"]["J_e"] + 0.2 * t["VR"]["J_c"]
            lag = 0.4 * t["lag"]["J_s"] + 0.4 * t["lag"]["J_e"] + 0.2 * t["lag"]["J_c"]
            assert (d.J_vr[i, j], d.J_lag[i, j]) == pytest.approx((vr, lag))
    joint = d.J_vr + d.J_lag
    assert np.unravel_index(np.argmin(joint), joint.shape) == (AHEAD, YIELD)
    # ... so the CAV lag vehicle (VMC) yields: it is commanded to follow VV1
    assert d.cell == ("ahead", "yield")
    assert d.outcome.kind == "cooperative"
    assert plan.mode == Mode.LONGITUDINAL
    assert plan.group == group
    assert plan.group.vmc == 2
    assert not plan.fallback
    np.testing.assert_array_equal(plan.vv1, d.predictions[AHEAD][YIELD].vv1[0])
    assert d.candidates[AHEAD] == (plan.merge_x, plan.horizon)


def test_capped_variant_keeps_the_saturating_equilibrium():
    """The capped term scores both cells of the "ahead" row almost alike (min(1, 3.94 / 4)
    against 1), so comfort decides and VMC does not yield: the equilibrium hcomc played before
    the linear term, on the same predictions."""
    linear, capped = _game_plans()
    dl, dc = linear.details, capped.details
    assert isinstance(dl, GameDetails)
    assert isinstance(dc, GameDetails)
    assert dc.safety == "capped"
    np.testing.assert_array_equal(dc.u_safe, dl.u_safe)  # J_s is the only difference
    assert dc.candidates == dl.candidates
    assert dc.terms["ahead/not_yield"]["VR"]["J_s"] == 1.0
    assert dc.terms["ahead/yield"]["VR"]["J_s"] == pytest.approx(dl.u_safe[AHEAD, YIELD] / 4.0)
    assert dc.cell == ("ahead", "not_yield")
    assert capped.mode == Mode.NONE
    assert capped.vv1 is None
    assert "game-capped" in capped.reason


def test_game_is_deterministic_per_request():
    view, group = _game_state()
    for safety in ("linear", "capped"):
        controller = GameController(view.config, safety=safety)
        a, b = (controller.plan(view, group, np.random.default_rng(3)) for _ in "ab")
        _same_plan(a, b)


# ------------------------------------------------------ FIFO: the nearest feasible VV1
def _far_leader_view(config: ScenarioConfig | None = None) -> TrafficView:
    """VMF 200 m ahead of VR's projection: VV1, from VMF's state to VR's at VR's arrival
    (11 s), would have to brake harder than b_max = 7.5 m/s^2."""
    view = _view(vmc_x=330.0, vmc_v=30.0)
    x = view.x.copy()
    x[1] = 600.0
    return replace(view, x=x, config=config or view.config)


def _grid(view: TrafficView, merge_x: float, horizon: float) -> list[tuple[float, float]]:
    """The search grid in its documented order (oracle, written out independently)."""
    return documented_grid(merge_x, horizon, view.config.control.horizon_max,
                           last_merge_position(view, 0))  # fmt: skip


def _feasible(problem, cells: list[tuple[float, float]], duration: float) -> np.ndarray:
    rows = np.array([[x, duration, h, 0.0, 0.0] for x, h in cells])
    pred = problem.predict(rows)  # the population path, not evaluate's
    return np.array([virtual_vehicle_feasible(pred, r) for r in range(len(cells))])


def test_fifo_degrades_to_the_nearest_feasible_virtual_vehicle():
    view = _far_leader_view()
    group = find_key_vehicles(view, 0)
    controller = FIFOController(view.config)
    plan = controller.plan(view, group, np.random.default_rng(0))
    d = plan.details
    assert isinstance(d, FIFODetails)
    assert plan.sequence == "ahead"
    merge_x, horizon = d.nominal
    assert merge_x == 710.0
    duration = view.config.cav.lane_change_duration
    problem = controller.problem(view, group)
    assert not _feasible(problem, [d.nominal], duration)[0]  # the rule's own VV1 is infeasible
    # the plan still commands VMC, with a feasible VV1 ...
    assert not plan.fallback
    assert plan.mode == Mode.LONGITUDINAL
    assert plan.group.vmc == 2
    assert "nearest feasible VV1" in plan.reason
    tau = np.linspace(0.0, plan.horizon, 401)
    _, v, a = cubic_state(plan.vv1, tau)
    assert v.min() >= 0.0
    assert a.min() >= -view.config.control.virtual_max_decel
    # ... the first feasible candidate of the documented grid (merge position kept, H longer)
    grid = _grid(view, merge_x, horizon)
    ok = _feasible(problem, grid, duration)
    first = int(np.flatnonzero(ok)[0])
    assert (plan.merge_x, plan.horizon) == pytest.approx(grid[first])
    assert plan.merge_x == merge_x
    assert plan.horizon > horizon
    assert nearest_feasible(problem, merge_x, duration, horizon, 20.0, last_merge_position(
        view, 0)) == pytest.approx(grid[first])  # fmt: skip
    # deterministic
    _same_plan(plan, controller.plan(view, group, np.random.default_rng(9)))


def test_fifo_falls_back_only_when_no_candidate_is_feasible():
    strict = load_config("C1", control={"controller": "fifo", "virtual_max_decel": 0.05})
    view = _far_leader_view(strict)
    group = find_key_vehicles(view, 0)
    controller = FIFOController(strict)
    plan = controller.plan(view, group, np.random.default_rng(0))
    d = plan.details
    assert isinstance(d, FIFODetails)
    merge_x, horizon = d.nominal
    grid = _grid(view, merge_x, horizon)
    problem = controller.problem(view, group)
    duration = strict.cav.lane_change_duration
    assert not _feasible(problem, [d.nominal, *grid], duration).any()
    assert nearest_feasible(problem, merge_x, duration, horizon, 20.0, 900.0) is None
    assert plan.fallback
    assert plan.mode == Mode.NONE
    assert plan.vv1 is None
    assert np.isnan(plan.merge_x)
    assert "gap acceptance" in plan.reason
