"""Scoring of predicted candidates: Eq. 15 at merge completion, Eq. 17 from the accelerations
before (at the start of VR's change) and after VR's lane change (at its end), the feasibility of
the virtual vehicles, the constraints of a replanning controller (the point of no return and the
engine's execution criterion), the objective vector and the penalised scalar cost of
single-objective optimisers (Eq. 16 over a common distance: :mod:`~hcomc.control.prediction.fuel`).

Eq. 15 is :func:`hcomc.equations.safety.critical_accel` and the cubics' extremes
:func:`hcomc.equations.virtual_vehicle.cubic_minima`, their one homes. The objective vector
(:func:`objectives_into`) and the cost (:func:`penalised_cost`) are written once here and
called both for whole populations (:meth:`hcomc.control.hierarchical.problem.MergeProblem.evaluate`,
``scalarise``) and for the single rows of simulated annealing (``evaluate_row``), so that both
paths give the same values bit for bit.
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc.control.prediction.layout import (
    C_A_MERG,
    C_D,
    C_DELAY_CAV,
    C_DELAY_HDV,
    C_VV_DECEL,
    C_WIDTH,
    LANE0,
    N_ROLES,
    P_LEN,
    R_PRESENT,
    R_X,
    VMC,
    VMR,
    VNR,
    VR,
)
from hcomc.control.prediction.step import behind, free_road
from hcomc.equations.incentive import mobil_incentive
from hcomc.equations.safety import critical_accel, stopping_distance
from hcomc.equations.virtual_vehicle import cubic_minima

U_SAFE_CAP = 1e3
"""Cap of the safety objective [m/s^2]: an unavoidable crash (U_safe = inf) is constrained
away by ``unsafe``; capped, its objective stays finite for the optimisers' arithmetic."""


@kernel
def _lanes_at_merge(y: np.ndarray, lateral: bool, width: float) -> np.ndarray:
    """Lane of each role when VR's merge ends (VMC counts in lane 2 once its centre crossed)."""
    lane = LANE0.copy()
    lane[VR] = 1
    if lateral and y[VMC] >= 0.5 * width:
        lane[VMC] = 2
    return lane


@kernel
def _nearest(r: int, lane: np.ndarray, x: np.ndarray, present: np.ndarray, ahead: bool) -> int:
    """Nearest present role in role r's lane ahead of (or behind) it, -1 if none."""
    best, best_d = -1, np.inf
    for j in range(N_ROLES):
        if j == r or not present[j] or lane[j] != lane[r]:
            continue
        d = x[j] - x[r] if ahead else x[r] - x[j]
        if 0.0 < d < best_d:
            best, best_d = j, d
    return best


@kernel
def created_pairs_safety(
    x: np.ndarray,
    v: np.ndarray,
    y: np.ndarray,
    present: np.ndarray,
    cav: np.ndarray,
    params: np.ndarray,
    lateral: bool,
    consts: np.ndarray,
) -> float:
    """Eq. 15 over the follower-leader pairs the merge creates, the largest [m/s^2].

    Followers: VR (behind its new leader) and VR's new follower; in lateral mode also VMC
    (behind its lane-2 leader) and VNR (behind VMC). Each follower's leader is the nearest key
    vehicle ahead in its lane at merge completion. Pairs the plan does not change do not
    enter; ``inf`` when some pair cannot avoid a crash.
    """
    lane = _lanes_at_merge(y, lateral, consts[C_WIDTH])
    followers = np.array([VR, _nearest(VR, lane, x, present, False), -1, -1])
    if lateral:
        followers[2], followers[3] = VMC, VNR
    worst = 0.0
    for r in followers:
        if r < 0 or not present[r]:
            continue
        lead = _nearest(r, lane, x, present, True)
        if lead < 0:
            continue
        d = x[lead] - params[lead, P_LEN] - x[r]
        delay = consts[C_DELAY_CAV] if cav[r] else consts[C_DELAY_HDV]
        u = critical_accel(d, v[r], v[lead], delay, consts[C_D], consts[C_A_MERG])
        worst = max(worst, u)
    return worst


@kernel(inline="always")
def _leader_in(S: np.ndarray, r: int, lanes: np.ndarray, lane: int) -> int:
    """Nearest present role strictly ahead of role r among the roles whose entry in
    ``lanes`` is ``lane``, -1 if none."""
    best, best_x = -1, np.inf
    for j in range(N_ROLES):
        if j != r and S[R_PRESENT, j] and lanes[j] == lane and S[R_X, r] < S[R_X, j] < best_x:
            best, best_x = j, S[R_X, j]
    return best


@kernel(inline="always")
def _follower_in(S: np.ndarray, r: int, lanes: np.ndarray, lane: int) -> int:
    """Nearest present role strictly behind role r among the roles whose entry in ``lanes``
    is ``lane``, -1 if none."""
    best, best_x = -1, -np.inf
    for j in range(N_ROLES):
        if j != r and S[R_PRESENT, j] and lanes[j] == lane and best_x < S[R_X, j] < S[R_X, r]:
            best, best_x = j, S[R_X, j]
    return best


@kernel
def accels_before(S: np.ndarray, params: np.ndarray) -> tuple[float, float]:
    """The "before" accelerations of Eq. 17 in the predicted state ``S`` (8, 6) of the step
    at which VR begins its change [m/s^2]: VR's free-road acceleration (VR on the
    acceleration lane; with the lane end as its leader the incentive would grow the later VR
    decides), and the sum over the present VMC, VMR, VNR of their car-following accelerations
    behind the nearest present key vehicle ahead in their lanes before the merge (VMC in
    lane 1; VR, on the ramp, is nobody's leader)."""
    ori = LANE0.copy()
    ori[VR] = 0
    a_vr = free_road(S, params, VR)
    others = 0.0
    for r in (VMC, VMR, VNR):
        if S[R_PRESENT, r]:
            others += behind(S, params, r, _leader_in(S, r, ori, ori[r]))
    return a_vr, others


@kernel
def accels_after(S: np.ndarray, params: np.ndarray, lateral: bool) -> tuple[float, float]:
    """The "after" accelerations of Eq. 17 in the predicted state ``S`` (8, 6) of the step
    at which VR completes its change (or of the window's end if it does not) [m/s^2]: VR's
    car-following acceleration behind the nearest present key vehicle ahead of it in lane 1,
    and the sum over the present VMC, VMR, VNR of theirs behind the nearest one ahead in their
    lanes with VR in lane 1 (and, in lateral mode, the cooperating VMC in lane 2)."""
    new = LANE0.copy()
    new[VR] = 1
    if lateral:
        new[VMC] = 2
    a_vr = behind(S, params, VR, _leader_in(S, VR, new, 1))
    others = 0.0
    for r in (VMC, VMR, VNR):
        if S[R_PRESENT, r]:
            others += behind(S, params, r, _leader_in(S, r, new, new[r]))
    return a_vr, others


@kernel(inline="always")
def incentive_of(
    before: tuple[float, float], after: tuple[float, float], politeness: float
) -> float:
    """Eq. 17 from the accelerations of :func:`accels_before` and :func:`accels_after`:
    ``(a_VR,after - a_VR,before) + eta (sum_i a_i,after - sum_i a_i,before)``
    (:func:`hcomc.equations.incentive.mobil_incentive`) [m/s^2]."""
    return mobil_incentive(after[0] - before[0], after[1] - before[1], politeness)


@kernel
def lane_change_incentive(
    before: np.ndarray, after: np.ndarray, params: np.ndarray, lateral: bool, politeness: float
) -> float:
    """Eq. 17, the MOBIL-style incentive of VR's lane change, from the accelerations before
    and after it [m/s^2].

    ``U_eff = (a_VR,after - a_VR,before) + eta sum_{VMC, VMR, VNR} (a_i,after - a_i,before)``
    (the paper: "acceleration before and after lane change"), each acceleration the vehicle's
    own car-following model (:func:`~hcomc.control.prediction.step.behind`): "before" in the
    predicted state ``before`` (8, 6) of the step at which VR begins its change, in the
    arrangement before it (:func:`accels_before`), "after" in the predicted state ``after``
    of the step at which VR completes it, with VR in lane 1 (:func:`accels_after`). The
    joint pass takes the two parts at their steps
    (:func:`~hcomc.control.prediction.passes.joint_pass`); this is their composition.
    """
    return incentive_of(
        accels_before(before, params), accels_after(after, params, lateral), politeness
    )


@kernel
def no_return_violation(
    merge_x: float, v: float, s0: float, accel_end: float, b_safe: float, period: float
) -> float:
    """How far a merge position lies beyond the last one a replanning controller may plan
    [m] (<= 0: ok).

    The cap is the engine's point of no return (the acceleration-lane end minus the
    stopping distance at b_safe, :func:`hcomc.equations.safety.stopping_distance`, with VR's
    jam gap s0), less the distance VR covers in one replan period, both at VR's predicted
    speed ``v`` when it begins its change: a change refused at the merge position then
    leaves a replan before VR is released.
    """
    cap = accel_end - stopping_distance(v, b_safe, s0) - v * period
    return merge_x - cap


@kernel
def execution_violation(
    S: np.ndarray, params: np.ndarray, vmc_in_lane1: bool, b_safe: float, min_gap: float
) -> float:
    """How far the engine's execution criterion fails for VR's change in the predicted
    state ``S`` (8, 6) of the step at which VR begins it (<= 0: the engine would start it).

    The engine starts a commanded change only if MOBIL's safety criterion holds
    (:func:`hcomc.sim.mobil.mobil_decide_into`): VR behind its new leader and its new
    follower behind VR each brake no harder than b_safe, and both bumper gaps are at least
    ``min_gap``. Lane 1 holds its key vehicles, VR and, while it has not ended a lateral
    change, VMC (a changing vehicle occupies both lanes, as in the engine). Returns the
    largest of ``-a - b_safe`` [m/s^2] of the two decelerations and ``min_gap - s`` [m] of
    the two gaps.
    """
    lanes = LANE0.copy()
    lanes[VR] = 1
    if not vmc_in_lane1:
        lanes[VMC] = 2
    lead = _leader_in(S, VR, lanes, 1)
    fol = _follower_in(S, VR, lanes, 1)
    worst = -np.inf
    if lead >= 0:
        gap = S[R_X, lead] - params[lead, P_LEN] - S[R_X, VR]
        worst = max(worst, min_gap - gap, -behind(S, params, VR, lead) - b_safe)
    else:
        worst = max(worst, -free_road(S, params, VR) - b_safe)
    if fol >= 0:
        gap = S[R_X, VR] - params[VR, P_LEN] - S[R_X, fol]
        worst = max(worst, min_gap - gap, -behind(S, params, fol, VR) - b_safe)
    return worst


@kernel
def cubic_violation(b: np.ndarray, horizon: float, max_decel: float) -> float:
    """How far a cubic virtual vehicle leaves v >= 0 and a >= -b_max on [0, H] (<= 0: ok)."""
    v_min, a_min = cubic_minima(b, horizon)
    return max(-v_min, -a_min - max_decel)


@kernel
def virtual_violation(
    vvs: np.ndarray, horizon: float, uses: tuple[bool, bool, bool], consts: np.ndarray
) -> float:
    """The largest violation among the virtual vehicles VV0, VV1, VV2 (rows of ``vvs``) the
    plan uses, 0 when all are feasible or none is used."""
    worst = 0.0
    for i in range(3):
        if uses[i]:
            worst = max(worst, cubic_violation(vvs[i], horizon, consts[C_VV_DECEL]))
    return worst


@kernel(inline="always")
def _at_least_zero(value: float) -> float:
    """``np.maximum(value, 0.0)`` of one value, numpy's semantics: NaN propagates and both
    zeros give +0.0 (the cost must equal the array form's bit for bit, signed zeros too)."""
    return value if value > 0.0 or math.isnan(value) else 0.0


@kernel(inline="always")
def objectives_into(u_safe: float, fuel: float, u_eff: float, out: np.ndarray) -> None:
    """The objective vector (safety, fuel, efficiency) of one candidate into ``out`` (3,):
    U_safe capped at :data:`U_SAFE_CAP` (``np.minimum``'s semantics: NaN propagates), U_fuel
    and -U_eff, all minimised."""
    out[0] = u_safe if u_safe < U_SAFE_CAP or math.isnan(u_safe) else U_SAFE_CAP
    out[1] = fuel
    out[2] = -u_eff


@kernel
def objective_rows(u_safe: np.ndarray, fuel: np.ndarray, u_eff: np.ndarray) -> np.ndarray:
    """:func:`objectives_into` of every candidate: (C, 3)."""
    out = np.empty((u_safe.size, 3))
    for c in range(u_safe.size):
        objectives_into(u_safe[c], fuel[c], u_eff[c], out[c])
    return out


@kernel(inline="always")
def _violation_sum(g: np.ndarray) -> float:
    """``np.maximum(g, 0.0).sum()`` of one row, in numpy's order of summation (its pairwise
    summation): in order below eight values; else eight partial sums over the blocks of
    eight, combined pairwise, then the rest in order."""
    n = g.size
    if n < 8:
        total = 0.0
        for j in range(n):
            total += _at_least_zero(g[j])
        return total
    r0, r1, r2, r3 = (
        _at_least_zero(g[0]),
        _at_least_zero(g[1]),
        _at_least_zero(g[2]),
        _at_least_zero(g[3]),
    )
    r4, r5, r6, r7 = (
        _at_least_zero(g[4]),
        _at_least_zero(g[5]),
        _at_least_zero(g[6]),
        _at_least_zero(g[7]),
    )
    i = 8
    while i < n - n % 8:
        r0, r1 = r0 + _at_least_zero(g[i]), r1 + _at_least_zero(g[i + 1])
        r2, r3 = r2 + _at_least_zero(g[i + 2]), r3 + _at_least_zero(g[i + 3])
        r4, r5 = r4 + _at_least_zero(g[i + 4]), r5 + _at_least_zero(g[i + 5])
        r6, r7 = r6 + _at_least_zero(g[i + 6]), r7 + _at_least_zero(g[i + 7])
        i += 8
    total = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        total += _at_least_zero(g[i])
        i += 1
    return total


@kernel(inline="always")
def penalised_cost(f: np.ndarray, g: np.ndarray, threshold: float, fuel_ref: float) -> float:
    """Eq. 19 as one cost with the U_safe gate and the constraints as penalties (the formula
    of :meth:`~hcomc.control.hierarchical.problem.MergeProblem.scalarise`) for one row's objectives
    ``f`` (3,) and constraints ``g``; the violations are summed as numpy sums a row
    (:func:`_violation_sum`), so that the cost equals the array form bit for bit."""
    gate = 10.0 * _at_least_zero(f[0] - threshold)
    return f[1] / fuel_ref + f[2] + (gate + 1000.0 * _violation_sum(g))


@kernel
def penalised_costs(F: np.ndarray, G: np.ndarray, threshold: float, fuel_ref: float) -> np.ndarray:
    """:func:`penalised_cost` of every row of ``F`` (n, 3) and ``G`` (n, n_constr): (n,)."""
    out = np.empty(F.shape[0])
    for i in range(F.shape[0]):
        out[i] = penalised_cost(F[i], G[i], threshold, fuel_ref)
    return out
