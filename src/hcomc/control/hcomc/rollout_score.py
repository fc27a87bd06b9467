"""Scoring of one predicted candidate: Eq. 15 at merge completion, Eq. 17 accumulated over the
window, and the feasibility of its virtual vehicles.

Eq. 15 is :func:`hcomc.safety.critical.critical_accel` and the cubics' extremes
:func:`hcomc.control.virtual_vehicle.cubic_minima`, their one homes. Eq. 16 (fuel over a
common distance) is computed by the caller from the trajectories.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hcomc.control.hcomc.rollout_layout import (
    C_A_MERG,
    C_D,
    C_DELAY_CAV,
    C_DELAY_HDV,
    C_VV_DECEL,
    C_WIDTH,
    LANE0,
    N_ROLES,
    P_LEN,
    VMC,
    VMR,
    VNR,
    VR,
)
from hcomc.control.virtual_vehicle import cubic_minima
from hcomc.safety.critical import critical_accel


@njit(cache=True)
def _lanes_at_merge(y: np.ndarray, lateral: bool, width: float) -> np.ndarray:
    """Lane of each role when VR's merge ends (VMC counts in lane 2 once its centre crossed)."""
    lane = LANE0.copy()
    lane[VR] = 1
    if lateral and y[VMC] >= 0.5 * width:
        lane[VMC] = 2
    return lane


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def efficiency_gain(A: np.ndarray, Ac: np.ndarray, present: np.ndarray, politeness: float) -> float:
    """Eq. 17 accumulated against the no-merge counterfactual [m/s^2].

    Mean over the K steps of (a_VR - a_VR,cf) + eta sum over VMC, VMR, VNR of (a_i - a_i,cf),
    with ``A`` and ``Ac`` (K + 1, 6) the candidate's and the counterfactual accelerations.
    """
    K = A.shape[0] - 1
    gain_vr, others = 0.0, 0.0
    for k in range(1, K + 1):
        gain_vr += A[k, VR] - Ac[k, VR]
        for r in (VMC, VMR, VNR):
            if present[r]:
                others += A[k, r] - Ac[k, r]
    return (gain_vr + politeness * others) / K


@njit(cache=True)
def cubic_violation(b: np.ndarray, horizon: float, max_decel: float) -> float:
    """How far a cubic virtual vehicle leaves v >= 0 and a >= -b_max on [0, H] (<= 0: ok)."""
    v_min, a_min = cubic_minima(b, horizon)
    return max(-v_min, -a_min - max_decel)


@njit(cache=True)
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
