"""Tests for the lane-change game (paper Section III-B).

Covers the generic solvers of :mod:`hcomc.control.lane_change_game.solvers` on hand-computed
games and the traffic game of :mod:`hcomc.control.lane_change_game.decision` on small scenarios.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from pydantic import ValidationError

from hcomc.config import CAVParams, HDVParams, IDMParams, ScenarioConfig
from hcomc.control.lane_change_game.decision import (
    FV_AC,
    FV_CS,
    FV_LC,
    GAME_DEFAULT,
    INFEASIBLE_SAFETY_COST,
    SV_K,
    SV_LC,
    GameParams,
    GameVehicle,
    LaneChangeDecision,
    game_params,
    lane_change_game,
)
from hcomc.control.lane_change_game.solvers import (
    GameSolution,
    solve_cooperative,
    solve_stackelberg_harsanyi,
)

PRIOR = (0.25, 0.5, 0.25)  # (aggressive, normal, conservative)

# SV cost J_SV[s, f]: SV actions s = 0 (LC), 1 (K); FV actions f = 0..3 (LC, CS, AC, DC).
SV_COST = np.array(
    [
        [1.0, 4.0, 2.0, 6.0],
        [3.0, 3.0, 3.0, 3.0],
    ]
)
# FV cost J_FV[s, f, θ], written per type θ as rows over f, then stacked on the last axis.
FV_COST = np.stack(
    [
        # θ = 0 (aggressive)
        [[5.0, 2.0, 1.0, 4.0], [1.0, 1.0, 2.0, 3.0]],
        # θ = 1 (normal)
        [[3.0, 1.0, 2.0, 4.0], [2.0, 0.0, 0.0, 5.0]],
        # θ = 2 (conservative)
        [[0.0, 2.0, 3.0, 1.0], [4.0, 3.0, 2.0, 1.0]],
    ],
    axis=-1,
)


# ----------------------------------------------------------------------------------------------
# solve_stackelberg_harsanyi
# ----------------------------------------------------------------------------------------------


def test_hand_built_game() -> None:
    sol = solve_stackelberg_harsanyi(SV_COST, FV_COST, PRIOR)
    # Best responses BR_θ(s) = argmin_f J_FV[s, f, θ], ties to the lowest f:
    #   s = 0: θ0 [5, 2, 1, 4] -> 2;  θ1 [3, 1, 2, 4] -> 1;  θ2 [0, 2, 3, 1] -> 0
    #   s = 1: θ0 [1, 1, 2, 3] -> 0 (tie 0/1);  θ1 [2, 0, 0, 5] -> 1 (tie 1/2);
    #          θ2 [4, 3, 2, 1] -> 3
    np.testing.assert_array_equal(sol.fv_response, [[2, 1, 0], [0, 1, 3]])
    assert sol.fv_response.dtype == np.int64
    # σ(f | s) = Σ_θ p_θ 1[f = BR_θ(s)]:
    #   s = 0: f0 <- θ2 (0.25), f1 <- θ1 (0.5), f2 <- θ0 (0.25), f3 <- none
    #   s = 1: f0 <- θ0 (0.25), f1 <- θ1 (0.5), f3 <- θ2 (0.25)
    np.testing.assert_array_equal(sol.fv_mixed, [[0.25, 0.5, 0.25, 0.0], [0.25, 0.5, 0.0, 0.25]])
    # E(s) = Σ_θ p_θ J_SV[s, BR_θ(s)]:
    #   E(0) = 0.25 * J[0, 2] + 0.5 * J[0, 1] + 0.25 * J[0, 0] = 0.25*2 + 0.5*4 + 0.25*1 = 2.75
    #   E(1) = 0.25 * 3 + 0.5 * 3 + 0.25 * 3 = 3
    np.testing.assert_array_equal(sol.expected_cost, [2.75, 3.0])
    # SV plays argmin E = 0 (LC).
    assert sol.sv_action == 0
    assert sol.cooperative is False


def test_prior_flips_sv_choice() -> None:
    # More weight on the "normal" type, whose best response to s = 0 is f = 1 (J_SV = 4):
    #   E(0) = 0.125 * 2 + 0.75 * 4 + 0.125 * 1 = 0.25 + 3 + 0.125 = 3.375 > E(1) = 3 -> s = 1.
    sol = solve_stackelberg_harsanyi(SV_COST, FV_COST, (0.125, 0.75, 0.125))
    np.testing.assert_array_equal(sol.expected_cost, [3.375, 3.0])
    assert sol.sv_action == 1
    # Best responses do not depend on the prior, σ does.
    np.testing.assert_array_equal(sol.fv_response, [[2, 1, 0], [0, 1, 3]])
    np.testing.assert_array_equal(sol.fv_mixed[0], [0.125, 0.75, 0.125, 0.0])


def test_type_dependent_sv_cost() -> None:
    # SV's cost may depend on the type: J_SV[0, 0, θ2] = 9 instead of 1.
    #   E(0) = 0.25 * 2 + 0.5 * 4 + 0.25 * 9 = 0.5 + 2 + 2.25 = 4.75 > 3 -> s = 1.
    sv3 = np.repeat(SV_COST[:, :, None], 3, axis=2)
    sv3[0, 0, 2] = 9.0
    sol = solve_stackelberg_harsanyi(sv3, FV_COST, PRIOR)
    np.testing.assert_array_equal(sol.expected_cost, [4.75, 3.0])
    assert sol.sv_action == 1


def test_sv_ties_go_to_lowest_action() -> None:
    sol = solve_stackelberg_harsanyi(np.ones((2, 4)), np.zeros((2, 4, 3)), PRIOR)
    # All FV costs tie -> BR = 0 for every type; both SV actions cost 1 -> s = 0.
    np.testing.assert_array_equal(sol.fv_response, np.zeros((2, 3)))
    np.testing.assert_array_equal(sol.fv_mixed[:, 0], [1.0, 1.0])
    assert sol.sv_action == 0


def test_zero_prior_type_with_infinite_cost_is_ignored() -> None:
    sv3 = np.repeat(SV_COST[:, :, None], 3, axis=2)
    sv3[0, 0, 2] = np.inf  # only reached by θ2, which has prior 0
    sol = solve_stackelberg_harsanyi(sv3, FV_COST, (0.5, 0.5, 0.0))
    # E(0) = 0.5 * 2 + 0.5 * 4 = 3 (finite), E(1) = 3 -> tie -> s = 0.
    np.testing.assert_array_equal(sol.expected_cost, [3.0, 3.0])
    assert sol.sv_action == 0


def test_inputs_not_modified() -> None:
    sv, fv = SV_COST.copy(), FV_COST.copy()
    solve_stackelberg_harsanyi(sv, fv, PRIOR)
    solve_cooperative(sv, fv[:, :, 1])
    np.testing.assert_array_equal(sv, SV_COST)
    np.testing.assert_array_equal(fv, FV_COST)


@pytest.mark.parametrize(
    ("sv", "fv", "prior", "match"),
    [
        (SV_COST, FV_COST, (0.5, 0.5), r"prior must have shape \(3,\)"),
        (SV_COST, FV_COST, (0.5, 0.25, 0.5), r"prior must sum to 1, got sum 1\.25"),
        (SV_COST, FV_COST, (1.5, -0.25, -0.25), r"non-negative, got \[1\.5, -0\.25, -0\.25\]"),
        (SV_COST, FV_COST, (np.nan, 0.5, 0.5), "finite and non-negative"),
        (SV_COST, FV_COST[:, :, 0], (1.0,), r"fv_cost must be 3-D, got shape \(2, 4\)"),
        (SV_COST[:, :3], FV_COST, PRIOR, r"sv_cost shape \(2, 3, 1\) does not match"),
        (np.ones((2, 4, 2)), FV_COST, PRIOR, r"sv_cost shape \(2, 4, 2\) does not match"),
        (np.ones(4), FV_COST, PRIOR, r"sv_cost must be 2-D or 3-D, got shape \(4,\)"),
        (SV_COST, np.zeros((2, 0, 3)), PRIOR, "empty axis"),
        (np.full((2, 4), np.nan), FV_COST, PRIOR, "sv_cost contains NaN"),
    ],
)
def test_stackelberg_validation(sv: object, fv: object, prior: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        solve_stackelberg_harsanyi(sv, fv, prior)  # type: ignore[arg-type]


@settings(max_examples=40, deadline=None)
@given(
    sv=arrays(np.float64, (2, 4), elements=st.floats(0.0, 10.0)),
    fv=arrays(np.float64, (2, 4, 3), elements=st.floats(0.0, 10.0)),
    raw=arrays(np.float64, 3, elements=st.floats(0.01, 1.0)),
)
def test_expected_cost_equals_sigma_weighted_cost(
    sv: np.ndarray, fv: np.ndarray, raw: np.ndarray
) -> None:
    prior = raw / raw.sum()
    prior[-1] = 1.0 - prior[:-1].sum()
    sol = solve_stackelberg_harsanyi(sv, fv, prior)
    # With a type-independent SV cost, E(s) = Σ_f σ(f|s) J_SV(s, f).
    np.testing.assert_allclose(
        sol.expected_cost, (sol.fv_mixed * sv).sum(axis=1), rtol=1e-12, atol=1e-12
    )
    np.testing.assert_allclose(sol.fv_mixed.sum(axis=1), 1.0, rtol=1e-12)
    for s in range(2):
        for th in range(3):
            assert fv[s, sol.fv_response[s, th], th] == fv[s, :, th].min()
    assert sol.expected_cost[sol.sv_action] == sol.expected_cost.min()


# ----------------------------------------------------------------------------------------------
# solve_cooperative
# ----------------------------------------------------------------------------------------------


def test_cooperative_hand_case() -> None:
    fv = np.array([[5.0, 0.5, 2.0, 0.0], [0.0, 1.0, 0.5, 2.0]])
    sol = solve_cooperative(SV_COST, fv)
    # Joint cost J_SV + J_FV:
    #   s = 0: [1+5, 4+0.5, 2+2, 6+0] = [6, 4.5, 4, 6] -> f = 2, cost 4
    #   s = 1: [3+0, 3+1, 3+0.5, 3+2] = [3, 4, 3.5, 5] -> f = 0, cost 3
    # Joint argmin (s, f) = (1, 0).
    np.testing.assert_array_equal(sol.expected_cost, [4.0, 3.0])
    np.testing.assert_array_equal(sol.fv_response, [[2], [0]])
    np.testing.assert_array_equal(sol.fv_mixed, [[0, 0, 1, 0], [1, 0, 0, 0]])
    assert sol.sv_action == 1
    assert sol.cooperative is True
    # The Stackelberg-Harsanyi solution of the same SV cost prefers s = 0 (see above): the
    # cooperative follower's own cost changes SV's choice.


@pytest.mark.parametrize(
    ("sv", "fv", "match"),
    [
        (SV_COST, FV_COST, r"fv_cost must be 2-D, got shape \(2, 4, 3\)"),
        (SV_COST, np.zeros((2, 3)), r"sv_cost shape \(2, 4\) differs from fv_cost shape \(2, 3\)"),
        (SV_COST, np.full((2, 4), np.nan), "fv_cost contains NaN"),
    ],
)
def test_cooperative_validation(sv: object, fv: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        solve_cooperative(sv, fv)  # type: ignore[arg-type]


# ----------------------------------------------------------------------------------------------
# lane_change_game
# ----------------------------------------------------------------------------------------------

SV_IDM = CAVParams()
FV_IDM = HDVParams()


def veh(x: float, v: float, *, cav: bool = True, v0: float = 33.3) -> GameVehicle:
    """A 5 m vehicle with front bumper at x [m] and speed v [m/s]."""
    return GameVehicle(x=x, v=v, length=5.0, desired_speed=v0, is_cav=cav)


def play(
    sv: GameVehicle,
    fv: GameVehicle | None,
    sv_leader: GameVehicle | None,
    target_leader: GameVehicle | None,
    *,
    params: GameParams = GAME_DEFAULT,
) -> LaneChangeDecision:
    return lane_change_game(
        sv, fv, sv_leader, target_leader, params=params, sv_idm=SV_IDM, fv_idm=FV_IDM
    )


def test_a_stuck_behind_slow_leader_changes_to_empty_lane() -> None:
    # SV at 15 m/s, 20 m behind a 15 m/s leader; target lane empty, no follower.
    d = play(veh(0.0, 15.0), None, veh(25.0, 15.0), None)
    assert d.change
    assert d.reason.startswith("no follower in target lane")
    assert d.sv_cost.shape == (2, 1)
    assert d.fv_cost.shape == (2, 1, 3)
    np.testing.assert_array_equal(d.fv_cost, 0.0)
    np.testing.assert_array_equal(d.solution.expected_cost, d.sv_cost[:, 0])
    assert d.sv_cost[SV_LC, 0] < d.sv_cost[SV_K, 0]


@pytest.mark.parametrize("fv_is_cav", [False, True])
def test_b_follower_right_behind_target_slot_forces_keep(fv_is_cav: bool) -> None:
    # Same incentive as (a), but FV is 3 m behind SV's target slot at the same speed.
    fv = veh(-8.0, 15.0, cav=fv_is_cav)
    d = play(veh(0.0, 15.0), fv, veh(25.0, 15.0), None)
    assert not d.change
    # Cutting in 3 m ahead of FV is infeasible whatever FV does (gap closes below Eq. 15's
    # reach), so every SV-LC entry carries the forbidding safety cost.
    w_s = GAME_DEFAULT.sv_weights[0]
    assert (d.sv_cost[SV_LC] >= w_s * INFEASIBLE_SAFETY_COST).all()
    # FV cannot escape by changing lane: it is still in the target lane until H/2.
    fv_cost_lc = d.fv_cost[SV_LC, FV_LC]
    assert (fv_cost_lc >= GAME_DEFAULT.types[0].w_safety * INFEASIBLE_SAFETY_COST).all()


def test_c_large_gaps_equal_speeds_keep() -> None:
    # All at 25 m/s, leaders 145 m ahead in both lanes, HDV follower 145 m behind: the
    # longitudinal outcome of LC and K is identical, so LC only adds its lateral comfort cost.
    d = play(veh(0.0, 25.0), veh(-150.0, 25.0, cav=False), veh(150.0, 25.0), veh(150.0, 25.0))
    assert not d.change
    assert (d.sv_cost[SV_LC] > d.sv_cost[SV_K]).all()
    # With FV CS (no interaction effect) the gap is the lateral comfort term only.
    assert d.sv_cost[SV_LC, FV_CS] - d.sv_cost[SV_K, FV_CS] > 0.05


def test_d_follower_kind_selects_solver() -> None:
    # SV at 15 m/s stuck 15 m behind a 15 m/s leader, target lane free ahead, FV 120 m behind
    # at 20 m/s. (With the linear safety term a_cr / a_merg shared with the merge game, the
    # 20 m gap of test (a) is not enough for the HDV game to cut in: keeping costs J_s = 0.65
    # there, no longer the saturated 1 of the former capped term.)
    args = (veh(0.0, 15.0), veh(20.0, 15.0), None)
    hdv = play(args[0], veh(-125.0, 20.0, cav=False), *args[1:])
    cav = play(args[0], veh(-125.0, 20.0, cav=True), *args[1:])
    assert hdv.solution.cooperative is False
    assert hdv.reason.startswith("HDV follower")
    assert hdv.fv_cost.shape == (2, 4, 3)
    assert hdv.solution.fv_response.shape == (2, 3)
    assert cav.solution.cooperative is True
    assert cav.reason.startswith("CAV follower")
    assert cav.fv_cost.shape == (2, 4)
    assert cav.solution.fv_response.shape == (2, 1)
    np.testing.assert_allclose(cav.solution.fv_mixed.sum(axis=1), 1.0)
    np.testing.assert_allclose(hdv.solution.fv_mixed.sum(axis=1), 1.0)
    # With these defaults the HDV game lets SV cut in (FV keeps its speed), whereas the
    # cooperative game also counts the CAV follower's cost of receiving SV and keeps.
    assert hdv.change
    assert not cav.change


def test_fv_response_uses_yielding_when_closing_in() -> None:
    # FV approaches 40 m behind at 20 m/s while SV drives 15 m/s: every HDV type yields (DC),
    # and accelerating would make the cut-in infeasible for SV.
    d = play(veh(0.0, 15.0), veh(-45.0, 20.0, cav=False), veh(25.0, 15.0), None)
    np.testing.assert_array_equal(d.solution.fv_response[SV_LC], [3, 3, 3])
    assert d.sv_cost[SV_LC, FV_AC] >= 0.5 * INFEASIBLE_SAFETY_COST


def test_e_deterministic_and_pure() -> None:
    sv, fv = veh(0.0, 20.0), veh(-40.0, 22.0, cav=False)
    lead, target = veh(30.0, 18.0), veh(60.0, 24.0)
    before = copy.deepcopy((sv, fv, lead, target, GAME_DEFAULT, SV_IDM, FV_IDM))
    d1 = play(sv, fv, lead, target)
    d2 = play(sv, fv, lead, target)
    assert (sv, fv, lead, target, GAME_DEFAULT, SV_IDM, FV_IDM) == before
    assert d1.change == d2.change
    assert d1.reason == d2.reason
    np.testing.assert_array_equal(d1.sv_cost, d2.sv_cost)
    np.testing.assert_array_equal(d1.fv_cost, d2.fv_cost)
    np.testing.assert_array_equal(d1.solution.expected_cost, d2.solution.expected_cost)
    assert np.isfinite(d1.sv_cost).all()
    assert np.isfinite(d1.fv_cost).all()


def test_iidm_variant_and_custom_params_run() -> None:
    params = GameParams(prior=(0.0, 1.0, 0.0), dt=0.5, horizon=3.0)
    d = lane_change_game(
        veh(0.0, 15.0),
        veh(-60.0, 15.0, cav=False),
        veh(25.0, 15.0),
        veh(80.0, 25.0),
        params=params,
        sv_idm=IDMParams(variant="iidm"),
        fv_idm=FV_IDM,
    )
    assert isinstance(d.solution, GameSolution)
    assert d.sv_cost.shape == (2, 4)
    # Only the normal type has mass: σ is its pure best response.
    np.testing.assert_array_equal(d.solution.fv_mixed.max(axis=1), 1.0)


def test_overlapping_follower_forbids_change() -> None:
    # FV alongside SV (its front bumper 2 m behind SV's front): the target slot is occupied.
    d = play(veh(0.0, 25.0), veh(-2.0, 25.0, cav=False), None, None)
    assert not d.change
    np.testing.assert_array_equal(
        d.sv_cost[SV_LC] >= GAME_DEFAULT.sv_weights[0] * INFEASIBLE_SAFETY_COST, True
    )


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"prior": (0.5, 0.5)}, "prior has 2 entries for 3 types"),
        ({"prior": (0.5, 0.5, 0.5)}, "prior must sum to 1"),
        ({"prior": (1.5, -0.25, -0.25)}, "prior entries must be finite and >= 0"),
        ({"sv_weights": (0.5, -0.3, 0.2)}, "sv_weights must be finite and >= 0"),
        ({"dt": 0.3}, "horizon = 4.0 must be a multiple of dt = 0.3"),
        ({"unknown": 1.0}, "Extra inputs are not permitted"),
    ],
)
def test_game_params_validation(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ValidationError, match=match):
        GameParams(**kwargs)  # type: ignore[arg-type]


def test_game_params_defaults_and_frozen() -> None:
    p = GAME_DEFAULT
    assert [t.name for t in p.types] == ["aggressive", "normal", "conservative"]
    assert p.prior == (0.25, 0.5, 0.25)
    assert p.n_steps == 16
    assert p.reference_type == 1
    with pytest.raises(ValidationError):
        p.dt = 0.1  # type: ignore[misc]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"v": -1.0}, "v must be finite and >= 0"),
        ({"length": 0.0}, "length must be finite and > 0"),
        ({"desired_speed": 0.0}, "desired_speed must be finite and > 0"),
        ({"x": float("nan")}, "x must be finite"),
    ],
)
def test_game_vehicle_validation(kwargs: dict[str, float], match: str) -> None:
    base: dict[str, float | bool] = {
        "x": 0.0,
        "v": 20.0,
        "length": 5.0,
        "desired_speed": 30.0,
        "is_cav": True,
    }
    with pytest.raises(ValueError, match=match):
        GameVehicle(**{**base, **kwargs})  # type: ignore[arg-type]


def test_the_game_defaults_are_the_config_defaults() -> None:
    """The Eq. 15 values, the threshold, the lane width and the transition tolerance have one
    home, the scenario config: the game's own defaults are read from it."""
    assert game_params(ScenarioConfig(), ScenarioConfig().road.lane_width) == GAME_DEFAULT
    moved = ScenarioConfig().model_copy(
        update={"control": ScenarioConfig().control.model_copy(update={"safety_threshold": 3.0})}
    )
    moved_game = game_params(moved, moved.road.lane_width)
    assert moved_game.safety_threshold == 3.0 != GAME_DEFAULT.safety_threshold
