"""The three passes of the HCOMC prediction over one candidate (see
:mod:`hcomc.control.prediction.population`): the no-merge counterfactual, the pre-pass that
fixes the end states of the virtual vehicles VV1 and VV2, and the joint pass of every key vehicle.
"""

from __future__ import annotations

import numpy as np

from hcomc._jit import borrow, kernel
from hcomc.control.prediction.accelerations import accelerations, vmc_accel, vr_accel
from hcomc.control.prediction.lane_changes import (
    advance_progress,
    advance_vmc,
    collisions_at,
    lateral_pose,
    memberships,
    start_progress,
)
from hcomc.control.prediction.layout import (
    C_ACCEL_END,
    C_B_SAFE,
    C_DT,
    C_EMERGENCY,
    C_GAMMA,
    C_MIN_GAP,
    C_POLITENESS,
    C_REPLAN,
    C_VMC_DUR,
    C_WIDTH,
    L_LATERAL,
    L_VMC_DONE,
    L_VR_DONE,
    L_VR_STARTED,
    L_VR_XF,
    LANE0,
    N_PROGRESS,
    N_ROLES,
    P_LEN,
    P_S0,
    R_A,
    R_ACC,
    R_FREE,
    R_PRESENT,
    R_V,
    R_X,
    S_VV0_V,
    S_VV0_X,
    S_VV1_V,
    S_VV1_X,
    VMC,
    VMF,
    VMR,
    VNF,
    VNR,
    VR,
    KeyVehicles,
    Scratch,
    Trajectories,
)
from hcomc.control.prediction.scoring import (
    accels_after,
    accels_before,
    execution_violation,
    incentive_of,
    no_return_violation,
)
from hcomc.control.prediction.step import (
    behind,
    free_road,
    integrate,
    integrate_role,
    leader,
    new_state,
    reset_state,
)
from hcomc.equations.virtual_vehicle import cubic_into


@kernel
def counterfactual(
    key: KeyVehicles, consts: np.ndarray, n_steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pass 0: the key vehicles without the merge, (n_steps + 1, 6) each of x, v, a.

    VR drives alone on a free road (no lane end); every mainline key vehicle follows the
    nearest key vehicle ahead in its own lane, nobody cooperates or changes lane.
    """
    X = np.empty((n_steps + 1, N_ROLES))
    V = np.empty((n_steps + 1, N_ROLES))
    A = np.empty((n_steps + 1, N_ROLES))
    params = key.params
    S = new_state(key.x, key.v, key.a, key.present)
    for k in range(n_steps + 1):
        record(S, X, V, A, k)
        if k == n_steps:
            break
        S[R_ACC, VR] = free_road(S, params, VR)
        for r in (VMC, VMR, VNR):
            if S[R_PRESENT, r]:
                S[R_ACC, r] = behind(S, params, r, leader(S, r, LANE0[r]))
        integrate(S, consts[C_DT], consts[C_EMERGENCY])
    return X, V, A


@kernel(inline="always")
def record(S: np.ndarray, X: np.ndarray, V: np.ndarray, A: np.ndarray, k: int) -> None:
    """Write the roles' x, v and a into row k of X, V, A."""
    for r in range(N_ROLES):
        X[k, r], V[k, r], A[k, r] = S[R_X, r], S[R_V, r], S[R_A, r]


@kernel(inline="always")
def step(
    k: int, S: np.ndarray, lc: np.ndarray, params: np.ndarray, vvs: np.ndarray,
    plan: np.ndarray, flags: tuple[bool, bool, bool], consts: np.ndarray, joint: bool,
    vr_known: float, cf: np.ndarray,
) -> tuple[bool, bool]:  # fmt: skip
    """Advance the roles by one step from step k; (VR started, VR ended its change) in it.

    ``plan`` holds the candidate's merge position, VR's lane-change duration and horizon H;
    ``flags`` and ``vr_known`` are those of
    :func:`~hcomc.control.prediction.accelerations.accelerations`. In longitudinal mode VNR
    follows VNF alone, exactly as in the no-merge counterfactual ``cf`` (3, K + 1, 6): its
    states are taken from there.
    """
    dt = consts[C_DT]
    memberships(lc, S)
    lane_consts = (consts[C_ACCEL_END], consts[C_VMC_DUR], consts[C_GAMMA])
    vnr_known = not lc[L_LATERAL]
    accelerations(S, lc, params, vvs, k * dt, plan[2], plan[1], flags, lane_consts, joint,
                  vr_known, vnr_known)  # fmt: skip
    integrate(S, dt, consts[C_EMERGENCY])
    if vnr_known:
        S[R_X, VNR], S[R_V, VNR], S[R_A, VNR] = (
            cf[0, k + 1, VNR],
            cf[1, k + 1, VNR],
            cf[2, k + 1, VNR],
        )
        S[R_FREE, VNR] = np.nan
    return advance_progress(lc, S, (k + 1) * dt, plan[0], plan[1], params[VR, P_LEN])


@kernel
def vmc_pre_track(key: KeyVehicles, lateral: bool, consts: np.ndarray, n_steps: int) -> np.ndarray:
    """VMC's position and speed (n_steps + 1, 2) in the pre-pass, at every step.

    In the pre-pass VMC follows only VMF (and VNF in lateral mode), which keep their speed, so
    its trajectory depends on the mode alone, not on the candidate: it is rolled out once per
    population and mode, with the same per-step functions as the candidates' passes.
    """
    track = np.empty((n_steps + 1, 2))
    params = key.params
    S = new_state(key.x, key.v, key.a, key.present)
    lc = np.empty(N_PROGRESS)
    start_progress(lc, lateral, S, consts[C_VMC_DUR], params)
    vvs = np.zeros((3, 4))  # not followed in the pre-pass
    dt, em = consts[C_DT], consts[C_EMERGENCY]
    for k in range(n_steps + 1):
        track[k, 0], track[k, 1] = S[R_X, VMC], S[R_V, VMC]
        if k == n_steps:
            break
        if S[R_PRESENT, VMC]:
            S[R_ACC, VMC] = vmc_accel(S, lc, params, vvs, k * dt, 0.0, consts[C_VMC_DUR],
                                      consts[C_GAMMA], False, False)  # fmt: skip
        for r in (VMC, VMF, VNF):  # the commanded acceleration of VMF, VNF stays 0
            if S[R_PRESENT, r]:
                integrate_role(S, r, dt, em)
        advance_vmc(lc, S)
    return track


@kernel
def pre_pass(
    key: KeyVehicles, starts: np.ndarray, vvs: np.ndarray, plan: np.ndarray, controlled: bool,
    consts: np.ndarray, vmc_track: np.ndarray, scratch: Scratch,
) -> int:  # fmt: skip
    """Pass 1: VR follows only VV0 and VMF, VMC only VMF and VNF, up to the horizon; fixes
    the end states of VV1 (VR's state at H) and VV2 (VMC's state at H) in ``vvs``.

    Nobody else enters VR's or VMC's accelerations in this pass, so only VR (with VMF, which
    keeps its speed) is rolled out here; VMC's states come from ``vmc_track``
    (:func:`vmc_pre_track` of the candidate's mode). The pass works in ``scratch``'s state
    and progress.

    Until VR starts its change its acceleration depends on VR, VV0 and VMF alone, as in the
    joint pass: the steps' accelerations are written to ``scratch.vr_acc`` (K,) and their
    number is returned, so that the joint pass takes them instead of computing them again.
    """
    n_steps = vmc_track.shape[0] - 1
    S, lc, params = borrow(scratch.state), borrow(scratch.progress), borrow(key.params)
    vvs, plan = borrow(vvs), borrow(plan)
    vr_acc = borrow(scratch.vr_acc)
    reset_state(S, key.x, key.v, key.a, key.present)
    start_progress(lc, False, S, consts[C_VMC_DUR], params)
    dt, em = consts[C_DT], consts[C_EMERGENCY]
    k = n_known = 0
    while k * dt < plan[2] and k < n_steps:
        S[R_ACC, VR] = vr_accel(S, lc, params, vvs, k * dt, plan[2], plan[1], controlled,
                                consts[C_ACCEL_END], consts[C_GAMMA], False)  # fmt: skip
        if not lc[L_VR_STARTED]:
            vr_acc[k], n_known = S[R_ACC, VR], k + 1
        for r in (VR, VMF):  # the commanded acceleration of VMF stays 0 (new_state)
            if S[R_PRESENT, r]:
                integrate_role(S, r, dt, em)
        advance_progress(lc, S, (k + 1) * dt, plan[0], plan[1], params[VR, P_LEN])
        k += 1
    # virtual-vehicle end states at the horizon, or at the window's end if that comes first
    cubic_into(plan[2], starts[S_VV1_X], starts[S_VV1_V], S[R_X, VR], S[R_V, VR], vvs[1])
    cubic_into(plan[2], key.x[VNF], key.v[VNF], vmc_track[k, 0], vmc_track[k, 1], vvs[2])
    return n_known


@kernel
def joint_pass(
    key: KeyVehicles, vvs: np.ndarray, plan: np.ndarray, lateral: bool,
    flags: tuple[bool, bool, bool], consts: np.ndarray, trajectories: Trajectories,
    scratch: Scratch, n_known: int, cf: np.ndarray,
) -> tuple[int, float, float, float, float, float]:  # fmt: skip
    """Pass 2: every key vehicle, written to ``trajectories`` (K + 1, 6).

    Returns the step at which VR's change ends (-1: not within the window), how far the end
    of its path lies beyond the acceleration lane [m], the number of colliding
    (pair, step) combinations of the key vehicles (Eq. 7), U_eff (Eq. 17,
    :func:`~hcomc.control.prediction.scoring.incentive_of`: the accelerations "before" in the
    state in which VR begins its change, :func:`~hcomc.control.prediction.scoring.
    accels_before`, and "after" in the state in which it completes it, or at the window's end
    if it does not, :func:`~hcomc.control.prediction.scoring.accels_after`; 0 if it never
    begins), and, for a replanning controller (``consts[C_REPLAN] > 0``, else 0), how far the
    merge position lies beyond the point of no return
    (:func:`~hcomc.control.prediction.scoring.no_return_violation`) and how far the engine's
    execution criterion fails when VR begins its change
    (:func:`~hcomc.control.prediction.scoring.execution_violation`; both 0 if VR never
    begins). The pass works in ``scratch``; VR's accelerations of the first ``n_known``
    steps are those of the pre-pass (``scratch.vr_acc``, see :func:`pre_pass`); ``cf`` is
    the no-merge counterfactual (:func:`step`).
    """
    X, Y, V = borrow(trajectories.x), borrow(trajectories.y), borrow(trajectories.v)
    A, HEAD = borrow(trajectories.a), borrow(trajectories.heading)
    n_steps = X.shape[0] - 1
    S, lc, box = borrow(scratch.state), borrow(scratch.progress), borrow(scratch.boxes)
    params, vvs, plan, consts = borrow(key.params), borrow(vvs), borrow(plan), borrow(consts)
    vr_acc, cf = borrow(scratch.vr_acc), borrow(cf)
    reset_state(S, key.x, key.v, key.a, key.present)
    start_progress(lc, lateral, S, consts[C_VMC_DUR], params)
    k_merge, overrun, collisions, u_eff = -1, plan[0] - consts[C_ACCEL_END], 0, 0.0
    no_return = execution = 0.0
    period = consts[C_REPLAN]
    before = (0.0, 0.0)
    for k in range(n_steps + 1):
        record(S, X, V, A, k)
        lateral_pose(lc, S, consts[C_WIDTH], Y, HEAD, k)
        collisions += collisions_at(X, Y, HEAD, k, S, params, box)
        if k == n_steps:
            break
        vr_known = vr_acc[k] if k < n_known else np.nan
        started, done = step(k, S, lc, params, vvs, plan, flags, consts, True, vr_known, cf)
        if started:
            overrun = lc[L_VR_XF] - consts[C_ACCEL_END]
            before = accels_before(S, params)
            if period > 0.0:
                no_return = no_return_violation(plan[0], S[R_V, VR], params[VR, P_S0],
                                                consts[C_ACCEL_END], consts[C_B_SAFE],
                                                period)  # fmt: skip
                vmc_in_lane1 = not (lc[L_LATERAL] > 0.5 and lc[L_VMC_DONE] > 0.5)
                execution = execution_violation(S, params, vmc_in_lane1, consts[C_B_SAFE],
                                                consts[C_MIN_GAP])  # fmt: skip
        if done:
            k_merge = k + 1
            u_eff = incentive_of(before, accels_after(S, params, lateral), consts[C_POLITENESS])
    if not lc[L_VR_STARTED]:
        overrun = plan[0] - consts[C_ACCEL_END]
    elif not lc[L_VR_DONE]:  # the change does not end within the window: "after" at its end
        u_eff = incentive_of(before, accels_after(S, params, lateral), consts[C_POLITENESS])
    return k_merge, overrun, float(collisions), u_eff, no_return, execution


@kernel
def vv0_cubic(
    starts: np.ndarray, horizon: float, cf: np.ndarray, dt: float, out: np.ndarray
) -> None:
    """VV0: from its start state to VR's future leader (the VMF role) at H, as predicted
    without the merge (projected from the nearest step)."""
    n_steps = cf.shape[1] - 1
    kh = min(int(round(horizon / dt)), n_steps)  # noqa: RUF046 (numba typing)
    xf = cf[0, kh, VMF] + cf[1, kh, VMF] * (horizon - kh * dt)
    cubic_into(horizon, starts[S_VV0_X], starts[S_VV0_V], xf, cf[1, kh, VMF], out)
