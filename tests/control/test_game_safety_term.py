"""The safety term both games share, and how the lane-change game admits a change.

:func:`hcomc.control.lane_change_game.game_safety.safety_term` is the one J_s of the
lane-change game (paper Section III-B) and of the merge game (the Game baseline): linear and
uncapped, J_s = U_safe / a_merg with U_safe Eq. 15. The lane-change game's decision records
whether a change was admitted by its equilibrium (the paper's rule) or only by the added
safety rule (an extension).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from hcomc.config import CAVParams, HDVParams, load_config
from hcomc.control.hierarchical.problem_terms import CONSTRAINTS, Prediction
from hcomc.control.key_group import find_key_vehicles
from hcomc.control.lane_change_game import costs, game_safety
from hcomc.control.lane_change_game.decision import (
    ADMITTED_BY,
    GAME_DEFAULT,
    SV_LC,
    GameVehicle,
    LaneChangeDecision,
    lane_change_game,
)
from hcomc.control.lane_change_game.game_safety import INFEASIBLE_SAFETY_COST, safety_term
from hcomc.control.merge_game import payoffs
from hcomc.control.merge_game.controller import GameController, GameDetails
from hcomc.equations.safety import critical_acceleration
from hcomc.experiments.results_row import lateral_cause
from hcomc.interface import Fleet, Mode, Ramp, TrafficView
from hcomc.road import Kind, Lane

A_MERG = 7.5  # control.safety_emergency_decel [m/s^2]

# (d_cri [m], v_r [m/s], v_f [m/s], T [s], D [m]); a_cr about 4.83, 6.90, 6.18, 3.98 m/s^2
STATES = [
    (50.0, 25.0, 25.0, 1.0, 2.0),
    (30.0, 30.0, 28.0, 0.5, 2.0),
    (80.0, 33.0, 20.0, 0.5, 2.0),
    (40.0, 20.0, 22.0, 1.0, 2.0),
]
BEYOND_A_MERG = (12.0, 15.0, 15.0, 1.0, 2.0)
"""a_cr = 225 / 20 = 11.25 m/s^2 > a_merg: a deceleration the follower cannot brake."""


def _eq15(d: float, v_r: float, v_f: float, delay: float, dmin: float, a_merg: float) -> float:
    """Eq. 15 written out: a_cr = v_r^2 / (2 (d_cri - D - v_r T + v_f^2 / (2 a_merg)))."""
    return v_r**2 / (2.0 * (d - dmin - v_r * delay + v_f**2 / (2.0 * a_merg)))


# -------------------------------------------------------------- the shared term, closed form
@pytest.mark.parametrize(("d", "v_r", "v_f", "delay", "dmin"), [*STATES, BEYOND_A_MERG])
def test_shared_term_is_eq15_over_a_merg(
    d: float, v_r: float, v_f: float, delay: float, dmin: float
) -> None:
    a_cr = float(
        critical_acceleration(d, v_r, v_f, delay=delay, min_distance=dmin, emergency_decel=A_MERG)
    )
    assert a_cr == pytest.approx(_eq15(d, v_r, v_f, delay, dmin, A_MERG), rel=1e-14)
    assert float(safety_term(a_cr, A_MERG)) == a_cr / A_MERG
    # the capped variant (controller game-capped only)
    capped = float(safety_term(a_cr, A_MERG, form="capped", threshold=4.0))
    assert capped == min(1.0, a_cr / 4.0)


def test_shared_term_is_linear_uncapped_and_forbids_the_infeasible() -> None:
    u = np.linspace(0.0, 20.0, 201)
    j_s = safety_term(u, A_MERG)
    np.testing.assert_array_equal(j_s, u / A_MERG)
    assert (np.diff(j_s) > 0.0).all()  # strictly increasing, beyond 4 m/s^2 and a_merg
    assert float(safety_term(np.inf, A_MERG)) == INFEASIBLE_SAFETY_COST
    np.testing.assert_array_equal(
        safety_term([1.0, 2.0], A_MERG, infeasible=[False, True]),
        [1.0 / A_MERG, INFEASIBLE_SAFETY_COST],
    )
    with pytest.raises(ValueError, match="safety = 'soft'"):
        safety_term(1.0, A_MERG, form="soft")
    with pytest.raises(ValueError, match="needs a threshold"):
        safety_term(1.0, A_MERG, form="capped")


@pytest.mark.parametrize(("d", "v_r", "v_f", "delay", "dmin"), STATES)
def test_lane_change_game_cost_is_the_shared_term_of_the_worst_eq15(
    d: float, v_r: float, v_f: float, delay: float, dmin: float
) -> None:
    """A pair held at one state over the horizon, then with the gap closing: J_s of the game's
    cost function is Eq. 15 of the worst instant over a_merg."""
    params = GAME_DEFAULT.model_copy(update={"min_distance": dmin, "emergency_decel": A_MERG})
    n = params.n_steps
    gaps = np.stack([np.full(n, d), np.linspace(d + 10.0, d, n)])
    on = np.ones((2, n), dtype=bool)
    j_s = costs.safety_cost(gaps, np.full((2, n), v_r), np.full((2, n), v_f), delay, on, params)
    expected = _eq15(d, v_r, v_f, delay, dmin, A_MERG) / A_MERG
    np.testing.assert_allclose(j_s, [expected, expected], rtol=1e-14)


def test_lane_change_game_forbids_a_cr_beyond_a_merg() -> None:
    """The lane-change game's own infeasibility rule (a_cr > a_merg), applied through the
    shared term's ``infeasible``; the merge game has its own rules (the braking it predicts)."""
    d, v_r, v_f, delay, dmin = BEYOND_A_MERG
    params = GAME_DEFAULT.model_copy(update={"min_distance": dmin, "emergency_decel": A_MERG})
    n = params.n_steps
    full = np.full((1, n), 1.0)
    a_cr = costs.worst_critical_acceleration(
        full * d, full * v_r, full * v_f, delay, full > 0.0, params
    )
    assert np.isinf(a_cr).all()
    j_s = costs.safety_cost(full * d, full * v_r, full * v_f, delay, full > 0.0, params)
    np.testing.assert_array_equal(j_s, INFEASIBLE_SAFETY_COST)


def test_merge_game_term_is_the_shared_term() -> None:
    pred, problem = _merge_prediction(), _merge_problem()
    for u in (0.5, 4.0, 6.0, 9.0):  # 9 > a_merg: still finite, uncapped
        assert payoffs.safety_term(pred, problem, u) == u / A_MERG
        assert payoffs.safety_term(pred, problem, u, "capped") == min(1.0, u / 4.0)
    assert payoffs.safety_term(pred, problem, np.inf) == INFEASIBLE_SAFETY_COST
    collided = _merge_prediction(collision=True)
    assert payoffs.safety_term(collided, problem, 1.0) == INFEASIBLE_SAFETY_COST


# ------------------------------------------------------------ one function, called by both
def test_both_games_call_the_one_shared_function(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[str] = []

    def fake(u_safe: Any, emergency_decel: float, **kwargs: Any) -> np.ndarray:
        calls.append(kwargs.get("form", "linear"))
        return np.full(np.shape(u_safe), 0.123)

    monkeypatch.setattr(game_safety, "safety_term", fake)
    # the lane-change game: every J_s of SV is the patched value
    d = _play(*_EQUILIBRIUM_STATE)
    np.testing.assert_array_equal(d.sv_safety, 0.123)
    n_lane_change = len(calls)
    assert n_lane_change > 0
    # the merge game: its payoff function and every cell of a played game
    assert payoffs.safety_term(_merge_prediction(), _merge_problem(), 5.0) == 0.123
    view = _merge_view()
    plan = GameController(view.config).plan(view, find_key_vehicles(view, 0), _rng())
    assert isinstance(plan.details, GameDetails)
    for cell in plan.details.terms.values():
        assert cell["VR"]["J_s"] == cell["lag"]["J_s"] == 0.123
    assert len(calls) > n_lane_change + 1


# ------------------------------------------- the lane-change game: equilibrium or safety rule
SV_IDM, FV_IDM = CAVParams(), HDVParams()


def _veh(x: float, v: float, *, cav: bool = True) -> GameVehicle:
    return GameVehicle(x=x, v=v, length=5.0, desired_speed=33.3, is_cav=cav)


def _play(*vehicles: GameVehicle | None) -> LaneChangeDecision:
    sv, fv, sv_leader, target_leader = vehicles
    assert sv is not None
    return lane_change_game(
        sv, fv, sv_leader, target_leader, params=GAME_DEFAULT, sv_idm=SV_IDM, fv_idm=FV_IDM
    )


# SV (CAV) at 15 m/s behind a 15 m/s leader, target lane free ahead, an HDV follower 120 m
# behind at 20 m/s; only SV's gap to its leader differs.
_EQUILIBRIUM_STATE = (_veh(0.0, 15.0), _veh(-125.0, 20.0, cav=False), _veh(20.0, 15.0), None)
"""15 m gap: keeping is unsafe enough (a_cr about 6.4 m/s^2) that the equilibrium changes."""
_SAFETY_RULE_STATE = (_veh(0.0, 15.0), _veh(-125.0, 20.0, cav=False), _veh(25.0, 15.0), None)
"""20 m gap: the equilibrium keeps (comfort), but the change keeps a_cr < 4 m/s^2 against
every response, so the added safety rule admits it."""
_NEITHER_STATE = (_veh(0.0, 25.0), _veh(-2.0, 25.0, cav=False), None, None)
"""The target slot is occupied: neither admits a change."""


def _check_record(d: LaneChangeDecision) -> None:
    """The record is consistent: the rule from the recorded a_cr, J_s from the shared term."""
    support = d.solution.fv_mixed[SV_LC] > 0.0
    assert d.change_is_safe == bool((d.sv_critical_accel[SV_LC][support] < 4.0).all())
    assert d.safety_threshold == GAME_DEFAULT.safety_threshold == 4.0
    np.testing.assert_array_equal(d.sv_safety, safety_term(d.sv_critical_accel, A_MERG))
    assert d.admitted_by in ADMITTED_BY
    assert d.admits() == (d.change or d.change_is_safe)  # HCOMC's lateral gate
    assert d.admits(safety_rule=False) == d.change  # HCOMC-eq's


def test_equilibrium_admits_the_change() -> None:
    d = _play(*_EQUILIBRIUM_STATE)
    _check_record(d)
    assert d.change
    assert d.change_is_safe  # both would admit it; the equilibrium is recorded
    assert d.admitted_by == "equilibrium"
    assert "change admitted by the equilibrium" in d.reason
    assert d.solution.expected_cost[SV_LC] < d.solution.expected_cost[1]


def test_only_the_added_safety_rule_admits_the_change() -> None:
    d = _play(*_SAFETY_RULE_STATE)
    _check_record(d)
    assert not d.change
    assert d.change_is_safe
    assert d.admitted_by == "safety_rule"
    assert d.admits()
    assert not d.admits(safety_rule=False)  # HCOMC-eq: the equilibrium alone
    assert "only by the added safety rule (extension)" in d.reason
    assert d.solution.expected_cost[SV_LC] > d.solution.expected_cost[1]


def test_neither_admits_a_change_into_an_occupied_slot() -> None:
    d = _play(*_NEITHER_STATE)
    _check_record(d)
    assert (d.change, d.change_is_safe, d.admitted_by) == (False, False, "")
    assert not d.admits()
    assert np.isinf(d.sv_critical_accel[SV_LC]).all()
    assert (d.sv_safety[SV_LC] == INFEASIBLE_SAFETY_COST).all()


@pytest.mark.parametrize(
    ("state", "cause"),
    [(_EQUILIBRIUM_STATE, "equilibrium"), (_SAFETY_RULE_STATE, "safety_rule")],
)
def test_results_row_cause_agrees_with_the_record(
    state: tuple[GameVehicle | None, ...], cause: str
) -> None:
    """A lateral plan's ``lateral_cause`` (runs table) is the decision's ``admitted_by``."""
    d = _play(*state)
    plan = SimpleNamespace(mode=Mode.LATERAL, details=SimpleNamespace(game=d))
    assert lateral_cause(plan) == d.admitted_by == cause


# --------------------------------------------------------------------------------- helpers
def _merge_prediction(*, collision: bool = False) -> Prediction:
    """A one-row prediction of 6 key vehicles over 3 steps: gentle accelerations, no
    violated constraint (or a collision)."""
    k, r = 3, 6
    g = np.zeros((1, len(CONSTRAINTS)))
    g[0, CONSTRAINTS.index("collision")] = 1.0 if collision else 0.0
    zeros = np.zeros((1, k, r))
    return Prediction(
        t=np.arange(k, dtype=np.float64), X=zeros, Y=zeros, V=zeros + 25.0, A=zeros - 0.5,
        heading=zeros, k_merge=np.array([1]), F=np.zeros((1, 3)), G=g,
        vv0=np.zeros((1, 4)), vv1=np.zeros((1, 4)), vv2=np.zeros((1, 4)),
        sequence=np.array([0]),
    )  # fmt: skip


def _merge_problem() -> Any:
    """What the merge game's safety term reads of a merge problem (a stand-in)."""
    return SimpleNamespace(
        states=(None, None),
        state=SimpleNamespace(present=np.ones(6, dtype=bool)),
        safety=SimpleNamespace(emergency_decel=A_MERG, threshold=4.0),
    )


def _merge_view() -> TrafficView:
    """All CAVs on C1: VR on the ramp, VMC 50 m behind VR's projection at 30 m/s."""
    config = load_config("C1", control={"controller": "game"})
    kind = np.full(7, Kind.CAV, dtype=np.int64)
    x = np.array([400.0, 480.0, 350.0, 250.0, 150.0, 350.0, 200.0])
    v = np.array([25.0, 30.0, 30.0, 30.0, 30.0, 31.0, 31.0])
    lane = np.array([Lane.RAMP, *[Lane.MAIN_1] * 4, Lane.MAIN_2, Lane.MAIN_2], dtype=np.int64)
    fleet = Fleet.build(config, kind, np.zeros(7, dtype=bool))
    return TrafficView(t=3.0, x=x, v=v, a=np.zeros(7), lane=lane, active=np.ones(7, dtype=bool),
                       changing=np.zeros(7, dtype=bool), fleet=fleet, config=config,
                       ramp=Ramp.of(config.road))  # fmt: skip


def _rng() -> np.random.Generator:
    return np.random.default_rng(0)


def test_hcomc_eq_drops_the_lateral_plans_only_the_safety_rule_admitted() -> None:
    """C2 seed 2: HCOMC's one plan is lateral, admitted by the added safety rule alone. HCOMC-eq
    plays the same game at the same instant (planning once, nothing has acted yet) and, the
    equilibrium being "keep", is not allowed the lateral mode."""
    from hcomc.experiments.runner import RunSpec, run_one

    hcomc, _ = run_one(RunSpec("C2", "HCOMC", 2))
    eq, _ = run_one(RunSpec("C2", "HCOMC-eq", 2))
    assert (hcomc["mode"], hcomc["lateral_cause"]) == ("lateral", "safety_rule")
    assert (hcomc["games"], hcomc["games_change"], hcomc["games_safety_rule"]) == (1, 0, 1)
    assert (eq["games"], eq["games_change"], eq["games_safety_rule"]) == (1, 0, 1)
    assert eq["mode"] in ("longitudinal", "none")
    assert eq["lateral_cause"] == ""
