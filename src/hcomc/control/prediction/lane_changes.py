"""Lane-change progress of the HCOMC prediction: lane membership, quintic path, collisions.

As in the engine, a lane change follows the quintic path of Eq. 4-6 parametrised in x, from
the position where it starts to ``x0 + max(v T_lc, 3 L)``, and a changing vehicle occupies
both lanes until its change ends. The path is :func:`hcomc.equations.lane_change.lateral_state` (its
one home); the progress of one candidate is a small vector (layout ``L_*`` of
:mod:`hcomc.control.prediction.layout`).
"""

from __future__ import annotations

import math

import numpy as np

from hcomc._jit import kernel
from hcomc.control.prediction.layout import (
    L_LATERAL,
    L_VMC_DONE,
    L_VMC_X0,
    L_VMC_XF,
    L_VR_DONE,
    L_VR_STARTED,
    L_VR_T0,
    L_VR_X0,
    L_VR_XF,
    LANE0,
    N_ROLES,
    P_LEN,
    P_WID,
    R_IN1,
    R_IN2,
    R_PRESENT,
    R_V,
    R_X,
    VMC,
    VNF,
    VNR,
    VR,
)
from hcomc.equations._collision_kernels import vehicle_pair_collides
from hcomc.equations.lane_change import lateral_state


@kernel
def path_end(x: float, v: float, duration: float, length: float) -> float:
    """Predicted end of a lane change starting at x: ``x + max(v T_lc, 3 L)`` [m]."""
    return x + max(v * duration, 3.0 * length)


@kernel
def start_progress(
    lc: np.ndarray, lateral: bool, S: np.ndarray, vmc_dur: float, params: np.ndarray
) -> None:
    """Reset ``lc`` at planning time: VR on the ramp; in lateral mode VMC starts its change."""
    lc[:] = 0.0
    lc[L_VR_XF] = 1.0
    lc[L_LATERAL] = 1.0 if lateral else 0.0
    lc[L_VMC_DONE] = 0.0 if lateral else 1.0
    lc[L_VMC_X0] = S[R_X, VMC]
    lc[L_VMC_XF] = path_end(S[R_X, VMC], S[R_V, VMC], vmc_dur, params[VMC, P_LEN])


@kernel(inline="always")
def memberships(lc: np.ndarray, S: np.ndarray) -> None:
    """Which roles occupy lane 1 and lane 2 (a changing vehicle occupies both)."""
    for r in range(N_ROLES):
        S[R_IN1, r] = 1.0 if LANE0[r] == 1 else 0.0
        S[R_IN2, r] = 1.0 if LANE0[r] == 2 else 0.0
    if lc[L_VR_STARTED]:
        S[R_IN1, VR] = 1.0
    if lc[L_LATERAL]:
        S[R_IN2, VMC] = 1.0
        if lc[L_VMC_DONE]:
            S[R_IN1, VMC] = 0.0


@kernel(inline="always")
def advance_progress(
    lc: np.ndarray, S: np.ndarray, t_next: float, merge_x: float, vr_dur: float, vr_len: float
) -> tuple[bool, bool]:
    """Update the progress after a step ending at ``t_next``; (VR started, VR done) now.

    VR starts its change where it first reaches ``merge_x``; a change ends once the vehicle
    passes the predicted end of its path.
    """
    started = done = False
    x_vr = S[R_X, VR]
    if not lc[L_VR_STARTED] and x_vr >= merge_x:
        started = True
        lc[L_VR_STARTED], lc[L_VR_T0], lc[L_VR_X0] = 1.0, t_next, x_vr
        lc[L_VR_XF] = path_end(x_vr, S[R_V, VR], vr_dur, vr_len)
    if lc[L_VR_STARTED] and not lc[L_VR_DONE] and x_vr >= lc[L_VR_XF]:
        done = True
        lc[L_VR_DONE] = 1.0
    advance_vmc(lc, S)
    return started, done


@kernel(inline="always")
def advance_vmc(lc: np.ndarray, S: np.ndarray) -> None:
    """VMC's part of :func:`advance_progress`: its lateral change ends once it passes the
    predicted end of its path."""
    if not lc[L_VMC_DONE] and S[R_X, VMC] >= lc[L_VMC_XF]:
        lc[L_VMC_DONE] = 1.0


@kernel(inline="always")
def lateral_pose(
    lc: np.ndarray, S: np.ndarray, width: float, Y: np.ndarray, H: np.ndarray, k: int
) -> None:
    """Lateral position ``Y[k]`` and heading ``H[k]`` of the roles (lane 1 at y = 0, the ramp
    at -width). The rows come in zeroed; only the roles off lane 1 or changing are written.
    """
    if lc[L_VR_STARTED] and not lc[L_VR_DONE]:
        Y[k, VR], slope, _ = lateral_state(S[R_X, VR], lc[L_VR_X0], lc[L_VR_XF], -width, 0.0)
        H[k, VR] = math.atan(slope)
    elif not lc[L_VR_DONE]:
        Y[k, VR] = -width
    if lc[L_LATERAL] and not lc[L_VMC_DONE]:
        Y[k, VMC], slope, _ = lateral_state(S[R_X, VMC], lc[L_VMC_X0], lc[L_VMC_XF], 0.0, width)
        H[k, VMC] = math.atan(slope)
    elif lc[L_LATERAL]:
        Y[k, VMC] = width
    Y[k, VNF] = width
    Y[k, VNR] = width


@kernel(inline="always")
def collisions_at(
    X: np.ndarray, Y: np.ndarray, H: np.ndarray, k: int, S: np.ndarray, params: np.ndarray,
    box: np.ndarray,
) -> int:  # fmt: skip
    """Number of colliding key pairs at step k (``box`` (4, 6) is scratch space).

    Axis-aligned bounding boxes first: a rectangle of length L and width W at heading h lies
    within x in [x - L - W/2, x + W/2] and y within W/2 + L |sin h| of its front-bumper
    reference point, so only pairs whose boxes overlap can collide; those get the exact Eq. 7
    test of :func:`hcomc.equations.collision.vehicle_pair_collides`. The boxes of the present
    roles are taken once per step (columns of ``box``: y reach, x front, x rear, role).
    """
    n = 0
    for r in range(N_ROLES):
        if S[R_PRESENT, r]:
            h = H[k, r]  # L |sin h| is exactly 0 at h = 0 (every role off a lane change)
            w = 0.5 * params[r, P_WID]
            box[0, n] = w + (params[r, P_LEN] * abs(math.sin(h)) if h else 0.0)
            box[1, n] = X[k, r] + w
            box[2, n] = X[k, r] - params[r, P_LEN] - w
            box[3, n] = r
            n += 1
    count = 0
    for p in range(n):
        for q in range(p + 1, n):
            i, j = int(box[3, p]), int(box[3, q])
            if (
                box[1, p] >= box[2, q]
                and box[1, q] >= box[2, p]
                and abs(Y[k, i] - Y[k, j]) <= box[0, p] + box[0, q]
                and vehicle_pair_collides(
                    X[k, i], Y[k, i], H[k, i], params[i, P_LEN], params[i, P_WID],
                    X[k, j], Y[k, j], H[k, j], params[j, P_LEN], params[j, P_WID],
                )
            ):  # fmt: skip
                count += 1
    return count
